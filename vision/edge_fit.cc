#include "vision/edge_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace clogscope::vision {
namespace {

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;
constexpr double kMinSigmaPx = 0.15;

// Parameters: base a, slope b, amplitude c, position e, width s, and for the shaded model the
// shading amplitude k. value(u) = a + b·(u − u_ref) + c·f((u − e)/s) [+ k·G(ι·(u − e)/s)].
enum { kA, kB, kC, kE, kS, kK };

// Phi(z) and phi(z) from one exp: Abramowitz & Stegun 7.1.26 gives erf to 1.5e-7, i.e. 2e-5 grey
// levels on a 160-level step, far below the noise; glibc's erfc costs about as much as the rest of
// the fit.
inline void StepShape(double z, double* f, double* df) {
  const double g = std::exp(-0.5 * z * z);
  *df = kInvSqrt2Pi * g;
  const double x = std::abs(z) * kInvSqrt2;
  const double t = 1.0 / (1.0 + 0.3275911 * x);
  const double poly =
      t *
      (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
  const double half_erfc = 0.5 * poly * g;  // (1 - erf(x)) / 2
  *f = z >= 0 ? 1.0 - half_erfc : half_erfc;
}

// G(z) = ∫₀^∞ √t·φ(z − t) dt: a √d ramp starting at the edge, blurred by a unit Gaussian. Near
// its silhouette a lit cylinder of radius R shows n·v ≈ √(2d/R) at depth d, so a Lambertian
// object's brightness rises like √d from the edge inwards; this is that rise, blurred. Tabulated
// once (with G' = ∫₀^∞ φ(z − v²) dv, from t = v²) and interpolated: cubic Hermite for G, linear for
// G'; past the table G ≈ √z − 1/(8 z^1.5).
class BlurredSqrt {
 public:
  static const BlurredSqrt& Get() {
    static const BlurredSqrt table;
    return table;
  }
  void operator()(double z, double* g, double* dg) const {
    if (z <= kZMin) {
      *g = *dg = 0;
      return;
    }
    if (z >= kZMax) {
      const double r = std::sqrt(z);
      *g = r - 1.0 / (8 * z * r);
      *dg = 0.5 / r + 3.0 / (16 * z * z * r);
      return;
    }
    const double x = (z - kZMin) / kH;
    const int i = static_cast<int>(x);
    const double t = x - i;
    const double g0 = g_[i], g1 = g_[i + 1], d0 = dg_[i] * kH, d1 = dg_[i + 1] * kH;
    const double t2 = t * t, t3 = t2 * t;
    *g = (2 * t3 - 3 * t2 + 1) * g0 + (t3 - 2 * t2 + t) * d0 + (-2 * t3 + 3 * t2) * g1 +
         (t3 - t2) * d1;
    *dg = dg_[i] + t * (dg_[i + 1] - dg_[i]);
  }

 private:
  static constexpr double kZMin = -8.0, kZMax = 60.0, kH = 0.02;
  BlurredSqrt() {
    const int n = static_cast<int>((kZMax - kZMin) / kH) + 2;
    g_.resize(n);
    dg_.resize(n);
    for (int i = 0; i < n; ++i) {
      const double z = kZMin + i * kH;
      // φ(z − v²) matters for |z − v²| < 9: v from √max(0, z − 9) to √(z + 9).
      const double lo = std::sqrt(std::max(0.0, z - 9.0)), hi = std::sqrt(std::max(0.0, z + 9.0));
      constexpr int kSteps = 400;  // Simpson; the integrands are smooth in v
      const double h = (hi - lo) / kSteps;
      double sg = 0, sd = 0;
      for (int k = 0; k <= kSteps; ++k) {
        const double v = lo + k * h;
        const double w = (k == 0 || k == kSteps) ? 1 : (k % 2 ? 4 : 2);
        const double ph = kInvSqrt2Pi * std::exp(-0.5 * (z - v * v) * (z - v * v));
        sg += w * 2 * v * v * ph;
        sd += w * ph;
      }
      g_[i] = sg * h / 3;
      dg_[i] = sd * h / 3;
    }
  }
  std::vector<double> g_, dg_;
};

// The blurred step: 5 parameters.
struct StepModel {
  static constexpr int kN = 5;
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    double f, df;
    StepShape(z, &f, &df);
    *value = p[kA] + p[kB] * du + p[kC] * f;
    const double de = -p[kC] * df * inv_s;
    j[kA] = 1.0;
    j[kB] = du;
    j[kC] = f;
    j[kE] = de;
    j[kS] = de * z;
  }
};

// The blurred step with a blurred √d shading ramp on the object side (ι = +1: object at +u).
struct ShadedStepModel {
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
    j[kA] = 1.0;
    j[kB] = du;
    j[kC] = f;
    j[kE] = de;
    j[kS] = de * z;
    j[kK] = g;
  }
};

// A thin line's blurred profile, close to a Gaussian; symmetric, so its centre is unbiased.
struct LineModel {
  static constexpr int kN = 5;
  void operator()(double du, double u, const double* p, double* value, double* j) const {
    const double inv_s = 1.0 / p[kS];
    const double z = (u - p[kE]) * inv_s;
    const double f = std::exp(-0.5 * z * z);
    *value = p[kA] + p[kB] * du + p[kC] * f;
    const double de = p[kC] * z * f * inv_s;
    j[kA] = 1.0;
    j[kB] = du;
    j[kC] = f;
    j[kE] = de;
    j[kS] = de * z;
  }
};

