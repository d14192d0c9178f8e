#include "model/fit.h"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <stdexcept>

#include "model/physics.h"

namespace clogscope::model {
namespace {

enum class Quantity { kAmplitude, kCurrent };

// (model − measured) / measured for one step and quantity, the unknowns in one parameter block.
struct RelativeResidual {
  std::array<double, kParamCount> base;
  std::vector<int> unknowns;
  bool gain_from_baseline;  // gain not given nor fitted: G = baseline amplitude / W_0
  LoadModel load_model;
  StepInput step;
  Quantity quantity;
  double measured;

  template <typename T>
  bool operator()(T const* const* x, T* residual) const {
    std::array<T, kParamCount> p;
    for (int i = 0; i < kParamCount; ++i) p[i] = T(base[i]);
    for (size_t j = 0; j < unknowns.size(); ++j) p[unknowns[j]] = x[0][j];
    // The step's measured feedstock (if any) sets its back-pressure force; W_0 stays nominal.
    std::array<T, kParamCount> ps = p;
    UseStepFeedstock(step, ps.data());
    const T f_bp = physics::BackPressureForce(ps.data(), T(step.diameter_m), T(step.temperature_c));
    T model;
    if (quantity == Quantity::kAmplitude) {
      const T load = physics::Load(p.data(), f_bp, load_model);
      const T gain = gain_from_baseline ? physics::P(p.data(), Param::kBaselineAmplitudeMS2) /
                                              physics::ReferenceLoad(p.data(), load_model)
                                        : physics::P(p.data(), Param::kGainMS2PerN);
      model = gain * load;
    } else {
      model = physics::MotorCurrent(p.data(), f_bp);
    }
    residual[0] = (model - T(measured)) / T(measured);
    return true;
  }
};

double BackPressureForceAt(const ExtruderParams& params, const StepInput& s) {
  const auto v = StepValues(params, s);
  return physics::BackPressureForce(v.data(), s.diameter_m, s.temperature_c);
}

}  // namespace

bool FitOptions::Validate(std::string* why) const {
  if (params.empty()) {
    *why = "no parameters to fit";
    return false;
  }
  for (size_t i = 0; i < params.size(); ++i) {
    for (size_t j = i + 1; j < params.size(); ++j) {
      if (params[i] == params[j]) {
        *why = fmt::format("{} is listed twice", InfoOf(params[i]).name);
        return false;
      }
    }
  }
  if (max_iterations < 1 || !(max_solver_time_in_seconds > 0)) {
    *why = "max_iterations and max_solver_time_in_seconds must be positive";
    return false;
  }
  return true;
}

FitSummary FitParameters(const ExtruderParams& start_in, const std::vector<StepInput>& steps,
                         const std::vector<Measurement>& measurements, const FitOptions& options) {
  std::string why;
  if (!options.Validate(&why)) throw std::invalid_argument("--fit-params: " + why);
  CheckSteps(start_in, steps);
  std::map<int, const StepInput*> by_step;
  for (const auto& s : steps) by_step[s.step] = &s;

  // Pair each measured value with its step.
  struct Observation {
    const StepInput* step;
    Quantity quantity;
    double measured;
  };
  std::vector<Observation> obs;
  bool any_amplitude = false, any_current = false;
  for (const auto& m : measurements) {
    const auto it = by_step.find(m.step);
    if (it == by_step.end()) {
      throw std::invalid_argument(
          fmt::format("measurement of step {}{}: no such step in the diameter table", m.step,
                      m.source_line ? fmt::format(" (line {})", m.source_line) : ""));
    }
    for (auto [value, q] : {std::make_pair(m.amplitude_m_s2, Quantity::kAmplitude),
                            std::make_pair(m.current_ma, Quantity::kCurrent)}) {
      if (!value) continue;
      if (!(*value > 0)) {
        throw std::invalid_argument(
            fmt::format("measurement of step {}: {} must be positive (relative residuals)", m.step,
                        q == Quantity::kAmplitude ? "amplitude_m_s2" : "current_ma"));
      }
      obs.push_back({it->second, q, *value});
      (q == Quantity::kAmplitude ? any_amplitude : any_current) = true;
    }
  }
  if (options.params.size() >= obs.size()) {
    throw std::invalid_argument(fmt::format("{} unknowns need more than {} measured values",
                                            options.params.size(), obs.size()));
  }

  ExtruderParams start = start_in;
  auto fitted = [&](Param p) {
    return std::find(options.params.begin(), options.params.end(), p) != options.params.end();
  };
  const bool gain_known = start.Has(Param::kGainMS2PerN) || fitted(Param::kGainMS2PerN);
  const bool gain_from_baseline = !gain_known && start.Has(Param::kBaselineAmplitudeMS2);
  if (any_amplitude && !gain_known && !gain_from_baseline) {
    throw std::invalid_argument(
        "amplitudes need the gain: fit 'gain', or give gain_m_s2_per_n or baseline_amplitude_m_s2");
  }
  if (any_current) {
    for (Param p : {Param::kCurrentOffsetMa, Param::kCurrentGainMaPerN}) {
      if (!start.Has(p) && !fitted(p)) {
        throw std::invalid_argument(
            fmt::format("currents need {}: fit it or give it", InfoOf(p).name));
      }
    }
  }
  // Starting values for unknowns the parameter set leaves open: from the data, in closed form.
  if (fitted(Param::kGainMS2PerN) && !start.Has(Param::kGainMS2PerN)) {
    std::vector<double> ratios;
    const auto& v = start.Values();
    for (const auto& o : obs) {
      if (o.quantity != Quantity::kAmplitude) continue;
      const double f =
          physics::BackPressureForce(v.data(), o.step->diameter_m, o.step->temperature_c);
      ratios.push_back(o.measured / physics::Load(v.data(), f, start.load_model));
    }
    std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
    start.Set(Param::kGainMS2PerN, ratios.empty() ? 0.01 : ratios[ratios.size() / 2]);
  }
  const bool open_offset = fitted(Param::kCurrentOffsetMa) && !start.Has(Param::kCurrentOffsetMa);
  const bool open_slope =
      fitted(Param::kCurrentGainMaPerN) && !start.Has(Param::kCurrentGainMaPerN);
  if (open_offset || open_slope) {
    // Straight line of current against back-pressure force.
    double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (const auto& o : obs) {
      if (o.quantity != Quantity::kCurrent) continue;
      const double x = BackPressureForceAt(start, *o.step);
      n += 1;
      sx += x;
      sy += o.measured;
      sxx += x * x;
      sxy += x * o.measured;
    }
    const double det = n * sxx - sx * sx;
    const double slope = std::abs(det) > 1e-12 ? (n * sxy - sx * sy) / det : 0.0;
    if (open_slope) start.Set(Param::kCurrentGainMaPerN, slope);
    if (open_offset) {
      const double g = start.Get(Param::kCurrentGainMaPerN);
      start.Set(Param::kCurrentOffsetMa, n > 0 ? (sy - g * sx) / n : 100.0);
    }
  }
  for (Param p : options.params) {
    if (!start.Has(p)) {
      throw std::invalid_argument(
          fmt::format("{} has no starting value: give one", InfoOf(p).name));
    }
  }
  if (!start.Validate(&why)) throw std::invalid_argument("starting parameters: " + why);

  std::vector<int> unknowns;
  std::vector<double> x;
  for (Param p : options.params) {
    unknowns.push_back(static_cast<int>(p));
    x.push_back(start.Get(p));
  }
  const std::array<double, kParamCount> base = start.Values();

  ceres::Problem problem;
  const int k = static_cast<int>(x.size());
  for (const auto& o : obs) {
    auto* functor = new RelativeResidual{base,    unknowns,   gain_from_baseline, start.load_model,
                                         *o.step, o.quantity, o.measured};
    auto* cost = new ceres::DynamicAutoDiffCostFunction<RelativeResidual, 8>(functor);
    cost->AddParameterBlock(k);
    cost->SetNumResiduals(1);
    problem.AddResidualBlock(cost, nullptr, x.data());
  }
  for (int j = 0; j < k; ++j) {
    const ParamInfo& info = InfoOf(options.params[j]);
    if (info.lower > -1e299) problem.SetParameterLowerBound(x.data(), j, info.lower);
    if (info.upper < 1e299) problem.SetParameterUpperBound(x.data(), j, info.upper);
  }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = options.max_iterations;
  so.max_solver_time_in_seconds = options.max_solver_time_in_seconds;
  so.function_tolerance = 1e-12;
  so.parameter_tolerance = 1e-12;
  so.gradient_tolerance = 1e-14;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary ss;
  ceres::Solve(so, &problem, &ss);

  FitSummary out;
  out.iterations = static_cast<int>(ss.iterations.size());
  out.solver_report = ss.BriefReport();
  out.fitted = start;
  for (int j = 0; j < k; ++j) out.fitted.Set(options.params[j], x[j]);
  out.fitted.origin = start_in.origin + " (fitted)";

  // Residuals at the solution.
  const int m = static_cast<int>(obs.size());
  double sum2 = 0;
  for (int i = 0; i < m; ++i) {
    double r = 0;
    const RelativeResidual f{base,         unknowns,        gain_from_baseline, start.load_model,
                             *obs[i].step, obs[i].quantity, obs[i].measured};
    const double* blocks[] = {x.data()};
    f(blocks, &r);
    FitResidual fr;
    fr.step = obs[i].step->step;
    fr.quantity = obs[i].quantity == Quantity::kAmplitude ? "amplitude_m_s2" : "current_ma";
    fr.measured = obs[i].measured;
    fr.relative = r;
    fr.model = obs[i].measured * (1 + r);
    out.residuals.push_back(fr);
    sum2 += r * r;
    if (out.worst_index < 0 || std::abs(r) > out.worst_relative) {
      out.worst_relative = std::abs(r);
      out.worst_index = i;
    }
  }
  out.rms_relative = std::sqrt(sum2 / m);

  // σ from the covariance of the unknowns, scaled by the residual variance (the measurements'
  // noise is unknown; the residuals estimate it).
  const double dof = m - k;
  const double residual_var = sum2 / dof;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  co.null_space_rank = -1;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> blocks = {{x.data(), x.data()}};
  std::vector<double> c(k * k, NAN);
  const bool cov_ok =
      cov.Compute(blocks, &problem) && cov.GetCovarianceBlock(x.data(), x.data(), c.data());
  // Separability: the Jacobian with unit-norm columns (unknowns differ by many orders of magnitude)
  // must have full rank. The pseudo-inverse above would hide a flat direction.
  bool separable = cov_ok;
  {
    ceres::CRSMatrix crs;
    problem.Evaluate(ceres::Problem::EvaluateOptions(), nullptr, nullptr, nullptr, &crs);
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
    for (int row = 0; row < crs.num_rows; ++row) {
      for (int idx = crs.rows[row]; idx < crs.rows[row + 1]; ++idx)
        jac(row, crs.cols[idx]) = crs.values[idx];
    }
    for (int col = 0; col < jac.cols(); ++col) {
      const double norm = jac.col(col).norm();
      if (norm > 0) jac.col(col) /= norm;
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(jac);
    const auto& sv = svd.singularValues();
    if (sv.size() == 0 || !(sv(sv.size() - 1) > 1e-7 * sv(0))) separable = false;
  }
  for (int j = 0; j < k; ++j) {
    FittedValue fv;
    fv.param = options.params[j];
    fv.initial = start.Get(fv.param);
    fv.value = x[j];
    const double var = c[j * k + j] * residual_var;
    fv.sigma = cov_ok && std::isfinite(var) && var >= 0 ? std::sqrt(var) : NAN;
    if (!std::isfinite(fv.sigma)) separable = false;
    const ParamInfo& info = InfoOf(fv.param);
    const double span = std::max(std::abs(fv.value), 1e-12) * 1e-9;
    fv.at_bound =
        std::abs(fv.value - info.lower) <= span || std::abs(fv.value - info.upper) <= span;
    out.values.push_back(fv);
  }
  const bool converged = ss.termination_type == ceres::CONVERGENCE;
  if (!converged) {
    out.message = "the solver did not converge: " + ss.message;
  } else if (!separable) {
    out.message = "the unknowns cannot be told apart from these data (covariance rank-deficient)";
  } else {
    out.usable = true;
    out.message = "converged";
  }
  return out;
}

}  // namespace clogscope::model
