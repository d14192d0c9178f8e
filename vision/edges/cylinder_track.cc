#include "vision/edges/cylinder_track.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "common/robust.h"
#include "vision/edges/cylinder_model.h"
#include "vision/edges/fit_shapes.h"

namespace clogscope::vision {
namespace {

using fitcore::Mat;
using fitcore::Vec;
using fitcore::cylinder::EvalShapes;
using fitcore::cylinder::kCauchyC;
using fitcore::cylinder::kMinSigmaPx;
using fitcore::cylinder::RobustScale;
using fitcore::cylinder::Shapes;

// The template's parameters: the one background line b₀ + b₁·(u − u_ref), amplitudes a, k, l as
// the full (kOneLine) fit's, and the geometry as offsets from the template's centre, radius and
// blur.
enum { kB0, kB1, kA, kK, kL, kDc, kDr, kDs, kN };
// The template's object shapes, in the order of the amplitudes a, k, l.
constexpr fitcore::cylinder::Shape kObjectShapes[3] = {
    fitcore::cylinder::kBox, fitcore::cylinder::kLit, fitcore::cylinder::kTilt};

// A fit's parameters about the template's geometry: the one line's level at u_ref (from its
// level at the left silhouette) and slope, the amplitudes, and the geometry's offsets.
Vec<kN> Parameters(const CylinderFit& fit, const CylinderTemplate& t) {
  Vec<kN> q;
  q << fit.background_left - fit.background_slope_left_per_px * (fit.left_px - fit.u_ref_px),
      fit.background_slope_left_per_px, fit.ambient, fit.shading, fit.tilt,
      fit.centre_px - t.centre_px, fit.radius_px - t.radius_px, fit.sigma_px - t.sigma_px;
  return q;
}

using Cols = CylinderTemplate;  // the template's shape columns
using ShapeColumns = Eigen::Matrix<double, Eigen::Dynamic, Cols::kShapeColumns>;
Eigen::Map<const ShapeColumns> ShapesOf(const CylinderTemplate& t) {
  return {t.shapes.data(), static_cast<Eigen::Index>(t.groups.size()), Cols::kShapeColumns};
}

// One fit's scratch: each group's Jacobian row, model value and slope across u; each pixel's
// residual (indexed as the samples).
struct Work {
  Eigen::Matrix<double, Eigen::Dynamic, kN> j;
  Eigen::ArrayXd model, slope;
  std::vector<double> residuals;
  // Weigh's, per group: the weights' sum, Σ w·r, the curvature's sum.
  Eigen::ArrayXd w_sum, wr_sum, curvature_sum;
};

// The template's model at q for all groups at once, its Jacobian rows and its slope across each
// group (the line's, less the object's shapes' by their centre), then each pixel's residual from
// its group's value and slope.
void Residuals(const CylinderTemplate& t, const std::vector<EdgeSample>& samples, const Vec<kN>& q,
               Work* work) {
  const auto s = ShapesOf(t);
  const double amp[3] = {q[kA], q[kK], q[kL]};
  const double dg[3] = {q[kDc], q[kDr], q[kDs]};
  auto& j = work->j;
  j.resize(s.rows(), kN);
  j.col(kB0).setOnes();
  j.col(kB1) = s.col(Cols::kDu);
  work->model = q[kB0] + q[kB1] * s.col(Cols::kDu).array();
  for (int k = 0; k < 3; ++k) {
    j.col(kA + k) = s.col(Cols::kShape + k) + s.col(Cols::DShape(k, 0)) * dg[0] +
                    s.col(Cols::DShape(k, 1)) * dg[1] + s.col(Cols::DShape(k, 2)) * dg[2];
    work->model += amp[k] * j.col(kA + k).array();
  }
  for (int m = 0; m < 3; ++m)
    j.col(kDc + m) = amp[0] * s.col(Cols::DShape(0, m)) + amp[1] * s.col(Cols::DShape(1, m)) +
                     amp[2] * s.col(Cols::DShape(2, m));
  work->slope = q[kB1] - j.col(kDc).array();
  const PixelGroups& groups = t.groups;
  int p = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const double model = work->model[g], slope = work->slope[g];
    for (const int end = groups.end[g]; p < end; ++p) {
      const int i = groups.pixels[p];
      work->residuals[i] = model + slope * groups.offset_px[p] - samples[i].value;
    }
  }
}

// The system at the residuals Residuals left, with Cauchy weights at scale `noise`, as the full
// fit's second run. Its gradient is the Cauchy loss's with each group's Jacobian row for its
// pixels' (their offsets about the group's mean u sum to zero); its matrix the Gauss–Newton one
// with those weights (kWeights: what the fit's covariance is taken from), or with the loss's own
// curvature (kCurvature: Newton's step, which converges quadratically where the weights' fixed
// point is approached only by a constant ratio a step). With kCurvature, `weighted` (when given)
// takes the kWeights system's rows besides, for the covariance where the fit ends. (Apart from
// Residuals, so that a scale taken from these residuals weights them at once.)
enum class Curvature { kWeights, kCurvature };
struct System {
  Mat<kN> jtj;
  Vec<kN> jtr;
  // kCurvature: the model's own curvature, each amplitude times its shape's first order in the
  // geometry (Σ w·r·∂²model), which Step adds to jtj.
  double cross[3][3] = {};
  double wsum = 0, wrss = 0;
};

// The Cauchy loss's curvature at a sample, (1 − z²)/(1 + z²)², falls to nothing at |z| = 1 and is
// negative beyond: from where it is below this share of the sample's weight (|z| ≈ 0.95) it is
// kept at that share, so that the matrix stays positive definite (an
// outlier then barely bends the step, as it barely pulls the gradient).
constexpr double kMinCurvatureShare = 0.05;

System Weigh(const CylinderTemplate& t, double noise, Curvature curvature, Work* work,
             fitcore::NormalSystem<kN>* normal, fitcore::NormalSystem<kN>* weighted = nullptr) {
  System out;
  const double cs = kCauchyC * noise, inv_cs2 = 1.0 / (cs * cs);
  const PixelGroups& groups = t.groups;
  const auto n = static_cast<Eigen::Index>(groups.size());
  work->w_sum.resize(n);
  work->wr_sum.resize(n);
  work->curvature_sum.resize(n);
  int p = 0;
  for (Eigen::Index g = 0; g < n; ++g) {
    double w_sum = 0, wr_sum = 0, curvature_sum = 0;
    for (const int end = groups.end[g]; p < end; ++p) {
      const double r = work->residuals[groups.pixels[p]];
      const double z2 = r * r * inv_cs2;
      const double w = 1.0 / (1.0 + z2);
      out.wsum += w;
      out.wrss += w * r * r;
      w_sum += w;
      wr_sum += w * r;
      if (curvature == Curvature::kCurvature)
        curvature_sum += std::max((1.0 - z2) * w * w, kMinCurvatureShare * w);
    }
    work->w_sum[g] = w_sum;
    work->wr_sum[g] = wr_sum;
    work->curvature_sum[g] = curvature_sum;
  }
  // The weights' rows: each group's weighted mean residual at its weights' sum.
  const auto weights_rows = [&](fitcore::NormalSystem<kN>* system) {
    system->SetRows(work->j, work->wr_sum / work->w_sum, work->w_sum);
  };
  if (curvature == Curvature::kWeights) {
    weights_rows(normal);
  } else {
    normal->SetNewtonRows(work->j, work->wr_sum, work->curvature_sum);
    if (weighted) weights_rows(weighted);
    const auto s = ShapesOf(t);
    for (int k = 0; k < 3; ++k)
      for (int m = 0; m < 3; ++m)
        out.cross[k][m] = work->wr_sum.matrix().dot(s.col(Cols::DShape(k, m)));
  }
  normal->Get(&out.jtj, &out.jtr);
  return out;
}

// The step that solves the system: with the model's curvature where the matrix stays positive
// definite with it, else (far from the minimum, a saddle of the bilinear model) with the loss's
// alone, which does.
Vec<kN> Step(const System& s) {
  Mat<kN> a = s.jtj;
  a.diagonal().array() += 1e-12;
  Mat<kN> h = a;
  for (int k = 0; k < 3; ++k)
    for (int m = 0; m < 3; ++m) {
      h(kA + k, kDc + m) += s.cross[k][m];
      h(kDc + m, kA + k) += s.cross[k][m];
    }
  fitcore::SmallCholesky<kN> newton;
  if (newton.Factor(h)) return newton.Solve(-s.jtr);
  return fitcore::SolveSymmetric<kN>(a, -s.jtr);
}

// The template's pixels grouped about the geometry (centre, radius, blur) and its shapes there at
// the groups' mean u, kept in t. (Grouped again wherever the shapes are evaluated: a silhouette
// that moved into the interior's wide groups would be read off their slope.)
void Linearise(const std::vector<EdgeSample>& samples, double u_ref_px, double centre_px,
               double radius_px, double sigma_px, CylinderTemplate* t) {
  const auto& root = fitcore::BlurredSqrt::Get();
  t->groups = GroupCylinderPixels(samples, centre_px - radius_px, centre_px + radius_px, sigma_px);
  t->centre_px = centre_px;
  t->radius_px = radius_px;
  t->sigma_px = sigma_px;
  t->shapes.resize(t->groups.size() * Cols::kShapeColumns);
  Eigen::Map<ShapeColumns> s(t->shapes.data(), static_cast<Eigen::Index>(t->groups.size()),
                             Cols::kShapeColumns);
  for (size_t g = 0; g < t->groups.size(); ++g) {
    const double u = t->groups.mean_u_px[g];
    Shapes sh;
    EvalShapes<false>(u, u_ref_px, centre_px, radius_px, sigma_px, root, &sh);
    auto row = s.row(static_cast<Eigen::Index>(g));
    row[Cols::kDu] = u - u_ref_px;
    for (int k = 0; k < 3; ++k) {
      row[Cols::kShape + k] = sh.v[kObjectShapes[k]];
      for (int m = 0; m < 3; ++m) row[Cols::DShape(k, m)] = sh.d[kObjectShapes[k]][m];
    }
  }
}

}  // namespace

