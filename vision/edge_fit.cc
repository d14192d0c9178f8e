#include "vision/edge_fit.h"

#include <Eigen/Dense>
#include <cmath>

namespace clogscope::vision {
namespace {

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;
constexpr double kMinSigmaPx = 0.15;

// value(u) = a + b·(u − u_ref) + c·f((u − e)/s): base, slope, amplitude, position, width.
struct Params {
  double a, b, c, e, s;
};

// Phi(z) and phi(z) from one exp: Abramowitz & Stegun 7.1.26 gives erf to 1.5e-7, i.e. 2e-5 grey
// levels on a 160-level step, far below the noise; glibc's erfc costs about as much as the rest of
// the fit.
struct StepShape {
  void operator()(double z, double* f, double* df) const {
    const double g = std::exp(-0.5 * z * z);
    *df = kInvSqrt2Pi * g;
    const double x = std::abs(z) * kInvSqrt2;
    const double t = 1.0 / (1.0 + 0.3275911 * x);
    const double poly =
        t * (0.254829592 +
             t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    const double half_erfc = 0.5 * poly * g;  // (1 - erf(x)) / 2
    *f = z >= 0 ? 1.0 - half_erfc : half_erfc;
  }
};

// A thin line's blurred profile, close to a Gaussian; symmetric, so its centre is unbiased.
struct GaussianShape {
  void operator()(double z, double* f, double* df) const {
    *f = std::exp(-0.5 * z * z);
    *df = -z * *f;
  }
};

// Residuals' sum of squares with the Gauss-Newton system J^T J and J^T r at p. The upper triangle
// is accumulated by hand: this loop is most of the measurement's time.
template <typename Shape>
double Evaluate(const std::vector<EdgeSample>& samples, const Params& p, double u_ref, Shape shape,
                Eigen::Matrix<double, 5, 5>* jtj, Eigen::Matrix<double, 5, 1>* jtr) {
  double h[5][5] = {}, g[5] = {};
  double cost = 0;
  const double inv_s = 1.0 / p.s;
  for (const auto& smp : samples) {
    const double du = smp.u_px - u_ref;
    const double z = (smp.u_px - p.e) * inv_s;
    double f, df;
    shape(z, &f, &df);
    const double r = p.a + p.b * du + p.c * f - smp.value;
    cost += r * r;
    const double de = -p.c * df * inv_s;
    const double j[5] = {1.0, du, f, de, de * z};
    for (int i = 0; i < 5; ++i) {
      g[i] += j[i] * r;
      for (int k = i; k < 5; ++k) h[i][k] += j[i] * j[k];
    }
  }
  for (int i = 0; i < 5; ++i) {
    (*jtr)(i) = g[i];
    for (int k = i; k < 5; ++k) (*jtj)(i, k) = (*jtj)(k, i) = h[i][k];
  }
  return cost;
}

// Levenberg–Marquardt from p; fills the fit's common fields. The position's standard error comes
// from the inverse normal matrix scaled by the residual variance.
template <typename Shape>
EdgeFit Solve(const std::vector<EdgeSample>& samples, Params p, double u_ref, Shape shape) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  Eigen::Matrix<double, 5, 5> jtj;
  Eigen::Matrix<double, 5, 1> jtr;
  double cost = Evaluate(samples, p, u_ref, shape, &jtj, &jtr);
  double lambda = 1e-3;
  constexpr int kMaxIterations = 30;
  for (int it = 0; it < kMaxIterations; ++it) {
    fit.iterations = it + 1;
    Eigen::Matrix<double, 5, 5> a = jtj;
    a.diagonal() *= 1.0 + lambda;
    a.diagonal().array() += 1e-12;
    const Eigen::Matrix<double, 5, 1> delta = a.ldlt().solve(-jtr);
    Params trial{p.a + delta[0], p.b + delta[1], p.c + delta[2], p.e + delta[3],
                 std::max(p.s + delta[4], kMinSigmaPx)};
    // One pass gives the trial's cost and, if it is accepted, the next step's system.
    Eigen::Matrix<double, 5, 5> trial_jtj;
    Eigen::Matrix<double, 5, 1> trial_jtr;
    const double trial_cost = Evaluate(samples, trial, u_ref, shape, &trial_jtj, &trial_jtr);
    if (trial_cost <= cost) {
      const bool small_step = std::abs(delta[3]) < 2e-5 && std::abs(delta[4]) < 2e-4;
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
  fit.edge_px = p.e;
  fit.sigma_px = p.s;
  fit.step = p.c;
  fit.base = p.a;
  fit.slope_per_px = p.b;
  const int dof = fit.samples - 5;
  fit.rms = std::sqrt(cost / fit.samples);
  const double residual_var = dof > 0 ? cost / dof : 0.0;
  const Eigen::Matrix<double, 5, 5> cov = jtj.ldlt().solve(Eigen::Matrix<double, 5, 5>::Identity());
  fit.edge_sigma_px = std::sqrt(std::max(0.0, cov(3, 3) * residual_var));
  if (!std::isfinite(fit.edge_px) || !std::isfinite(fit.sigma_px)) fit.converged = false;
  return fit;
}

}  // namespace

EdgeFit FitBlurredStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                       double sigma_guess_px, double u_ref) {
  EdgeFit fit;
  fit.samples = static_cast<int>(samples.size());
  if (samples.size() < 8) return fit;
  // Start from the plateau means on either side of the guess.
  double lo_sum = 0, hi_sum = 0;
  int lo_n = 0, hi_n = 0;
  const double guard = 2.0 * sigma_guess_px + 0.5;
  for (const auto& smp : samples) {
    if (smp.u_px < edge_guess_px - guard) {
      lo_sum += smp.value;
      ++lo_n;
    } else if (smp.u_px > edge_guess_px + guard) {
      hi_sum += smp.value;
      ++hi_n;
    }
  }
  if (lo_n == 0 || hi_n == 0) return fit;
  const Params p{lo_sum / lo_n, 0.0, hi_sum / hi_n - lo_sum / lo_n, edge_guess_px,
                 std::max(sigma_guess_px, 0.5)};
  return Solve(samples, p, u_ref, StepShape());
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
  const Params p{far_sum / far_n, 0.0, near_v - far_sum / far_n, centre_guess_px,
                 std::max(width_guess_px, 0.5)};
  return Solve(samples, p, centre_guess_px, GaussianShape());
}

}  // namespace clogscope::vision
