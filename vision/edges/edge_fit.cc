#include "vision/edges/edge_fit.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/fit_shapes.h"

namespace clogscope::vision {
namespace {

constexpr double kMinSigmaPx = 0.15;
// Where the linearised move samples the window: fine against any blur the fits allow.
constexpr double kLinearMoveStepPx = 0.25;
using fitcore::BlurredSqrt;
using fitcore::Mat;
using fitcore::StepShape;
using fitcore::Vec;

// Parameters: base a, slope b, amplitude c, position e, width s, and for the shaded, two-slope and
// peaked models their sixth, k. value(u) = a + b·(u − u_ref) + c·f((u − e)/s) [+ k·(the model's
// own shape)].
enum { kA, kB, kC, kE, kS, kK };

// The Jacobian's columns every model shares: base, slope, the amplitude of its step shape f, and
// position and width through de = ∂value/∂e (the shapes are functions of z = (u − e)/s, so
// ∂value/∂s = de·z). A model adds its own terms to them.
void StepColumns(double du, double f, double de, double z, double* j) {
  j[kA] = 1.0;
  j[kB] = du;
  j[kC] = f;
  j[kE] = de;
  j[kS] = de * z;
}

// What every model with one position shares: u enters through the base's slope and through the
// position (u − e), so the model's slope across u is b less its derivative by e.
struct OnePosition {
  static double SlopeAcrossU(const double* p, const double* j) { return p[kB] - j[kE]; }
};

// The blurred step: 5 parameters.
struct StepModel : OnePosition {
  static constexpr int kN = 5;
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    double f, df;
    StepShape(z, &f, &df);
    *value = p[kA] + p[kB] * du + p[kC] * f;
    const double de = -p[kC] * df * inv_s;
    StepColumns(du, f, de, z, j);
  }
};

// The blurred step and a second one of the same blur: 7 parameters, the second step's amplitude
// and position after the first five.
enum { kC2 = 5, kE2 = 6 };
struct InnerStepModel {
  static constexpr int kN = 7;
  // Through both positions.
  static double SlopeAcrossU(const double* p, const double* j) { return p[kB] - j[kE] - j[kE2]; }
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s, z2 = (u - p[kE2]) * inv_s;
    double f, df, f2, df2;
    StepShape(z, &f, &df);
    StepShape(z2, &f2, &df2);
    *value = p[kA] + p[kB] * du + p[kC] * f + p[kC2] * f2;
    const double de = -p[kC] * df * inv_s, de2 = -p[kC2] * df2 * inv_s;
    StepColumns(du, f, de, z, j);
    j[kS] += de2 * z2;
    j[kC2] = f2;
    j[kE2] = de2;
  }
};

// The blurred step and a stripe inside the object of the same blur, both its sides: 8
// parameters, the stripe's amplitude, near side and far side after the first five. The stripe's
// term c2·(Φ(z2) − Φ(z3)) is the inner step's with its far side taken off again.
enum { kE3 = 7 };
struct InnerStripeModel {
  static constexpr int kN = 8;
  static double SlopeAcrossU(const double* p, const double* j) {
    return p[kB] - j[kE] - j[kE2] - j[kE3];
  }
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s, z2 = (u - p[kE2]) * inv_s, z3 = (u - p[kE3]) * inv_s;
    double f, df, f2, df2, f3, df3;
    StepShape(z, &f, &df);
    StepShape(z2, &f2, &df2);
    StepShape(z3, &f3, &df3);
    *value = p[kA] + p[kB] * du + p[kC] * f + p[kC2] * (f2 - f3);
    const double de = -p[kC] * df * inv_s, de2 = -p[kC2] * df2 * inv_s, de3 = p[kC2] * df3 * inv_s;
    StepColumns(du, f, de, z, j);
    j[kS] += de2 * z2 + de3 * z3;
    j[kC2] = f2 - f3;
    j[kE2] = de2;
    j[kE3] = de3;
  }
};

// The blurred step with a blurred √d shading ramp on the object side (ι = +1: object at +u).
struct ShadedStepModel : OnePosition {
  static constexpr int kN = 6;
  double iota = 1.0;
  const BlurredSqrt* sqrt_table = &BlurredSqrt::Get();
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    double f, df, g, dg;
    StepShape(z, &f, &df);
    (*sqrt_table)(iota * z, &g, &dg);
    *value = p[kA] + p[kB] * du + p[kC] * f + p[kK] * g;
    const double de = -(p[kC] * df + p[kK] * iota * dg) * inv_s;
    StepColumns(du, f, de, z, j);
    j[kK] = g;
  }
};

