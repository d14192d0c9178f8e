#include "vision/edges/cylinder_fit.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/edges/caliper_samples.h"
#include "vision/edges/cylinder_model.h"
#include "vision/edges/fit_shapes.h"

namespace clogscope::vision {
namespace {

using fitcore::Mat;
using fitcore::Vec;
using fitcore::cylinder::EvalShapes;
using fitcore::cylinder::kBox;
using fitcore::cylinder::kCauchyC;
using fitcore::cylinder::kLit;
using fitcore::cylinder::kMinSigmaPx;
using fitcore::cylinder::kShapes;
using fitcore::cylinder::kTilt;
using fitcore::cylinder::RobustScale;
using fitcore::cylinder::Shapes;

// The parameters: the backgrounds' (kBg = 4: each side its own line, the object opaque; kBg = 2:
// one line through both sides and behind the object), the object's a, k, l; centre, radius, blur.
template <int kBg>
struct Layout {
  static constexpr int kA = kBg, kK = kBg + 1, kL = kBg + 2;
  static constexpr int kAmplitudes = kBg + 3;
  static constexpr int kC = kAmplitudes, kR = kAmplitudes + 1, kS = kAmplitudes + 2;
  static constexpr int kN = kAmplitudes + 3;
  // The shapes the amplitudes multiply at u (xr = u − u_ref).
  static void Amplitudes(const Shapes& sh, double xr, double* v, double (*d)[3]) {
    if constexpr (kBg == 4) {
      for (int i = 0; i < kShapes; ++i) {
        v[i] = sh.v[i];
        for (int q = 0; q < 3; ++q) d[i][q] = sh.d[i][q];
      }
    } else {
      // One line through both sides and behind the object: b₀ + b₁·(u − u_ref), which moves with
      // none of the geometry.
      v[0] = 1.0;
      v[1] = xr;
      for (int q = 0; q < 3; ++q) d[0][q] = d[1][q] = 0.0;
      for (int i = kBox; i < kShapes; ++i) {
        v[i - 2] = sh.v[i];
        for (int q = 0; q < 3; ++q) d[i - 2][q] = sh.d[i][q];
      }
    }
  }
};

// A cylinder lit from one side (tilt l beside its Lambertian part k) is dark from its far rim to
// the terminator: its light k·√(1 − x²) + l·x is clamped at 0 there, where the shapes' goes
// negative, down to −|l| at the rim (a strip R·(1 − cos θ) deep, tan θ = |l|/k). Without it the
// fit moved that silhouette outward, 0.1-1.4 px at 20-35°. The clamp's part is added to the
// model, blurred: I(u) = ∫ C(x)·φ_σ(u − c − R·x)·R dx over the strip, C = −(k√(1 − x²) + l·x),
// and its derivatives by k, l, centre, radius and blur (the strip's ends depend on k and l only,
// and C is 0 at the terminator: no end terms). Only where the fit without it put the light
// within kMaxTerminatorDeg of the camera's axis: beyond, k is too weak beside l for a lit
// cylinder's shading, and l is a gradient across a flat object, which has no terminator. (Decided
// once, between the fit's two runs: a model that switched the fill off past that angle within a
// run had a step in its cost, where a flat object under a gradient stuck with a spurious shading.
// For the same reason the run keeps its number of nodes, and k stays above 0.) The strip's groups
// are the interior's, 2 px wide past CylinderInteriorMarginPx: where a deep strip's terminator
// lies there, its blurred kink is read at their means (its curvature, about a grey level per px²
// at a blur of 1 px, costs the model less than half a level over a group).
constexpr double kMaxTerminatorDeg = 60.0;
// Shallower strips are nothing a fit can see (their fill ~ |l|·depth/3 grey level·px).
constexpr double kMinTerminatorDepthPx = 0.01;
// The smallest k while the fill is on: at 0 the strip would be half the object, and the fill off.
constexpr double kMinTerminatorShading = 1e-6;

struct TerminatorFill {
  double value = 0, d_k = 0, d_l = 0, d_centre = 0, d_radius = 0, d_sigma = 0;
};

// The dark strip's depth inside the far rim, px (k > 0).
double TerminatorDepthPx(double k, double l, double radius) {
  return radius * (1.0 - k / std::hypot(k, l));
}

// The fill's nodes for a run from a fit's k, l, radius and blur: 0 (none) unless the light lies
// within kMaxTerminatorDeg of the axis and the strip is deep enough to matter; else midpoints at
// most half a blur apart, far finer than the Gaussian they are summed under.
int TerminatorNodes(double k, double l, double radius, double sigma) {
  static const double kMaxTan = std::tan(kMaxTerminatorDeg * kDegToRad);
  if (!(k > 0) || l == 0 || std::abs(l) > kMaxTan * k) return 0;
  const double depth_px = TerminatorDepthPx(k, l, radius);
  if (depth_px < kMinTerminatorDepthPx) return 0;
  return std::clamp(static_cast<int>(std::ceil(2 * depth_px / sigma)) + 2, 4, 128);
}

// The strip at one parameter vector, over `nodes` midpoints: what does not depend on u (each
// node's place, root and clamp), taken once for all the groups of an evaluation.
class TerminatorStrip {
 public:
  TerminatorStrip(double k, double l, double centre, double radius, double sigma, int nodes)
      : centre_(centre), radius_(radius), sigma_(sigma), inv_s_(1.0 / sigma) {
    if (nodes <= 0 || !(k > 0) || l == 0) return;
    const double cos_theta = k / std::hypot(k, l);
    // Light toward +u (l > 0) leaves the left rim (x = −1) dark.
    const double x0 = l > 0 ? -1.0 : cos_theta, x1 = l > 0 ? -cos_theta : 1.0;
    u0_ = centre + radius * x0;
    u1_ = centre + radius * x1;
    const double dx = (x1 - x0) / nodes;
    du_ = radius * dx;
    for (int i = 0; i < nodes; ++i) {
      const double x = x0 + (i + 0.5) * dx;
      const double root = std::sqrt(std::max(0.0, 1 - x * x));
      const double c = -(k * root + l * x);
      if (c > 0) nodes_.push_back({x, radius * x, root, c});
    }
    present_ = true;
  }
  // The fill at u, or false where there is none (no strip, or u beyond the blur's reach of it).
  bool At(double u, TerminatorFill* out) const {
    if (!present_ || u < u0_ - 6 * sigma_ || u > u1_ + 6 * sigma_) return false;
    TerminatorFill f;
    double sum_cxz = 0;
    for (const Node& n : nodes_) {
      const double z = (u - centre_ - n.rx) * inv_s_;
      const double g = fitcore::kInvSqrt2Pi * fitcore::Exp(-0.5 * z * z) * inv_s_ * du_;
      f.value += n.c * g;
      f.d_k -= n.root * g;
      f.d_l -= n.x * g;
      f.d_centre += n.c * g * z * inv_s_;
      sum_cxz += n.c * g * n.x * z * inv_s_;
      f.d_sigma += n.c * g * (z * z - 1) * inv_s_;
    }
    f.d_radius = f.value / radius_ + sum_cxz;
    *out = f;
    return true;
  }

