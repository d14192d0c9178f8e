#include "vision/edge_fit.h"

#include <Eigen/Dense>
#include <cmath>

namespace clogscope::vision {
namespace {

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;
constexpr double kMinSigmaPx = 0.15;

struct Params {
  double a, b, c, e, s;
};

// Residuals' sum of squares, and optionally the Gauss-Newton system J^T J and J^T r.
double Evaluate(const std::vector<EdgeSample>& samples, const Params& p, double u_ref,
                Eigen::Matrix<double, 5, 5>* jtj, Eigen::Matrix<double, 5, 1>* jtr) {
  double cost = 0;
  if (jtj) {
    jtj->setZero();
    jtr->setZero();
  }
  const double inv_s = 1.0 / p.s;
  for (const auto& smp : samples) {
    const double du = smp.u_px - u_ref;
    const double z = (smp.u_px - p.e) * inv_s;
    const double cdf = 0.5 * std::erfc(-z * kInvSqrt2);
    const double r = p.a + p.b * du + p.c * cdf - smp.value;
    cost += r * r;
    if (jtj) {
      const double pdf = kInvSqrt2Pi * std::exp(-0.5 * z * z);
      Eigen::Matrix<double, 5, 1> j;
      j << 1.0, du, cdf, -p.c * pdf * inv_s, -p.c * pdf * z * inv_s;
      jtj->selfadjointView<Eigen::Lower>().rankUpdate(j);
      *jtr += j * r;
    }
  }
  if (jtj) *jtj = jtj->selfadjointView<Eigen::Lower>();
  return cost;
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
  Params p{lo_sum / lo_n, 0.0, hi_sum / hi_n - lo_sum / lo_n, edge_guess_px,
           std::max(sigma_guess_px, 0.5)};

  Eigen::Matrix<double, 5, 5> jtj;
  Eigen::Matrix<double, 5, 1> jtr;
  double cost = Evaluate(samples, p, u_ref, &jtj, &jtr);
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
    const double trial_cost = Evaluate(samples, trial, u_ref, nullptr, nullptr);
    if (trial_cost <= cost) {
      const bool small_step = std::abs(delta[3]) < 1e-5 && std::abs(delta[4]) < 1e-4;
      p = trial;
      cost = Evaluate(samples, p, u_ref, &jtj, &jtr);
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

}  // namespace clogscope::vision