// The blurred step whose two sides slope differently (a background gradient that stops at the
// silhouette): the blurred ramp k·s·R(z), R(z) = zΦ(z) + φ(z), adds slope k on the +u side.
struct TwoSlopeStepModel : OnePosition {
  static constexpr int kN = 6;
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    double f, df;
    StepShape(z, &f, &df);
    const double ramp = z * f + df;
    *value = p[kA] + p[kB] * du + p[kC] * f + p[kK] * p[kS] * ramp;
    StepColumns(du, f, -p[kC] * df * inv_s, z, j);
    j[kE] -= p[kK] * f;
    j[kS] += p[kK] * df;
    j[kK] = p[kS] * ramp;
  }
};

// The blurred step through a symmetric PSF somewhat more or less peaked than a Gaussian (a colour
// camera's luma mixes channels demosaiced at different blurs): the Gram–Charlier term
// k·H(z), H(z) = φ(z)·(3z − z³), odd about the edge, so the edge stays the step's middle.
struct PeakedStepModel : OnePosition {
  static constexpr int kN = 6;
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    double f, df;
    StepShape(z, &f, &df);
    const double z2 = z * z;
    const double h = df * z * (3.0 - z2);
    const double dh = df * (z2 * z2 - 6.0 * z2 + 3.0);
    *value = p[kA] + p[kB] * du + p[kC] * f + p[kK] * h;
    const double de = -(p[kC] * df + p[kK] * dh) * inv_s;
    StepColumns(du, f, de, z, j);
    j[kK] = h;
  }
};

// A thin line's blurred profile, close to a Gaussian; symmetric, so its centre is unbiased.
struct LineModel : OnePosition {
  static constexpr int kN = 5;
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    const double f = fitcore::Exp(-0.5 * z * z);
    *value = p[kA] + p[kB] * du + p[kC] * f;
    const double de = p[kC] * z * f * inv_s;
    StepColumns(du, f, de, z, j);
  }
};

// A fit's samples in groups at about the same u (GroupByU, within kGroupSpanBlurs of the starting
// blur): each group's count, mean u and mean value. With equal weights a group's pixels pull the
// fit as their count at their mean (their offsets about it sum to zero), and the model is evaluated
// once a group: on an edge nearly along a pixel axis, once a column. With clip levels to censor
// at, the pixels clipped at either level are grouped apart from the others (a group is counted
// or left out whole) and each group knows its side: +1 clipped high, −1 low, 0 neither.
struct Grouped {
  PixelGroups groups;
  std::vector<double> count, mean_value;
  const ClipLevels* censor = nullptr;  // null when no sample is clipped
  std::vector<signed char> clipped_side;
};
// GroupByU of the samples at `indices`, appended to `out` (indices into all the samples).
void AppendGroups(const std::vector<EdgeSample>& samples, const std::vector<int>& indices,
                  double span_px, int side, Grouped* out) {
  if (indices.empty()) return;
  std::vector<EdgeSample> part(indices.size());
  for (size_t i = 0; i < indices.size(); ++i) part[i] = samples[indices[i]];
  const PixelGroups g = GroupByU(part, span_px);
  PixelGroups& all = out->groups;
  const int base = static_cast<int>(all.pixels.size());
  for (size_t k = 0; k < g.pixels.size(); ++k) {
    all.pixels.push_back(indices[g.pixels[k]]);
    all.offset_px.push_back(g.offset_px[k]);
  }
  for (size_t k = 0; k < g.size(); ++k) {
    all.end.push_back(base + g.end[k]);
    all.mean_u_px.push_back(g.mean_u_px[k]);
    out->clipped_side.push_back(static_cast<signed char>(side));
  }
}
Grouped GroupSamples(const std::vector<EdgeSample>& samples, double sigma_px,
                     const ClipLevels* censor) {
  Grouped out;
  const double span_px = kGroupSpanBlurs * sigma_px;
  if (censor && std::any_of(samples.begin(), samples.end(),
                            [&](const EdgeSample& smp) { return Clipped(smp.value, *censor); })) {
    out.censor = censor;
    std::vector<int> by_side[3];  // low, neither, high
    for (int i = 0; i < static_cast<int>(samples.size()); ++i) {
      const float v = samples[i].value;
      by_side[v <= censor->low ? 0 : v >= censor->high ? 2 : 1].push_back(i);
    }
    for (int side = -1; side <= 1; ++side)
      AppendGroups(samples, by_side[side + 1], span_px, side, &out);
  } else {
    out.groups = GroupByU(samples, span_px);
  }
  const size_t n = out.groups.size();
  out.count.resize(n);
  out.mean_value.resize(n);
  int k = 0;
  for (size_t g = 0; g < n; ++g) {
    double sum = 0;
    const int begin = k;
    for (const int end = out.groups.end[g]; k < end; ++k)
      sum += samples[out.groups.pixels[k]].value;
    out.count[g] = k - begin;
    out.mean_value[g] = sum / (k - begin);
  }
  return out;
}