const char* CylinderTrackRefusalName(CylinderTrackRefusal r) {
  switch (r) {
    case CylinderTrackRefusal::kNone:
      return "none";
    case CylinderTrackRefusal::kOtherSamples:
      return "other_samples";
    case CylinderTrackRefusal::kMoved:
      return "moved";
    case CylinderTrackRefusal::kShadingChanged:
      return "shading_changed";
    case CylinderTrackRefusal::kNoisier:
      return "noisier";
    case CylinderTrackRefusal::kNotConverged:
      return "not_converged";
  }
  return "?";
}

bool MakeCylinderTemplate(const std::vector<EdgeSample>& samples, const CylinderFit& fit,
                          CylinderTemplate* out) {
  if (!fit.converged || fit.background != CylinderBackground::kOneLine || samples.empty() ||
      fit.samples != static_cast<int>(samples.size()))
    return false;
  out->reference = fit;
  out->first_u_px = samples.front().u_px;
  out->last_u_px = samples.back().u_px;
  // The full fit's bound (cylinder_fit.cc) about its own start; here about the fitted blur.
  out->max_sigma_px = std::max(3.0 * fit.sigma_px, std::min(8.0, fit.radius_px / 3.0));
  out->pixels = static_cast<int>(samples.size());
  Linearise(samples, fit.u_ref_px, fit.centre_px, fit.radius_px, fit.sigma_px, out);
  Work work;
  work.residuals.resize(samples.size());
  Residuals(*out, samples, Parameters(fit, *out), &work);
  out->noise = RobustScale(work.residuals);
  return true;
}