 private:
  struct Node {
    double x, rx, root, c;  // x, R·x, √(1 − x²), the clamp's part
  };
  double centre_, radius_, sigma_, inv_s_;
  double u0_ = 0, u1_ = 0, du_ = 0;
  bool present_ = false;
  std::vector<Node> nodes_;
};

// The model at u, its Jacobian row j and its slope across u: the object's shapes and each side's
// level depend on u − centre, and each side's line moves with u besides. With a line each side (a
// strand), the terminator's fill (above); a filament's fit (one line) is its templates' reference,
// which have none (cylinder_track.h).
template <int kBg>
inline double Model(double u, const Vec<Layout<kBg>::kN>& p, double u_ref,
                    const fitcore::BlurredSqrt& root, const TerminatorStrip& strip, double* j,
                    double* slope) {
  using L = Layout<kBg>;
  Shapes sh;
  EvalShapes<kBg == 4>(u, u_ref, p[L::kC], p[L::kR], p[L::kS], root, &sh);
  double v[L::kAmplitudes], d[L::kAmplitudes][3];
  L::Amplitudes(sh, u - u_ref, v, d);
  double value = 0;
  for (int i = 0; i < L::kAmplitudes; ++i) {
    j[i] = v[i];
    value += p[i] * v[i];
  }
  for (int q = 0; q < 3; ++q) {
    double dq = 0;
    for (int i = 0; i < L::kAmplitudes; ++i) dq += p[i] * d[i][q];
    j[L::kC + q] = dq;
  }
  TerminatorFill fill;
  if (strip.At(u, &fill)) {
    value += fill.value;
    j[L::kK] += fill.d_k;
    j[L::kL] += fill.d_l;
    j[L::kC] += fill.d_centre;
    j[L::kR] += fill.d_radius;
    j[L::kS] += fill.d_sigma;
  }
  *slope = -j[L::kC] + p[1] * v[0] + (kBg == 4 ? p[3] * v[2] : 0.0);
  return value;
}

// The amplitudes by weighted least squares for fixed centre, radius and blur: the start (each
// group's pixels taken at its mean u).
template <int kBg>
void SolveAmplitudes(const std::vector<EdgeSample>& samples, const PixelGroups& groups,
                     const std::vector<double>& w, double u_ref, Vec<Layout<kBg>::kN>* p) {
  using L = Layout<kBg>;
  const auto& root = fitcore::BlurredSqrt::Get();
  using Row = Eigen::Matrix<double, L::kAmplitudes, 1>;
  Eigen::Matrix<double, L::kAmplitudes, L::kAmplitudes> ata;
  ata.setZero();
  Row atb = Row::Zero();
  int k = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const double u = groups.mean_u_px[g];
    Shapes sh;
    EvalShapes<kBg == 4>(u, u_ref, (*p)[L::kC], (*p)[L::kR], (*p)[L::kS], root, &sh);
    Row row;
    double d[L::kAmplitudes][3];
    L::Amplitudes(sh, u - u_ref, row.data(), d);
    double w_sum = 0, wv_sum = 0;
    for (const int end = groups.end[g]; k < end; ++k) {
      const int i = groups.pixels[k];
      w_sum += w[i];
      wv_sum += w[i] * samples[i].value;
    }
    ata += w_sum * row * row.transpose();
    atb += wv_sum * row;
  }
  ata.diagonal().array() += 1e-9;
  p->template head<L::kAmplitudes>() = fitcore::SolveSymmetric<L::kAmplitudes>(ata, atb);
}

template <int kBg>
CylinderFit FitCylinder(const std::vector<EdgeSample>& samples, double left_guess_px,
                        double right_guess_px, double sigma_guess_px,
                        std::vector<double>* residuals_out) {
  using L = Layout<kBg>;
  constexpr int kN = L::kN, kA = L::kA, kK = L::kK, kL = L::kL, kC = L::kC, kR = L::kR, kS = L::kS;
  CylinderFit out;
  out.samples = static_cast<int>(samples.size());
  if (samples.size() < 3 * kN || !(right_guess_px > left_guess_px + 2.0)) return out;
  const auto& root = fitcore::BlurredSqrt::Get();
  const double u_ref = 0.5 * (left_guess_px + right_guess_px);
  Vec<kN> p = Vec<kN>::Zero();
  p[kC] = u_ref;
  p[kR] = 0.5 * (right_guess_px - left_guess_px);
  p[kS] = std::max(sigma_guess_px, 0.5);
  // The pixels in groups at about the same u (caliper_samples.h): the model once a group. About
  // the guesses first, then about the first run's fit (a guess may lie a few px off the
  // silhouette, inside the interior's wide groups).
  PixelGroups groups = GroupCylinderPixels(samples, left_guess_px, right_guess_px, p[kS]);
  std::vector<double> w(samples.size(), 1.0), residuals(samples.size());
  // Each group's slope across u where the residuals were last taken: what an LM run holds (below).
  std::vector<double> slopes;
  // The terminator's fill's nodes (0: none): in the second run, where the first put the light
  // within reach (above).
  int terminator_nodes = 0;
  // The fill's strip at q (none while terminator_nodes is 0).
  const auto strip_at = [&](const Vec<kN>& q) {
    return TerminatorStrip(q[kK], q[kL], q[kC], q[kR], q[kS], terminator_nodes);
  };
  const auto residuals_at = [&](const Vec<kN>& q) {
    const TerminatorStrip strip = strip_at(q);
    slopes.resize(groups.size());
    int k = 0;
    for (size_t g = 0; g < groups.size(); ++g) {
      double j[kN];
      double& slope = slopes[g];
      const double model = Model<kBg>(groups.mean_u_px[g], q, u_ref, root, strip, j, &slope);
      for (const int end = groups.end[g]; k < end; ++k) {
        const int i = groups.pixels[k];
        residuals[i] = model + slope * groups.offset_px[k] - samples[i].value;
      }
    }
  };
  // Cauchy weights from the residuals at a scale (RobustScale).
  const auto reweight = [&](double scale) {
    for (size_t i = 0; i < samples.size(); ++i) {
      const double z = residuals[i] / (kCauchyC * scale);
      w[i] = 1.0 / (1.0 + z * z);
    }
  };
  // Robust amplitudes at the guessed geometry before any of it moves: a specular stripe is then
  // already down-weighted when the nonlinear fit starts, instead of dragging blur and radius to
  // wherever it fits best (a stripe 40 levels high once pulled the blur to 14 px).
  SolveAmplitudes<kBg>(samples, groups, w, u_ref, &p);
  for (int round = 0; round < 2; ++round) {
    residuals_at(p);
    reweight(RobustScale(residuals));
    SolveAmplitudes<kBg>(samples, groups, w, u_ref, &p);
  }

  // Weighted least squares with the weights w while cauchy_scale is 0; else the Cauchy loss
  // (c·s)²·log(1 + (r/(c·s))²) at that scale, whose Gauss–Newton system carries the weights
  // 1/(1 + (r/(c·s))²) at the trial's own residuals (iteratively reweighted inside one LM run).
  // Within one LM run each group's slope stays where the run started: the Jacobian (the model's at
  // the group's mean u) is then the cost's own, and LM's steps agree with the costs it compares.
  // (A slope that moved with the trial changed the cost by terms no step foresaw: the first run
  // converged in 80 % of Greeff's fits; ungrouped, 91 %.) Each run starts where the last ended.
  double cauchy_scale = 0;
  fitcore::NormalSystem<kN> normal(groups.size());
  const auto evaluate = [&](const Vec<kN>& q, Mat<kN>* jtj, Vec<kN>* jtr) {
    const TerminatorStrip strip = strip_at(q);
    double cost = 0;
    const double cs = kCauchyC * cauchy_scale, inv_cs2 = cs > 0 ? 1.0 / (cs * cs) : 0.0;
    int k = 0;
    for (size_t g = 0; g < groups.size(); ++g) {
      double j[kN], unused_slope;
      const double model = Model<kBg>(groups.mean_u_px[g], q, u_ref, root, strip, j, &unused_slope);
      const double slope = slopes[g];
      double w_sum = 0, wr_sum = 0;
      for (const int end = groups.end[g]; k < end; ++k) {
        const int i = groups.pixels[k];
        const double r = model + slope * groups.offset_px[k] - samples[i].value;
        double wi = w[i];
        if (cs > 0) {
          const double z2 = r * r * inv_cs2;
          wi = 1.0 / (1.0 + z2);
          cost += cs * cs * std::log1p(z2);
        } else {
          cost += wi * r * r;
        }
        w_sum += wi;
        wr_sum += wi * r;
      }
      normal.Set(g, j, w_sum > 0 ? wr_sum / w_sum : 0.0, w_sum);
    }
    normal.Get(jtj, jtr);
    return cost;
  };
  // The geometry stays near its guess: a silhouette cannot be further than the blur's reach
  // outside the samples, nor the blur wider than a third of the object.
  const double r0 = p[kR];
  const double max_sigma_px = std::max(3.0 * p[kS], std::min(8.0, r0 / 3.0));
  const auto bound = [&](Vec<kN>* q) {
    (*q)[kS] = std::clamp((*q)[kS], kMinSigmaPx, max_sigma_px);
    (*q)[kR] = std::clamp((*q)[kR], std::max(1.0, 0.5 * r0), 1.5 * r0 + 2.0);
    if (terminator_nodes > 0) (*q)[kK] = std::max((*q)[kK], kMinTerminatorShading);
  };
  const auto small_step = [](const Vec<kN>& d) {
    return std::abs(d[kC]) < 1e-3 && std::abs(d[kR]) < 1e-3 && std::abs(d[kS]) < 1e-2;
  };

  // Then the whole model: first with the start's weights, which gives the residuals' scale; then
  // with the Cauchy loss at that scale, so a highlight or an internal line becomes a few
  // down-weighted samples. The scale is taken once: renewed with the weights it shrinks with the
  // down-weighted residuals and the edges never settle (on real footage they drifted 0.1 px per
  // renewal).
  residuals_at(p);  // the slopes the first run holds
  fitcore::LmResult<kN> lm = fitcore::MinimiseLm<kN>(p, evaluate, bound, small_step);
  out.iterations = lm.iterations;
  if (!lm.converged) return out;
  groups = GroupCylinderPixels(samples, lm.p[kC] - lm.p[kR], lm.p[kC] + lm.p[kR], lm.p[kS]);
  normal.Resize(groups.size());
  residuals_at(lm.p);
  const double noise = RobustScale(residuals);
  cauchy_scale = noise;
  if (kBg == 4) {
    terminator_nodes = TerminatorNodes(lm.p[kK], lm.p[kL], lm.p[kR], lm.p[kS]);
    if (terminator_nodes > 0) residuals_at(lm.p);  // the slopes the run holds, with the fill
  }
  lm = fitcore::MinimiseLm<kN>(lm.p, evaluate, bound, small_step);
  out.iterations += lm.iterations;
  if (!lm.converged) return out;
  p = lm.p;
  residuals_at(p);
  reweight(noise);
  double wsum = 0, wrss = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    wsum += w[i];
    wrss += w[i] * residuals[i] * residuals[i];
    if (std::abs(residuals[i]) > 4.0 * noise) ++out.outliers;
  }
  out.centre_px = p[kC];
  out.radius_px = p[kR];
  out.left_px = p[kC] - p[kR];
  out.right_px = p[kC] + p[kR];
  out.sigma_px = p[kS];
  // Each side's line (with one line, both are it), and the object's flat part over the background
  // behind its centre (the two sides' lines there; with one line, a is that already).
  const int right = kBg == 4 ? 2 : 0;
  out.background_left = p[0] + p[1] * (out.left_px - u_ref);
  out.background_right = p[right] + p[right + 1] * (out.right_px - u_ref);
  out.background_slope_left_per_px = p[1];
  out.background_slope_right_per_px = p[right + 1];
  out.background = kBg == 4 ? CylinderBackground::kEachSide : CylinderBackground::kOneLine;
  out.u_ref_px = u_ref;
  out.ambient = kBg == 4 ? p[kA] - 0.5 * (p[0] + p[2] + (p[1] + p[3]) * (p[kC] - u_ref)) : p[kA];
  out.shading = p[kK];
  out.tilt = p[kL];
  if (terminator_nodes > 0) out.terminator_px = TerminatorDepthPx(p[kK], p[kL], p[kR]);
  out.noise = noise;
  if (residuals_out) *residuals_out = std::move(residuals);  // not used here again
  out.rms = std::sqrt(wrss / std::max(wsum, 1.0));
  // Covariance from the weighted normal matrix, scaled by the weighted residual variance.
  const double dof = wsum * (1.0 - static_cast<double>(kN) / samples.size());
  const double var = dof > 0 ? wrss / dof : 0.0;
  const auto sigmas = fitcore::cylinder::SilhouetteSigmasOf<kN>(lm.jtj, kC, kR, var);
  out.left_sigma_px = sigmas.left_px;
  out.right_sigma_px = sigmas.right_px;
  out.width_sigma_px = sigmas.width_px;
  // A fit that ends on a bound found no optimum inside the model's domain.
  const bool on_bound = p[kS] >= max_sigma_px - 1e-6 || p[kR] <= std::max(1.0, 0.5 * r0) + 1e-6 ||
                        p[kR] >= 1.5 * r0 + 2.0 - 1e-6;
  out.converged = !on_bound && std::isfinite(out.left_px) && std::isfinite(out.right_px) &&
                  std::isfinite(out.sigma_px);
  return out;
}

}  // namespace