// Whether a group is left out at a model value m there: its pixels are clipped and m lies beyond
// their level.
bool LeftOut(const Grouped& grouped, size_t g, double m) {
  if (!grouped.censor) return false;
  const int side = grouped.clipped_side[g];
  return (side > 0 && m >= grouped.censor->high) || (side < 0 && m <= grouped.censor->low);
}

// The groups' part of the residuals' sum of squares, Σ count·(model at the mean u − mean value)²,
// with its Gauss-Newton system J^T J and J^T r at p, and how many pixels it counts (*counted).
// What it leaves out, each pixel's residual about its group's, moves with p only through the
// model's slope across the group; Solve adds it where the fit ends.
template <typename Model>
double Evaluate(const Grouped& grouped, const Vec<Model::kN>& p, double u_ref, const Model& model,
                Mat<Model::kN>* jtj, Vec<Model::kN>* jtr, double* counted = nullptr) {
  constexpr int N = Model::kN;
  double h[N][N] = {}, g[N] = {};
  double cost = 0, n = 0;
  for (size_t k = 0; k < grouped.count.size(); ++k) {
    const double u = grouped.groups.mean_u_px[k];
    double value, j[N];
    model(u - u_ref, u, p.data(), &value, j);
    if (LeftOut(grouped, k, value)) continue;
    const double r = value - grouped.mean_value[k];
    cost += grouped.count[k] * r * r;
    n += grouped.count[k];
    fitcore::Accumulate<N>(j, r, grouped.count[k], h, g);
  }
  fitcore::Symmetric<N>(h, g, jtj, jtr);
  if (counted) *counted = n;
  return cost;
}

// The pixels' residuals about their groups' at p: Σ (slope·offset − (value − mean value))², the
// slope the model's across u (of the groups counted).
template <typename Model>
double WithinGroups(const std::vector<EdgeSample>& samples, const Grouped& grouped,
                    const Vec<Model::kN>& p, double u_ref, const Model& model) {
  constexpr int N = Model::kN;
  double cost = 0;
  int k = 0;
  for (size_t g = 0; g < grouped.count.size(); ++g) {
    const double u = grouped.groups.mean_u_px[g];
    double value, j[N];
    model(u - u_ref, u, p.data(), &value, j);
    const double slope = Model::SlopeAcrossU(p.data(), j);
    if (LeftOut(grouped, g, value)) {
      k = grouped.groups.end[g];
      continue;
    }
    for (const int end = grouped.groups.end[g]; k < end; ++k) {
      const double r = slope * grouped.groups.offset_px[k] -
                       (samples[grouped.groups.pixels[k]].value - grouped.mean_value[g]);
      cost += r * r;
    }
  }
  return cost;
}