CylinderTrackRefusal TrackLitCylinder(CylinderTemplate* t, const std::vector<EdgeSample>& samples,
                                      const CylinderTrackOptions& opt, CylinderFit* out,
                                      const CylinderFit* start) {
  const CylinderFit& ref = t->reference;
  // Where the fit starts: the last frame's fit of this template, else the template's own. (A
  // copy: *out may be *start.)
  const CylinderFit from = start && start->converged ? *start : ref;
  *out = CylinderFit{};
  out->samples = static_cast<int>(samples.size());
  if (static_cast<int>(samples.size()) != t->pixels || samples.empty() ||
      samples.front().u_px != t->first_u_px || samples.back().u_px != t->last_u_px)
    return CylinderTrackRefusal::kOtherSamples;
  // The shapes fitted: the template's, or where they were evaluated again; *t takes the latter
  // only when the frame's fit is accepted.
  const CylinderTemplate* shapes = t;
  CylinderTemplate moved;
  Vec<kN> q = Parameters(from, *t);
  Work work;
  work.residuals.resize(samples.size());
  fitcore::NormalSystem<kN> normal(t->groups.size()), weighted(t->groups.size());
  // Cauchy weights at the scale the full fit would take: the full fit takes its scale once per
  // fit, from the residuals of a first weighted fit, and on real profiles its width moves with
  // that scale (half a px per unit of relative change on Greeff's video: knurl and compression
  // leave structure the model lacks). The reference's scale, then, in the ratio of this frame's
  // residuals to the reference's, once a first step on the shapes fitted has brought the fit near
  // its minimum (not at the last frame's fit: a filament whose width changed by a tenth of a px
  // then looked noisier at its edges, and its templates were refused in half the frames; nor on
  // shapes a move left behind, whose first-order error inflated it by up to a quarter). Its
  // weights are iterated to their fixed point, which they approach by a constant ratio (0.3 to
  // 0.85 per step on Greeff's knurled profiles) when each step is the weights' Gauss–Newton one;
  // once the scale is taken, the steps are Newton's on the loss's own curvature, which reach the
  // same minimum quadratically (on Greeff's video 1 template fit in 45 had not converged in 16
  // weighted steps, and was fitted in full).
  constexpr int kMaxIterations = 16, kScaleIteration = 1;
  double noise = from.noise > 0 ? from.noise : ref.noise;
  System sys;
  bool newton = false;
  const auto beyond_first_order = [&](const Vec<kN>& p) {
    return std::abs(p[kDc]) > opt.max_shift_px || std::abs(p[kDr]) > opt.max_shift_px ||
           std::abs(p[kDs]) > opt.max_blur_change_px;
  };
  for (int lin = 0;; ++lin) {
    bool converged = false;
    for (int it = 0; it < kMaxIterations && !converged; ++it) {
      Residuals(*shapes, samples, q, &work);
      // The scale from these residuals weighs them at once: the step from here is already the
      // one to the minimum at that scale (where the weights' step at the scale before, and a
      // Newton step on the next evaluation, took an evaluation more on most templates).
      if (it == kScaleIteration) noise = ref.noise * RobustScale(work.residuals) / t->noise;
      // Newton's steps only within the first order's reach: beyond it the bilinear model's
      // curvature is the template's, not the object's, and its steps may run away.
      newton = it >= kScaleIteration && !beyond_first_order(q);
      sys = Weigh(*shapes, noise, newton ? Curvature::kCurvature : Curvature::kWeights, &work,
                  &normal, &weighted);
      const Vec<kN> d = Step(sys);
      q += d;
      ++out->iterations;
      // The full fit's tolerance (cylinder_fit.cc).
      converged = it >= kScaleIteration && std::abs(d[kDc]) < 1e-3 && std::abs(d[kDr]) < 1e-3 &&
                  std::abs(d[kDs]) < 1e-2;
    }
    if (!converged || !q.allFinite()) return CylinderTrackRefusal::kNotConverged;
    const double sigma = shapes->sigma_px + q[kDs];
    if (sigma < kMinSigmaPx || sigma > t->max_sigma_px) return CylinderTrackRefusal::kMoved;
    if (!beyond_first_order(q)) break;
    // Moved beyond the first order's reach: the shapes evaluated again where it moved to and the
    // fit done again from there (one evaluation of the full model's shapes, where a full fit
    // takes dozens).
    if (lin >= opt.max_relinearisations) return CylinderTrackRefusal::kMoved;
    if (shapes == t) moved = *t;
    Linearise(samples, ref.u_ref_px, shapes->centre_px + q[kDc], shapes->radius_px + q[kDr], sigma,
              &moved);
    shapes = &moved;
    q[kDc] = q[kDr] = q[kDs] = 0;
  }
  // The lighting and the noise are judged against the full fit the template was made from.
  const double shading_change =
      std::abs(q[kA] - ref.ambient) + std::abs(q[kK] - ref.shading) + std::abs(q[kL] - ref.tilt);
  if (shading_change > opt.max_shading_change_fraction * std::abs(ref.ambient + ref.shading))
    return CylinderTrackRefusal::kShadingChanged;
  if (noise > opt.max_noise_ratio * ref.noise) return CylinderTrackRefusal::kNoisier;

  if (shapes != t) {
    moved.relinearisations = t->relinearisations + 1;
    *t = std::move(moved);
    shapes = t;
  }
  out->converged = true;
  out->centre_px = t->centre_px + q[kDc];
  out->radius_px = t->radius_px + q[kDr];
  out->left_px = out->centre_px - out->radius_px;
  out->right_px = out->centre_px + out->radius_px;
  out->sigma_px = t->sigma_px + q[kDs];
  out->background = CylinderBackground::kOneLine;
  out->u_ref_px = ref.u_ref_px;
  out->background_left = q[kB0] + q[kB1] * (out->left_px - ref.u_ref_px);
  out->background_right = q[kB0] + q[kB1] * (out->right_px - ref.u_ref_px);
  out->background_slope_left_per_px = out->background_slope_right_per_px = q[kB1];
  out->ambient = q[kA];
  out->shading = q[kK];
  out->tilt = q[kL];
  out->noise = noise;
  // As the full fit: the weighted residuals where the fit ended, their variance and the
  // covariance from the weighted normal matrix; those of the last step's start (its centre and
  // radius moved by less than 1e-3 px each), not evaluated again. (A last step on the weights'
  // own system left that system in sys.)
  if (newton) weighted.Get(&sys.jtj, &sys.jtr);
  for (double r : work.residuals)
    if (std::abs(r) > 4.0 * noise) ++out->outliers;
  out->rms = std::sqrt(sys.wrss / std::max(sys.wsum, 1.0));
  const double dof = sys.wsum * (1.0 - static_cast<double>(kN) / samples.size());
  const double var = dof > 0 ? sys.wrss / dof : 0.0;
  const auto sigmas = fitcore::cylinder::SilhouetteSigmasOf<kN>(sys.jtj, kDc, kDr, var);
  out->left_sigma_px = sigmas.left_px;
  out->right_sigma_px = sigmas.right_px;
  out->width_sigma_px = sigmas.width_px;
  return CylinderTrackRefusal::kNone;
}

}  // namespace clogscope::vision