PixelGroups GroupCylinderPixels(const std::vector<EdgeSample>& samples, double left_px,
                                double right_px, double sigma_px) {
  const double margin = CylinderInteriorMarginPx(sigma_px);
  return GroupByU(samples, kGroupSpanBlurs * sigma_px, left_px + margin, right_px - margin,
                  kInteriorGroupSpanPx);
}

CylinderFit FitLitCylinder(const std::vector<EdgeSample>& samples, double left_guess_px,
                           double right_guess_px, double sigma_guess_px,
                           CylinderBackground background, std::vector<double>* residuals_out) {
  return background == CylinderBackground::kEachSide
             ? FitCylinder<4>(samples, left_guess_px, right_guess_px, sigma_guess_px, residuals_out)
             : FitCylinder<2>(samples, left_guess_px, right_guess_px, sigma_guess_px,
                              residuals_out);
}

double CylinderEdgeContrast(const CylinderFit& fit, int side) {
  const double u = side == 0 ? fit.left_px + 2.0 * fit.sigma_px : fit.right_px - 2.0 * fit.sigma_px;
  Shapes sh;
  EvalShapes<false>(u, fit.u_ref_px, fit.centre_px, fit.radius_px, fit.sigma_px,
                    fitcore::BlurredSqrt::Get(), &sh);
  const double object =
      fit.ambient * sh.v[kBox] + fit.shading * sh.v[kLit] + fit.tilt * sh.v[kTilt];
  return side == 0 ? object : -object;
}

}  // namespace clogscope::vision