// Levenberg–Marquardt from p; fills the fit's common fields, and *solved (when given) with all
// the parameters, for the model's own. The position's standard error comes from the inverse
// normal matrix scaled by the residual variance.
template <typename Model>
EdgeFit Solve(const std::vector<EdgeSample>& samples, const Vec<Model::kN>& p0, double u_ref,
              const Model& model, Vec<Model::kN>* solved = nullptr,
              const ClipLevels* censor = nullptr) {
  constexpr int N = Model::kN;
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  // The groups span kGroupSpanBlurs of the blur they are made for: of the start's, then, should the
  // fit end at less than a quarter of it, of the fit's, and the fit runs again from there (from a
  // guess ten times a sharp edge's blur, 1 fit in 10 had reported its edge's σ above 0.2 px).
  Grouped grouped = GroupSamples(samples, p0[kS], censor);
  double within_start = 0;
  const auto run = [&](const Vec<N>& from) {
    // The cost LM compares carries the pixels' part about their groups as it is at the start: it
    // moves with p only through the model's slope across a group, which LM's own steps (the
    // groups' system) cannot foresee.
    within_start = WithinGroups(samples, grouped, from, u_ref, model);
    return fitcore::MinimiseLm<N>(
        from,
        [&](const Vec<N>& p, Mat<N>* jtj, Vec<N>* jtr) {
          return Evaluate(grouped, p, u_ref, model, jtj, jtr) + within_start;
        },
        [](Vec<N>* p) { (*p)[kS] = std::max((*p)[kS], kMinSigmaPx); },
        // The edge moves by less than 2e-4 px.
        [](const Vec<N>& d) { return std::abs(d[kE]) < 2e-4 && std::abs(d[kS]) < 2e-3; });
  };
  auto lm = run(p0);
  if (lm.converged && lm.p[kS] < 0.25 * p0[kS]) {
    grouped = GroupSamples(samples, lm.p[kS], censor);
    const int first_iterations = lm.iterations;
    lm = run(lm.p);
    lm.iterations += first_iterations;
  }
  const Vec<N>& p = lm.p;
  lm.cost += WithinGroups(samples, grouped, p, u_ref, model) - within_start;
  fit.converged = lm.converged;
  fit.iterations = lm.iterations;
  fit.edge_px = p[kE];
  fit.sigma_px = p[kS];
  fit.step = p[kC];
  fit.base = p[kA];
  fit.slope_per_px = p[kB];
  if (solved) *solved = p;
  // Censored, the pixels left out carry no residual: the residuals are the others', and a fit
  // with no more of them than parameters has no σ (not converged).
  double counted = fit.samples;
  if (grouped.censor) {
    Mat<N> jtj;
    Vec<N> jtr;
    Evaluate(grouped, p, u_ref, model, &jtj, &jtr, &counted);
    fit.samples = static_cast<int>(counted);
    if (counted <= N) fit.converged = false;
  }
  const double dof = counted - N;
  fit.rms = counted > 0 ? std::sqrt(lm.cost / counted) : 0.0;
  const double residual_var = dof > 0 ? lm.cost / dof : 0.0;
  const double var_e = fitcore::InverseColumn<N>(lm.jtj, kE)[kE];
  fit.edge_sigma_px = std::sqrt(std::max(0.0, var_e * residual_var));
  if (!std::isfinite(fit.edge_px) || !std::isfinite(fit.sigma_px)) fit.converged = false;
  return fit;
}

// Plateau means on either side of the guess, for a step's starting values. False when a side has
// no samples.
bool PlateauStart(const std::vector<EdgeSample>& samples, double edge_guess_px, double sigma_px,
                  double* lo, double* hi) {
  double lo_sum = 0, hi_sum = 0;
  int lo_n = 0, hi_n = 0;
  const double guard = 2.0 * sigma_px + 0.5;
  for (const auto& smp : samples) {
    if (smp.u_px < edge_guess_px - guard) {
      lo_sum += smp.value;
      ++lo_n;
    } else if (smp.u_px > edge_guess_px + guard) {
      hi_sum += smp.value;
      ++hi_n;
    }
  }
  if (lo_n == 0 || hi_n == 0) return false;
  *lo = lo_sum / lo_n;
  *hi = hi_sum / hi_n;
  return true;
}

}  // namespace

namespace {
// A step model fitted from the plateaus' levels on either side of the guess (extra terms from 0);
// *solved as Solve's, zero when there was nothing to fit.
template <typename Model>
EdgeFit FitStepModel(const std::vector<EdgeSample>& samples, double edge_guess_px,
                     double sigma_guess_px, double u_ref, size_t min_samples, const Model& model,
                     Vec<Model::kN>* solved = nullptr, const ClipLevels* censor = nullptr) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  if (solved) solved->setZero();
  double lo, hi;
  if (samples.size() < min_samples ||
      !PlateauStart(samples, edge_guess_px, sigma_guess_px, &lo, &hi))
    return fit;
  Vec<Model::kN> p = Vec<Model::kN>::Zero();
  p[kA] = lo;
  p[kC] = hi - lo;
  p[kE] = edge_guess_px;
  p[kS] = std::max(sigma_guess_px, 0.5);
  fit = Solve(samples, p, u_ref, model, solved, censor);
  fit.u_ref = u_ref;
  fit.contrast = fit.step;  // FitShadedStep adds its ramp's part
  return fit;
}
}  // namespace

