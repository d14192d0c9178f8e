#include "vision/edges/cylinder_fit.h"

#include <algorithm>
#include <cmath>

#include "common/robust.h"
#include "vision/edges/fit_shapes.h"

namespace clogscope::vision {
namespace {

using fitcore::Mat;
using fitcore::Vec;

constexpr double kMinSigmaPx = 0.15;
// Cauchy weights 1/(1 + (r/(c·s))²) with c = 2.385: 95 % efficiency on Gaussian noise.
constexpr double kCauchyC = 2.385;

// Parameters: background b₀, b₁; object a, k, l; centre, radius, blur.
enum { kB0, kB1, kA, kK, kL, kC, kR, kS, kN };

// The three object shapes at one u, blurred, and their derivatives by centre, radius and blur.
// With dl = u − c + R and dr = c + R − u the distances inside the left and right silhouettes,
// a = dl/σ and b = dr/σ:
//   box = Φ(a) + Φ(b) − 1                         (exact)
//   tilt = [(u − c)·box + σ(φ(a) − φ(b))]/R       (exact: a blurred linear ramp on the box)
//   lit = [σ·G(a)·G(b) − q·(G'(a) + G'(b))]/R,  q = σ^1.5 / (2√(2R))
// The last blurs √(1 − x²) = √dl·√dr / R: the product of the blurred roots, corrected for the
// other root's slope across each blurred edge (√dr ≈ √(2R)·(1 − dl/4R) near the left one, and
// blurring √t·(t − z) gives G'(z)); what remains is of order (σ/R)² of k.
struct Shapes {
  double v[3];     // box, lit, tilt
  double d[3][3];  // d[shape][c, R, σ]
};

inline void EvalShapes(double u, double c, double r, double s, const fitcore::BlurredSqrt& root,
                       Shapes* out) {
  const double inv_s = 1.0 / s, inv_r = 1.0 / r;
  const double a = (u - c + r) * inv_s, b = (c + r - u) * inv_s;
  double fa, pa, fb, pb, ga, gpa, gb, gpb, g2a, g2b;
  fitcore::StepShape(a, &fa, &pa);
  fitcore::StepShape(b, &fb, &pb);
  root.WithCurvature(a, &ga, &gpa, &g2a);
  root.WithCurvature(b, &gb, &gpb, &g2b);
  const double x = u - c;
  const double box = fa + fb - 1.0;
  out->v[0] = box;
  out->d[0][0] = (pb - pa) * inv_s;
  out->d[0][1] = (pa + pb) * inv_s;
  out->d[0][2] = -(a * pa + b * pb) * inv_s;
  const double k = s * std::sqrt(s) / (2.0 * std::sqrt(2.0 * r));
  const double q = k * (gpa + gpb);
  const double q_c = k * (g2b - g2a) * inv_s;
  const double q_r = -0.5 * q * inv_r + k * (g2a + g2b) * inv_s;
  const double q_s = 1.5 * q * inv_s - k * (a * g2a + b * g2b) * inv_s;
  const double lit = (s * ga * gb - q) * inv_r;
  out->v[1] = lit;
  out->d[1][0] = (ga * gpb - gpa * gb - q_c) * inv_r;
  out->d[1][1] = (gpa * gb + ga * gpb - q_r - lit) * inv_r;
  out->d[1][2] = (ga * gb - a * gpa * gb - b * ga * gpb - q_s) * inv_r;
  const double tilt = (x * box + s * (pa - pb)) * inv_r;
  out->v[2] = tilt;
  out->d[2][0] = (-box + x * (pb - pa) * inv_s + a * pa + b * pb) * inv_r;
  out->d[2][1] = (x * (pa + pb) * inv_s - a * pa + b * pb - tilt) * inv_r;
  out->d[2][2] = (-x * (a * pa + b * pb) * inv_s + pa - pb + a * a * pa - b * b * pb) * inv_r;
}

inline double Model(const EdgeSample& smp, const Vec<kN>& p, double u_ref,
                    const fitcore::BlurredSqrt& root, double* j) {
  Shapes sh;
  EvalShapes(smp.u_px, p[kC], p[kR], p[kS], root, &sh);
  const double amp[3] = {p[kA], p[kK], p[kL]};
  j[kB0] = 1.0;
  j[kB1] = smp.u_px - u_ref;
  j[kA] = sh.v[0];
  j[kK] = sh.v[1];
  j[kL] = sh.v[2];
  for (int q = 0; q < 3; ++q)
    j[kC + q] = amp[0] * sh.d[0][q] + amp[1] * sh.d[1][q] + amp[2] * sh.d[2][q];
  return p[kB0] + p[kB1] * j[kB1] + amp[0] * sh.v[0] + amp[1] * sh.v[1] + amp[2] * sh.v[2];
}

// The five amplitudes by weighted least squares for fixed centre, radius and blur: the start.
void SolveAmplitudes(const std::vector<EdgeSample>& samples, const std::vector<double>& w,
                     double u_ref, Vec<kN>* p) {
  const auto& root = fitcore::BlurredSqrt::Get();
  Eigen::Matrix<double, 5, 5> ata = Eigen::Matrix<double, 5, 5>::Zero();
  Eigen::Matrix<double, 5, 1> atb = Eigen::Matrix<double, 5, 1>::Zero();
  for (size_t i = 0; i < samples.size(); ++i) {
    Shapes sh;
    EvalShapes(samples[i].u_px, (*p)[kC], (*p)[kR], (*p)[kS], root, &sh);
    const Eigen::Matrix<double, 5, 1> row(1.0, samples[i].u_px - u_ref, sh.v[0], sh.v[1], sh.v[2]);
    ata += w[i] * row * row.transpose();
    atb += w[i] * samples[i].value * row;
  }
  ata.diagonal().array() += 1e-9;
  p->head<5>() = ata.ldlt().solve(atb);
}

}  // namespace

CylinderFit FitLitCylinder(const std::vector<EdgeSample>& samples, double left_guess_px,
                           double right_guess_px, double sigma_guess_px) {
  CylinderFit out;
  out.samples = static_cast<int>(samples.size());
  if (samples.size() < 3 * kN || !(right_guess_px > left_guess_px + 2.0)) return out;
  const auto& root = fitcore::BlurredSqrt::Get();
  const double u_ref = 0.5 * (left_guess_px + right_guess_px);
  Vec<kN> p = Vec<kN>::Zero();
  p[kC] = u_ref;
  p[kR] = 0.5 * (right_guess_px - left_guess_px);
  p[kS] = std::max(sigma_guess_px, 0.5);
  std::vector<double> w(samples.size(), 1.0), residuals(samples.size());
  const auto residuals_at = [&](const Vec<kN>& q) {
    for (size_t i = 0; i < samples.size(); ++i) {
      double j[kN];
      residuals[i] = Model(samples[i], q, u_ref, root, j) - samples[i].value;
    }
  };
  // The residuals' robust scale (1.4826·MAD), and Cauchy weights from the residuals at a scale.
  const auto robust_scale = [&]() {
    std::vector<double> abs_r(residuals.size());
    std::transform(residuals.begin(), residuals.end(), abs_r.begin(),
                   [](double r) { return std::abs(r); });
    return std::max(kMadToSigma * Median(abs_r), 1e-6);
  };
  const auto reweight = [&](double scale) {
    for (size_t i = 0; i < samples.size(); ++i) {
      const double z = residuals[i] / (kCauchyC * scale);
      w[i] = 1.0 / (1.0 + z * z);
    }
  };
  // Robust amplitudes at the guessed geometry before any of it moves: a specular stripe is then
  // already down-weighted when the nonlinear fit starts, instead of dragging blur and radius to
  // wherever it fits best (a stripe 40 levels high once pulled the blur to 14 px).
  SolveAmplitudes(samples, w, u_ref, &p);
  for (int round = 0; round < 2; ++round) {
    residuals_at(p);
    reweight(robust_scale());
    SolveAmplitudes(samples, w, u_ref, &p);
  }

  // Weighted least squares with the weights w while cauchy_scale is 0; else the Cauchy loss
  // (c·s)²·log(1 + (r/(c·s))²) at that scale, whose Gauss–Newton system carries the weights
  // 1/(1 + (r/(c·s))²) at the trial's own residuals (iteratively reweighted inside one LM run).
  double cauchy_scale = 0;
  const auto evaluate = [&](const Vec<kN>& q, Mat<kN>* jtj, Vec<kN>* jtr) {
    double h[kN][kN] = {}, g[kN] = {};
    double cost = 0;
    const double cs = kCauchyC * cauchy_scale, inv_cs2 = cs > 0 ? 1.0 / (cs * cs) : 0.0;
    for (size_t i = 0; i < samples.size(); ++i) {
      double j[kN];
      const double r = Model(samples[i], q, u_ref, root, j) - samples[i].value;
      double wi = w[i];
      if (cs > 0) {
        const double z2 = r * r * inv_cs2;
        wi = 1.0 / (1.0 + z2);
        cost += cs * cs * std::log1p(z2);
      } else {
        cost += wi * r * r;
      }
      fitcore::Accumulate<kN>(j, r, wi, h, g);
    }
    fitcore::Symmetric<kN>(h, g, jtj, jtr);
    return cost;
  };
  // The geometry stays near its guess: a silhouette cannot be further than the blur's reach
  // outside the samples, nor the blur wider than a third of the object.
  const double r0 = p[kR];
  const double max_sigma_px = std::max(3.0 * p[kS], std::min(8.0, r0 / 3.0));
  const auto bound = [&](Vec<kN>* q) {
    (*q)[kS] = std::clamp((*q)[kS], kMinSigmaPx, max_sigma_px);
    (*q)[kR] = std::clamp((*q)[kR], std::max(1.0, 0.5 * r0), 1.5 * r0 + 2.0);
  };
  const auto small_step = [](const Vec<kN>& d) {
    return std::abs(d[kC]) < 1e-3 && std::abs(d[kR]) < 1e-3 && std::abs(d[kS]) < 1e-2;
  };

  // Then the whole model: first with the start's weights, which gives the residuals' scale; then
  // with the Cauchy loss at that scale, so a highlight or an internal line becomes a few
  // down-weighted samples. The scale is taken once: renewed with the weights it shrinks with the
  // down-weighted residuals and the edges never settle (on real footage they drifted 0.1 px per
  // renewal).
  fitcore::LmResult<kN> lm = fitcore::MinimiseLm<kN>(p, evaluate, bound, small_step);
  out.iterations = lm.iterations;
  if (!lm.converged) return out;
  residuals_at(lm.p);
  const double noise = robust_scale();
  cauchy_scale = noise;
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
  out.background = p[kB0];
  out.background_slope_per_px = p[kB1];
  out.ambient = p[kA];
  out.shading = p[kK];
  out.tilt = p[kL];
  out.noise = noise;
  out.rms = std::sqrt(wrss / std::max(wsum, 1.0));
  // Covariance from the weighted normal matrix, scaled by the weighted residual variance.
  const double dof = wsum * (1.0 - static_cast<double>(kN) / samples.size());
  const double var = dof > 0 ? wrss / dof : 0.0;
  const Mat<kN> cov = lm.jtj.ldlt().solve(Mat<kN>::Identity()) * var;
  out.left_sigma_px = std::sqrt(std::max(0.0, cov(kC, kC) + cov(kR, kR) - 2 * cov(kC, kR)));
  out.right_sigma_px = std::sqrt(std::max(0.0, cov(kC, kC) + cov(kR, kR) + 2 * cov(kC, kR)));
  out.width_sigma_px = 2.0 * std::sqrt(std::max(0.0, cov(kR, kR)));
  // A fit that ends on a bound found no optimum inside the model's domain.
  const bool on_bound = p[kS] >= max_sigma_px - 1e-6 || p[kR] <= std::max(1.0, 0.5 * r0) + 1e-6 ||
                        p[kR] >= 1.5 * r0 + 2.0 - 1e-6;
  out.converged = !on_bound && std::isfinite(out.left_px) && std::isfinite(out.right_px) &&
                  std::isfinite(out.sigma_px);
  return out;
}

}  // namespace clogscope::vision
