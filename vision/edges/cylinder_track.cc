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

// The template's model at one group's mean u for parameters q, and its Jacobian row j.
double Model(const CylinderTemplate::Sample& s, const Vec<kN>& q, double* j) {
  const double amp[3] = {q[kA], q[kK], q[kL]};
  const double dg[3] = {q[kDc], q[kDr], q[kDs]};
  j[kB0] = 1.0;
  j[kB1] = s.du_px;
  double model = q[kB0] + q[kB1] * s.du_px;
  for (int k = 0; k < 3; ++k) {
    const double shape =
        s.shape[k] + s.d_shape[k][0] * dg[0] + s.d_shape[k][1] * dg[1] + s.d_shape[k][2] * dg[2];
    j[kA + k] = shape;
    model += amp[k] * shape;
  }
  for (int k = 0; k < 3; ++k)
    j[kDc + k] = amp[0] * s.d_shape[0][k] + amp[1] * s.d_shape[1][k] + amp[2] * s.d_shape[2][k];
  return model;
}

// The system at q over all samples with Cauchy weights at the residuals and scale `noise`, as the
// full fit's second run; keeps the residuals (each pixel's from its group's model value and the
// model's slope across u). Its gradient is the Cauchy loss's with each group's Jacobian row for
// its pixels' (their offsets about the group's mean u sum to zero); its matrix the
// Gauss–Newton one with those weights (kWeights: what the fit's covariance is taken from), or with
// the loss's own curvature (kCurvature: Newton's step, which converges quadratically where the
// weights' fixed point is approached only by a constant ratio a step). With kCurvature, `weighted`
// (when given) takes the kWeights system's rows besides, for the covariance where the fit ends.
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

System Evaluate(const CylinderTemplate& t, const std::vector<EdgeSample>& samples, const Vec<kN>& q,
                double noise, Curvature curvature, std::vector<double>* residuals,
                fitcore::NormalSystem<kN>* normal,
                fitcore::NormalSystem<kN>* weighted = nullptr) {
  System out;
  const double cs = kCauchyC * noise, inv_cs2 = 1.0 / (cs * cs);
  const PixelGroups& groups = t.groups;
  if (normal->size() != groups.size()) normal->Resize(groups.size());
  if (weighted && weighted->size() != groups.size()) weighted->Resize(groups.size());
  int p = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    double j[kN];
    const double model = Model(t.samples[g], q, j);
    // The model's slope across the group: the line's, less the object's shapes' by their centre.
    const double slope = q[kB1] - j[kDc];
    double w_sum = 0, wr_sum = 0, curvature_sum = 0;
    for (const int end = groups.end[g]; p < end; ++p) {
      const int i = groups.pixels[p];
      const double r = model + slope * groups.offset_px[p] - samples[i].value;
      (*residuals)[i] = r;
      const double z2 = r * r * inv_cs2;
      const double w = 1.0 / (1.0 + z2);
      out.wsum += w;
      out.wrss += w * r * r;
      w_sum += w;
      wr_sum += w * r;
      if (curvature == Curvature::kCurvature)
        curvature_sum += std::max((1.0 - z2) * w * w, kMinCurvatureShare * w);
    }
    if (curvature == Curvature::kWeights) {
      normal->Set(g, j, wr_sum / w_sum, w_sum);
    } else {
      normal->Set(g, j, wr_sum, 1.0, curvature_sum);
      if (weighted) weighted->Set(g, j, wr_sum / w_sum, w_sum);
      const CylinderTemplate::Sample& s = t.samples[g];
      for (int k = 0; k < 3; ++k)
        for (int m = 0; m < 3; ++m) out.cross[k][m] += wr_sum * s.d_shape[k][m];
    }
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
  const Eigen::LDLT<Mat<kN>> newton(h);
  if (newton.info() == Eigen::Success && newton.vectorD().minCoeff() > 0)
    return newton.solve(-s.jtr);
  return a.ldlt().solve(-s.jtr);
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
  t->samples.resize(t->groups.size());
  for (size_t g = 0; g < t->groups.size(); ++g) {
    const double u = t->groups.mean_u_px[g];
    Shapes sh;
    EvalShapes<false>(u, u_ref_px, centre_px, radius_px, sigma_px, root, &sh);
    CylinderTemplate::Sample& s = t->samples[g];
    s.du_px = static_cast<float>(u - u_ref_px);
    for (int k = 0; k < 3; ++k) {
      s.shape[k] = static_cast<float>(sh.v[kObjectShapes[k]]);
      for (int m = 0; m < 3; ++m) s.d_shape[k][m] = static_cast<float>(sh.d[kObjectShapes[k]][m]);
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
  std::vector<double> residuals(samples.size());
  fitcore::NormalSystem<kN> normal(out->samples.size());
  Evaluate(*out, samples, Parameters(fit, *out), fit.noise, Curvature::kWeights, &residuals,
           &normal);
  out->noise = RobustScale(residuals);
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
  std::vector<double> residuals(samples.size());
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
      // Newton's steps only within the first order's reach: beyond it the bilinear model's
      // curvature is the template's, not the object's, and its steps may run away.
      newton = it > kScaleIteration && !beyond_first_order(q);
      sys = Evaluate(*shapes, samples, q, noise,
                     newton ? Curvature::kCurvature : Curvature::kWeights, &residuals, &normal,
                     &weighted);
      if (it == kScaleIteration) noise = ref.noise * RobustScale(residuals) / t->noise;
      const Vec<kN> d = Step(sys);
      q += d;
      ++out->iterations;
      // The full fit's tolerance (cylinder_fit.cc).
      converged = it > kScaleIteration && std::abs(d[kDc]) < 1e-3 && std::abs(d[kDr]) < 1e-3 &&
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
  for (double r : residuals)
    if (std::abs(r) > 4.0 * noise) ++out->outliers;
  out->rms = std::sqrt(sys.wrss / std::max(sys.wsum, 1.0));
  const double dof = sys.wsum * (1.0 - static_cast<double>(kN) / samples.size());
  const double var = dof > 0 ? sys.wrss / dof : 0.0;
  const Mat<kN> cov = sys.jtj.ldlt().solve(Mat<kN>::Identity()) * var;
  out->left_sigma_px = std::sqrt(std::max(0.0, cov(kDc, kDc) + cov(kDr, kDr) - 2 * cov(kDc, kDr)));
  out->right_sigma_px = std::sqrt(std::max(0.0, cov(kDc, kDc) + cov(kDr, kDr) + 2 * cov(kDc, kDr)));
  out->width_sigma_px = 2.0 * std::sqrt(std::max(0.0, cov(kDr, kDr)));
  return CylinderTrackRefusal::kNone;
}

}  // namespace clogscope::vision