EdgeFit FitBlurredStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                       double sigma_guess_px, double u_ref, const ClipLevels* censor) {
  return FitStepModel(samples, edge_guess_px, sigma_guess_px, u_ref, 8, StepModel(), nullptr,
                      censor);
}

EdgeFit FitStepBeforeInnerStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                               double sigma_guess_px, double u_ref, double inner_guess_px,
                               double far_guess_px, const ClipLevels* censor) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  const bool stripe = std::isfinite(far_guess_px);
  if (samples.size() < (stripe ? 14u : 12u)) return fit;
  // The levels between the steps, from −u to +u, each away from the steps' blur: before the
  // first step, between it and the next, ... . A level squeezed between two steps has only the
  // sample nearest its middle, if no other.
  std::vector<double> at = {edge_guess_px, inner_guess_px};
  if (stripe) at.push_back(far_guess_px);
  std::sort(at.begin(), at.end());
  const size_t levels = at.size() + 1;
  const double guard = 1.5 * sigma_guess_px + 0.5;
  std::vector<double> sum(levels, 0.0), nearest(levels, 1e30), middle_value(levels, 0.0);
  std::vector<int> n(levels, 0);
  for (const auto& smp : samples) {
    const size_t region =
        static_cast<size_t>(std::upper_bound(at.begin(), at.end(), smp.u_px) - at.begin());
    const bool outer = region == 0 || region == levels - 1;
    const double lo_edge = region > 0 ? at[region - 1] : -1e30;
    const double hi_edge = region < at.size() ? at[region] : 1e30;
    if (smp.u_px < lo_edge + guard || smp.u_px > hi_edge - guard) {
      if (!outer) {
        const double d = std::abs(smp.u_px - 0.5 * (lo_edge + hi_edge));
        if (d < nearest[region]) nearest[region] = d, middle_value[region] = smp.value;
      }
      continue;
    }
    sum[region] += smp.value;
    ++n[region];
  }
  if (n[0] == 0 || n[levels - 1] == 0) return fit;
  std::vector<double> level(levels);
  for (size_t r = 0; r < levels; ++r) level[r] = n[r] > 0 ? sum[r] / n[r] : middle_value[r];
  // The inner steps lie toward −u of the silhouette (the object on the −u side) or toward +u.
  const bool inner_first = inner_guess_px < edge_guess_px;
  // The silhouette's step and the first inner step's, each across its own place; a stripe's far
  // side takes the inner step off again.
  const size_t edge_at = inner_first ? levels - 2 : 0;
  const size_t inner_at = inner_first ? levels - 3 : 1;
  const double c = level[edge_at + 1] - level[edge_at];
  const double c2 = level[inner_at + 1] - level[inner_at];
  const double s0 = std::max(sigma_guess_px, 0.5);
  // Either model's fit, and the inner step's amplitude and place from its solution.
  const auto solve = [&](const auto& model, const auto& p) {
    std::decay_t<decltype(p)> solved;
    fit = Solve(samples, p, u_ref, model, &solved, censor);
    fit.inner_step = solved[kC2];
    fit.inner_edge_px = solved[kE2];
    return solved;
  };
  if (stripe) {
    // Toward −u the stripe's far side comes first: c2·(Φ(z2) − Φ(z3)) is −c2 on the stripe, and
    // c2 there is the object's level less the stripe's.
    Vec<InnerStripeModel::kN> p;
    p << level[0], 0.0, c, edge_guess_px, s0, c2, inner_guess_px, far_guess_px;
    fit.inner_far_px = solve(InnerStripeModel(), p)[kE3];
  } else {
    Vec<InnerStepModel::kN> p;
    p << level[0], 0.0, c, edge_guess_px, s0, c2, inner_guess_px;
    solve(InnerStepModel(), p);
  }
  fit.u_ref = u_ref;
  fit.contrast = fit.step;
  const double inward = inner_first ? -1.0 : 1.0;
  const double apart = (fit.inner_edge_px - fit.edge_px) * inward;
  if (!(apart >= fit.sigma_px)) fit.converged = false;
  if (stripe && !((fit.inner_far_px - fit.inner_edge_px) * inward > 0)) fit.converged = false;
  return fit;
}