template <int N>
using Mat = Eigen::Matrix<double, N, N>;
template <int N>
using Vec = Eigen::Matrix<double, N, 1>;

// Residuals' sum of squares with the Gauss-Newton system J^T J and J^T r at p. The upper triangle
// is accumulated by hand: this loop is most of the measurement's time.
template <typename Model>
double Evaluate(const std::vector<EdgeSample>& samples, const Vec<Model::kN>& p, double u_ref,
                const Model& model, Mat<Model::kN>* jtj, Vec<Model::kN>* jtr) {
  constexpr int N = Model::kN;
  double h[N][N] = {}, g[N] = {};
  double cost = 0;
  for (const auto& smp : samples) {
    double value, j[N];
    model(smp.u_px - u_ref, smp.u_px, p.data(), &value, j);
    const double r = value - smp.value;
    cost += r * r;
    for (int i = 0; i < N; ++i) {
      g[i] += j[i] * r;
      for (int k = i; k < N; ++k) h[i][k] += j[i] * j[k];
    }
  }
  for (int i = 0; i < N; ++i) {
    (*jtr)(i) = g[i];
    for (int k = i; k < N; ++k) (*jtj)(i, k) = (*jtj)(k, i) = h[i][k];
  }
  return cost;
}

// Levenberg–Marquardt from p; fills the fit's common fields. The position's standard error comes
// from the inverse normal matrix scaled by the residual variance.
template <typename Model>
EdgeFit Solve(const std::vector<EdgeSample>& samples, Vec<Model::kN> p, double u_ref,
              const Model& model) {
  constexpr int N = Model::kN;
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  Mat<N> jtj;
  Vec<N> jtr;
  double cost = Evaluate(samples, p, u_ref, model, &jtj, &jtr);
  double lambda = 1e-3;
  constexpr int kMaxIterations = 30;
  for (int it = 0; it < kMaxIterations; ++it) {
    fit.iterations = it + 1;
    Mat<N> a = jtj;
    a.diagonal() *= 1.0 + lambda;
    a.diagonal().array() += 1e-12;
    const Vec<N> delta = a.ldlt().solve(-jtr);
    Vec<N> trial = p + delta;
    trial[kS] = std::max(trial[kS], kMinSigmaPx);
    // One pass gives the trial's cost and, if it is accepted, the next step's system.
    Mat<N> trial_jtj;
    Vec<N> trial_jtr;
    const double trial_cost = Evaluate(samples, trial, u_ref, model, &trial_jtj, &trial_jtr);
    if (trial_cost <= cost) {
      // Converged when the edge moves by less than 2e-4 px (LM converges quadratically here, so
      // what remains is far smaller), or the cost no longer falls: noisy real profiles otherwise
      // crawl along a flat valley in the nuisance parameters until the iteration cap.
      const bool small_step = (std::abs(delta[kE]) < 2e-4 && std::abs(delta[kS]) < 2e-3) ||
                              cost - trial_cost < 1e-9 * cost;
      p = trial;
      cost = trial_cost;
      jtj = trial_jtj;
      jtr = trial_jtr;
      lambda = std::max(lambda * 0.2, 1e-9);
      if (small_step) {
        fit.converged = true;
        break;
      }
    } else {
      lambda *= 8.0;
      if (lambda > 1e8) {
        // No step lowers the cost: we are at the minimum to rounding precision.
        fit.converged = true;
        break;
      }
    }
  }
  fit.edge_px = p[kE];
  fit.sigma_px = p[kS];
  fit.step = p[kC];
  fit.base = p[kA];
  fit.slope_per_px = p[kB];
  if constexpr (N > kK) fit.shading = p[kK];
  const int dof = fit.samples - N;
  fit.rms = std::sqrt(cost / fit.samples);
  const double residual_var = dof > 0 ? cost / dof : 0.0;
  const Mat<N> cov = jtj.ldlt().solve(Mat<N>::Identity());
  fit.edge_sigma_px = std::sqrt(std::max(0.0, cov(kE, kE) * residual_var));
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

EdgeFit FitBlurredStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                       double sigma_guess_px, double u_ref) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  double lo, hi;
  if (samples.size() < 8 || !PlateauStart(samples, edge_guess_px, sigma_guess_px, &lo, &hi))
    return fit;
  Vec<5> p;
  p << lo, 0.0, hi - lo, edge_guess_px, std::max(sigma_guess_px, 0.5);
  fit = Solve(samples, p, u_ref, StepModel());
  fit.contrast = fit.step;
  return fit;
}

EdgeFit FitShadedStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                      double sigma_guess_px, double u_ref, int object_side) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  double lo, hi;
  if (samples.size() < 10 || !PlateauStart(samples, edge_guess_px, sigma_guess_px, &lo, &hi))
    return fit;
  Vec<6> p;
  p << lo, 0.0, hi - lo, edge_guess_px, std::max(sigma_guess_px, 0.5), 0.0;
  ShadedStepModel model;
  model.iota = object_side > 0 ? 1.0 : -1.0;
  fit = Solve(samples, p, u_ref, model);
  double g2, dg2;
  BlurredSqrt::Get()(2.0, &g2, &dg2);
  fit.contrast = fit.step + model.iota * fit.shading * g2;
  return fit;
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
