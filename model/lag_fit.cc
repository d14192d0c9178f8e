#include "model/lag_fit.h"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/robust.h"

namespace clogscope::model {
namespace {

// All residuals in one block: the simulation walks the profile once for every sample.
struct WidthResiduals {
  const FlowProfile* profile;
  std::vector<WidthSample> samples;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    std::vector<T> times;
    times.reserve(samples.size());
    for (const auto& s : samples) times.push_back(T(s.time_s) - x[2]);
    const std::vector<T> q = OutletFlow(*profile, x[0], 0.0, times);
    for (size_t i = 0; i < samples.size(); ++i) r[i] = x[1] * q[i] - T(samples[i].width);
    return true;
  }
};

// Coarse search over K (log grid) and offset, the gain in closed form at each: a start that does
// not depend on the user's guess.
std::array<double, 3> GridStart(const FlowProfile& p, const std::vector<WidthSample>& s,
                                const LagFitOptions& o) {
  double dt = (s.back().time_s - s.front().time_s) / (s.size() - 1);
  // Half a frame interval, at most a tenth of the range; coarser when the range would need more
  // than kMaxGridOffsets steps a side (the solver refines the start).
  const double offset_step =
      std::max({std::min(dt / 2, o.max_offset_s / 10), o.max_offset_s / kMaxGridOffsets, 1e-4});
  const int offsets = static_cast<int>(
      std::min(std::floor(o.max_offset_s / offset_step), static_cast<double>(kMaxGridOffsets)));
  std::array<double, 3> best{1, 1, 0};
  double best_sse = INFINITY;
  std::vector<double> times(s.size());
  for (int ik = 0; ik <= 40; ++ik) {
    const double k = o.min_k_s * std::pow(o.max_k_s / o.min_k_s, ik / 40.0);
    for (int io = -offsets; io <= offsets; ++io) {
      const double offset = io * offset_step;
      for (size_t i = 0; i < s.size(); ++i) times[i] = s[i].time_s - offset;
      const std::vector<double> q = OutletFlow(p, k, 0.0, times);
      double wq = 0, qq = 0, ww = 0;
      for (size_t i = 0; i < s.size(); ++i) {
        wq += s[i].width * q[i];
        qq += q[i] * q[i];
        ww += s[i].width * s[i].width;
      }
      if (!(qq > 0)) continue;
      const double sse = ww - wq * wq / qq;
      if (sse < best_sse) {
        best_sse = sse;
        best = {k, wq / qq, offset};
      }
    }
  }
  return best;
}

struct Solved {
  std::array<double, 3> x;
  ceres::Solver::Summary summary;
  std::array<double, 9> covariance;
  bool covariance_ok = false;
};

Solved Solve(const FlowProfile& p, const std::vector<WidthSample>& s, std::array<double, 3> start,
             const LagFitOptions& o) {
  Solved out;
  out.x = start;
  ceres::Problem problem;
  auto* cost = new ceres::AutoDiffCostFunction<WidthResiduals, ceres::DYNAMIC, 3>(
      new WidthResiduals{&p, s}, static_cast<int>(s.size()));
  problem.AddResidualBlock(cost, nullptr, out.x.data());
  problem.SetParameterLowerBound(out.x.data(), 0, o.min_k_s);
  problem.SetParameterUpperBound(out.x.data(), 0, o.max_k_s);
  if (o.max_offset_s > 0) {
    problem.SetParameterLowerBound(out.x.data(), 2, -o.max_offset_s);
    problem.SetParameterUpperBound(out.x.data(), 2, o.max_offset_s);
  } else {  // the clocks are known to agree: hold the offset at 0
    problem.SetManifold(out.x.data(), new ceres::SubsetManifold(3, {2}));
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  // The response's time derivative has a corner at every step of the profile: when a frame time
  // sits on one, the last digits of the cost chatter as the offset moves. Relative changes of
  // 1e-10 are converged for any width measurement.
  so.function_tolerance = 1e-10;
  so.parameter_tolerance = 1e-10;
  so.gradient_tolerance = 1e-14;
  so.logging_type = ceres::SILENT;
  ceres::Solve(so, &problem, &out.summary);
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> blocks = {{out.x.data(), out.x.data()}};
  out.covariance_ok = cov.Compute(blocks, &problem) &&
                      cov.GetCovarianceBlock(out.x.data(), out.x.data(), out.covariance.data());
  return out;
}

}  // namespace

bool LagFitOptions::Validate(std::string* why) const {
  if (!(min_k_s > 0 && max_k_s > min_k_s && std::isfinite(max_k_s)))
    *why = "K bounds: need 0 < min < max";
  else if (!(max_offset_s >= 0 && max_offset_s <= kMaxLagOffsetS))
    *why = fmt::format(
        "--max-offset-s {:g}: must be in [0, {:g}] s (shift the profile's times for clocks "
        "further apart)",
        max_offset_s, kMaxLagOffsetS);
  else if (!(outlier_threshold_sigma > 1))
    *why = "outlier threshold must exceed 1 σ";
  else if (!(max_iterations >= 1 && max_iterations <= kMaxLagIterations))
    *why =
        fmt::format("solver iterations {}: must be in [1, {}]", max_iterations, kMaxLagIterations);
  else
    return true;
  return false;
}

LagFitSummary FitLag(const FlowProfile& p, const std::vector<WidthSample>& samples,
                     const LagFitOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument("lag fit: " + why);
  if (!p.Validate(&why)) throw std::invalid_argument("commanded profile: " + why);
  if (samples.size() < 8) {
    throw std::invalid_argument(
        fmt::format("lag fit: {} valid widths; at least 8 are needed", samples.size()));
  }
  for (size_t i = 1; i < samples.size(); ++i) {
    if (!(samples[i].time_s > samples[i - 1].time_s)) {
      throw std::invalid_argument(fmt::format(
          "lag fit: frame times must increase (sample {} at {:g} s)", i + 1, samples[i].time_s));
    }
  }
  const double s0 = samples.front().time_s, s1 = samples.back().time_s;
  if (p.EndS() < s0 - o.max_offset_s || p.StartS() > s1 + o.max_offset_s) {
    throw std::invalid_argument(fmt::format(
        "the commanded profile ({:g}…{:g} s) does not overlap the frames' time span ({:g}…{:g} s)",
        p.StartS(), p.EndS(), s0, s1));
  }
  double lo = p.At(s0 - o.max_offset_s), hi = lo;
  for (size_t i = 0; i < p.time_s.size(); ++i) {
    if (p.time_s[i] < s0 - o.max_offset_s || p.time_s[i] > s1 + o.max_offset_s) continue;
    lo = std::min(lo, p.flow_mm3_s[i]);
    hi = std::max(hi, p.flow_mm3_s[i]);
  }
  if (!(hi - lo > 1e-9 * std::max(1.0, std::abs(hi)))) {
    throw std::invalid_argument(fmt::format(
        "the commanded flow does not change during the frames ({:g}…{:g} s): nothing to fit K to",
        s0, s1));
  }

  LagFitSummary out;
  out.samples_total = static_cast<int>(samples.size());
  Solved fit = Solve(p, samples, GridStart(p, samples, o), o);

  // One round of outlier rejection on the robust spread of the residuals (a bad frame's width
  // must not bend K), then a refit from the first solution.
  const WidthResiduals all{&p, samples};
  std::vector<double> r(samples.size());
  all(fit.x.data(), r.data());
  std::vector<double> abs_dev(r.size());
  const double med = UpperMedian(r);
  for (size_t i = 0; i < r.size(); ++i) abs_dev[i] = std::abs(r[i] - med);
  const double robust_sigma = kMadToSigma * UpperMedian(abs_dev);
  out.outlier.assign(samples.size(), false);
  std::vector<WidthSample> inliers;
  for (size_t i = 0; i < samples.size(); ++i) {
    out.outlier[i] = robust_sigma > 0 && abs_dev[i] > o.outlier_threshold_sigma * robust_sigma;
    if (out.outlier[i])
      ++out.outliers;
    else
      inliers.push_back(samples[i]);
  }
  if (out.outliers > 0 && inliers.size() >= 8) fit = Solve(p, inliers, fit.x, o);
  if (inliers.size() < 8) inliers = samples;

  out.k_s = fit.x[0];
  out.gain = fit.x[1];
  out.offset_s = fit.x[2];
  out.k_la_s = out.k_s;
  out.iterations = static_cast<int>(fit.summary.iterations.size());
  out.solver_report = fit.summary.BriefReport();
  out.samples_used = static_cast<int>(inliers.size());
  all(fit.x.data(), r.data());
  double sum2 = 0;
  for (size_t i = 0; i < samples.size(); ++i) {
    out.fitted_width.push_back(samples[i].width + r[i]);
    if (out.outlier[i]) continue;
    sum2 += r[i] * r[i];
    if (std::abs(r[i]) > std::abs(out.worst_residual)) {
      out.worst_residual = r[i];
      out.worst_time_s = samples[i].time_s;
    }
  }
  out.rms = std::sqrt(sum2 / out.samples_used);
  const double variance = sum2 / std::max(out.samples_used - 3, 1);
  auto sigma = [&](int j) {
    const double v = fit.covariance[4 * j] * variance;
    return fit.covariance_ok && v >= 0 ? std::sqrt(v) : NAN;
  };
  out.k_sigma_s = sigma(0);
  out.gain_sigma = sigma(1);
  out.offset_sigma_s = sigma(2);

  const double span = 1e-6 * out.k_s;
  if (fit.summary.termination_type != ceres::CONVERGENCE) {
    out.message = "the solver did not converge: " + fit.summary.message;
  } else if (out.k_s - o.min_k_s < span || o.max_k_s - out.k_s < span) {
    out.message =
        fmt::format("K ended on its bound {:g} s: the width does not follow a lag in {:g}…{:g} s",
                    out.k_s, o.min_k_s, o.max_k_s);
  } else if (o.max_offset_s > 0 && std::abs(std::abs(out.offset_s) - o.max_offset_s) < 1e-6) {
    out.message = fmt::format(
        "the time offset ended on its bound ±{:g} s: the clocks differ by more (--max-offset-s)",
        o.max_offset_s);
  } else if (!std::isfinite(out.k_sigma_s) || !std::isfinite(out.gain_sigma)) {
    out.message = "K and the time offset cannot be told apart from these data";
  } else {
    out.usable = true;
    out.message = "converged";
  }
  return out;
}

}  // namespace clogscope::model