EdgeFit FitShadedStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                      double sigma_guess_px, double u_ref, int object_side,
                      const ClipLevels* censor) {
  ShadedStepModel model;
  model.iota = object_side > 0 ? 1.0 : -1.0;
  Vec<ShadedStepModel::kN> solved;
  EdgeFit fit =
      FitStepModel(samples, edge_guess_px, sigma_guess_px, u_ref, 10, model, &solved, censor);
  fit.shading = solved[kK];
  if (samples.size() < 10) return fit;
  fit.object_side = object_side > 0 ? 1 : -1;
  double g2, dg2;
  BlurredSqrt::Get()(2.0, &g2, &dg2);
  fit.contrast = fit.step + model.iota * fit.shading * g2;
  return fit;
}

EdgeFit FitPeakedStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                      double sigma_guess_px, double u_ref, const ClipLevels* censor) {
  return FitStepModel(samples, edge_guess_px, sigma_guess_px, u_ref, 10, PeakedStepModel(), nullptr,
                      censor);
}

EdgeFit FitTwoSlopeStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                        double sigma_guess_px, double u_ref, const ClipLevels* censor) {
  Vec<TwoSlopeStepModel::kN> solved;
  EdgeFit fit = FitStepModel(samples, edge_guess_px, sigma_guess_px, u_ref, 10, TwoSlopeStepModel(),
                             &solved, censor);
  fit.slope_change_per_px = solved[kK];
  return fit;
}

double PlainStepMovePerSlopeChange(double step, double sigma_px, double below_px, double above_px) {
  // One Gauss–Newton step of the plain step from the truth toward the profile with the two-slope
  // model's ramp of unit k added (TwoSlopeStepModel's own column): the move to first order, which
  // is all there is where the move is a small part of the blur.
  // (StepModel's columns at p = (0, 0, step, 0, sigma_px), from the one shape they share with the
  // ramp.)
  const double inv_s = 1.0 / sigma_px;
  Mat<StepModel::kN> jtj = Mat<StepModel::kN>::Zero();
  Vec<StepModel::kN> jtr = Vec<StepModel::kN>::Zero();
  double j[StepModel::kN];
  for (double u = -below_px; u <= above_px; u += kLinearMoveStepPx) {
    const double z = u * inv_s;
    double f, df;
    StepShape(z, &f, &df);
    StepColumns(u, f, -step * df * inv_s, z, j);
    const Eigen::Map<const Vec<StepModel::kN>> column(j);
    jtj.noalias() += column * column.transpose();
    jtr += column * (sigma_px * (z * f + df));
  }
  const Vec<StepModel::kN> delta = fitcore::SolveSymmetric<StepModel::kN>(jtj, jtr);
  return std::isfinite(delta[kE]) ? delta[kE] : 0.0;
}

double EdgeModelValue(const EdgeFit& fit, double u_px) {
  const double z = (u_px - fit.edge_px) / fit.sigma_px;
  double f, df;
  StepShape(z, &f, &df);
  double value = fit.base + fit.slope_per_px * (u_px - fit.u_ref) + fit.step * f +
                 fit.slope_change_per_px * fit.sigma_px * (z * f + df);
  if (fit.object_side != 0) {
    double g, dg;
    BlurredSqrt::Get()(fit.object_side * z, &g, &dg);
    value += fit.shading * g;
  }
  if (fit.inner_step != 0) {
    double f2, df2;
    StepShape((u_px - fit.inner_edge_px) / fit.sigma_px, &f2, &df2);
    value += fit.inner_step * f2;
    if (std::isfinite(fit.inner_far_px)) {
      StepShape((u_px - fit.inner_far_px) / fit.sigma_px, &f2, &df2);
      value -= fit.inner_step * f2;
    }
  }
  return value;
}

EdgeFit FitLineProfile(const std::vector<EdgeSample>& samples, double centre_guess_px,
                       double width_guess_px) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  if (samples.size() < 8) return fit;
  // Base from the samples far from the guess; amplitude from the sample nearest to it.
  double far_sum = 0, near_v = 0, near_d = 1e30;
  int far_n = 0;
  for (const auto& smp : samples) {
    const double d = std::abs(smp.u_px - centre_guess_px);
    if (d > 3 * width_guess_px) {
      far_sum += smp.value;
      ++far_n;
    }
    if (d < near_d) {
      near_d = d;
      near_v = smp.value;
    }
  }
  if (far_n == 0) return fit;
  Vec<5> p;
  p << far_sum / far_n, 0.0, near_v - far_sum / far_n, centre_guess_px,
      std::max(width_guess_px, 0.5);
  return Solve(samples, p, centre_guess_px, LineModel());
}

}  // namespace clogscope::vision
