#include "calib/pixel_scale.h"

#include <ceres/ceres.h>
#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "common/robust.h"

namespace clogscope::calib {
namespace {
constexpr double kMinPitchUm = 1.0, kMaxPitchUm = 10000.0;  // stage micrometers in use

// Floor on a target's standard deviation, px: below this, measured σ reflects only pixel noise,
// not the unmodelled effects (pin roundness, line quality) that dominate real residuals.
constexpr double kSigmaFloorPx = 0.002;

// A line centre's σ in px, floored.
double LineSigma(const LineObservation& l) {
  return std::sqrt(l.sigma_px * l.sigma_px + kSigmaFloorPx * kSigmaFloorPx);
}

struct PinResidual {
  double diameter_um, width_px, sigma_px;
  bool with_bias;
  template <typename T>
  bool operator()(const T* scale, const T* bias, T* r) const {
    const T model = T(diameter_um) / scale[0] + (with_bias ? bias[0] : T(0));
    r[0] = (model - T(width_px)) / T(sigma_px);
    return true;
  }
};

struct LineResidual {
  double offset_index, pitch_um, position_px, sigma_px;
  template <typename T>
  bool operator()(const T* scale, const T* x0, const T* d2, T* r) const {
    const T model =
        x0[0] + T(offset_index * pitch_um) / scale[0] + d2[0] * T(offset_index * offset_index);
    r[0] = (model - T(position_px)) / T(sigma_px);
    return true;
  }
};

// A problem whose residual blocks can be re-added with another loss: it keeps the cost functions.
struct RobustProblem {
  RobustProblem() : problem(Options()) {}
  static ceres::Problem::Options Options() {
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return po;
  }
  void Add(ceres::CostFunction* cost, std::vector<double*> blocks) {
    owned.emplace_back(cost);
    costs.push_back(cost);
    params.push_back(blocks);
    ids.push_back(problem.AddResidualBlock(cost, nullptr, blocks));
  }
  ceres::Problem problem;
  std::vector<std::unique_ptr<ceres::CostFunction>> owned;
  std::vector<ceres::CostFunction*> costs;
  std::vector<ceres::ResidualBlockId> ids;
  std::vector<std::vector<double*>> params;
};

// Least squares, then rounds with a Huber loss at 3× the normalised residuals' robust spread,
// re-estimated each round from the previous solution: a bad target must not pull the scale, and a
// spread measured around a solution it already pulled would be too generous.
void SolveRobust(RobustProblem& rp, int max_iterations, ceres::Solver::Summary* summary) {
  ceres::Problem& problem = rp.problem;
  std::vector<ceres::ResidualBlockId>& blocks = rp.ids;
  const std::vector<ceres::CostFunction*>& costs = rp.costs;
  const std::vector<std::vector<double*>>& params = rp.params;
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.function_tolerance = 1e-14;
  so.parameter_tolerance = 1e-14;
  so.logging_type = ceres::SILENT;
  ceres::Solve(so, &problem, summary);
  if (blocks.size() <= 2) return;
  constexpr int kRounds = 3;
  for (int round = 0; round < kRounds; ++round) {
    std::vector<double> abs_r;
    for (auto id : blocks) {
      double r = 0;
      problem.EvaluateResidualBlock(id, /*apply_loss_function=*/false, nullptr, &r, nullptr);
      abs_r.push_back(std::abs(r));
    }
    const double spread = std::max(1.0, kMadToSigma * UpperMedian(abs_r));
    for (auto id : blocks) problem.RemoveResidualBlock(id);
    for (size_t i = 0; i < costs.size(); ++i) {
      blocks[i] = problem.AddResidualBlock(costs[i], new ceres::HuberLoss(3.0 * spread), params[i]);
    }
    ceres::Solve(so, &problem, summary);
  }
}

// σ of the parameters from ceres::Covariance scaled by the residual variance; false when the
// covariance cannot be computed (unknowns not separable).
bool ParameterSigmas(ceres::Problem& problem, const std::vector<double*>& blocks,
                     double residual_var, std::vector<double>* sigmas) {
  // A non-finite parameter (an absurd input scale overflowed the fit) would reach the SVD.
  for (double* b : blocks)
    if (!std::isfinite(*b)) return false;
  if (!std::isfinite(residual_var)) return false;
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::DENSE_SVD;
  ceres::Covariance cov(co);
  std::vector<std::pair<const double*, const double*>> pairs;
  for (double* b : blocks) pairs.push_back({b, b});
  if (!cov.Compute(pairs, &problem)) return false;
  sigmas->clear();
  for (double* b : blocks) {
    double c = 0;
    cov.GetCovarianceBlock(b, b, &c);
    sigmas->push_back(std::sqrt(std::max(0.0, c * residual_var)));
  }
  return true;
}

// Records a target's residual (measured − model) in `cal`, `r` given its name, nominal, measured
// and model values; returns the residual's square in units of its σ.
double AddResidual(TargetResidual r, double sigma_px, ScaleCalibration* cal) {
  r.residual_px = r.measured_px - r.model_px;
  cal->residuals.push_back(r);
  return std::pow(r.residual_px / sigma_px, 2);
}

// The residuals in µm, the worst and the RMS, and the outliers: beyond the options' threshold in
// units of the residuals' robust spread (their MAD as a σ, at least the σ floor).
void Summarise(ScaleCalibration* cal, const ScaleFitOptions& opt) {
  std::vector<double> abs_res;
  for (const auto& r : cal->residuals) abs_res.push_back(std::abs(r.residual_px));
  const double robust_spread_px = std::max(kMadToSigma * UpperMedian(abs_res), kSigmaFloorPx);
  double sum2 = 0;
  cal->worst_residual_px = 0;
  for (auto& r : cal->residuals) {
    r.residual_um = r.residual_px * cal->scale_um_per_px;
    sum2 += r.residual_px * r.residual_px;
    if (std::abs(r.residual_px) > std::abs(cal->worst_residual_px))
      cal->worst_residual_px = r.residual_px;
    r.outlier = std::abs(r.residual_px) > opt.outlier_threshold_sigma * robust_spread_px;
    cal->outliers += r.outlier;
  }
  cal->targets = static_cast<int>(cal->residuals.size());
  cal->rms_residual_px = std::sqrt(sum2 / std::max<size_t>(cal->residuals.size(), 1));
  cal->rms_residual_um = cal->rms_residual_px * cal->scale_um_per_px;
  cal->worst_residual_um = cal->worst_residual_px * cal->scale_um_per_px;
}

}  // namespace

bool ScaleFitOptions::Validate(std::string* why) const {
  if (!(outlier_threshold_sigma > 0) || max_iterations < 1) {
    *why = "outlier threshold and iterations must be positive";
    return false;
  }
  return true;
}

double ScaleCalibration::ToMicrons(double width_px) const {
  return (width_px - edge_bias_px) * scale_um_per_px;
}

double ScaleCalibration::MicronsSigma(double width_px, double width_sigma_px) const {
  const double a = width_sigma_px * scale_um_per_px;
  const double b = (width_px - edge_bias_px) * scale_sigma_um_per_px;
  const double c = edge_bias_sigma_px * scale_um_per_px;
  return std::sqrt(a * a + b * b + c * c);
}

ScaleCalibration FitPinScale(const std::vector<PinObservation>& pins, const ScaleFitOptions& opt) {
  std::string why;
  if (!opt.Validate(&why)) throw std::invalid_argument(why);
  if (pins.empty()) throw std::invalid_argument("no pins to calibrate from");
  std::set<double> diameters;
  for (const auto& p : pins) {
    if (!(p.diameter_um > 0))
      throw std::invalid_argument(
          fmt::format("{}: diameter {} µm must be positive", p.name, p.diameter_um));
    if (!(p.width_px > 0))
      throw std::invalid_argument(fmt::format("{}: no width measured", p.name));
    if (p.tolerance_um < 0)
      throw std::invalid_argument(fmt::format("{}: tolerance must not be negative", p.name));
    diameters.insert(p.diameter_um);
  }
  const bool with_bias = pins.size() > 1;
  if (with_bias && diameters.size() < 2) {
    throw std::invalid_argument(fmt::format(
        "all {} pins have the same diameter ({} µm): scale and edge bias cannot be told apart; use "
        "pins of different diameters",
        pins.size(), *diameters.begin()));
  }
  // Start: through the first and last diameters (or the one pin).
  const auto [mn, mx] = std::minmax_element(
      pins.begin(), pins.end(),
      [](const auto& a, const auto& b) { return a.diameter_um < b.diameter_um; });
  double scale = with_bias ? (mx->diameter_um - mn->diameter_um) / (mx->width_px - mn->width_px)
                           : pins[0].diameter_um / pins[0].width_px;
  if (!(scale > 0)) scale = pins[0].diameter_um / pins[0].width_px;
  double bias = 0;

  // Each pin's σ in px: its measured width's, its diameter tolerance at the starting scale, a
  // floor.
  std::vector<double> sigmas;
  for (const auto& p : pins) {
    sigmas.push_back(std::sqrt(p.width_sigma_px * p.width_sigma_px +
                               std::pow(p.tolerance_um / scale, 2) +
                               kSigmaFloorPx * kSigmaFloorPx));
  }
  RobustProblem rp;
  ceres::Problem& problem = rp.problem;
  for (size_t i = 0; i < pins.size(); ++i) {
    const auto& p = pins[i];
    rp.Add(new ceres::AutoDiffCostFunction<PinResidual, 1, 1, 1>(
               new PinResidual{p.diameter_um, p.width_px, sigmas[i], with_bias}),
           {&scale, &bias});
  }
  problem.SetParameterLowerBound(&scale, 0, 1e-9);
  if (!with_bias) problem.SetParameterBlockConstant(&bias);
  ceres::Solver::Summary summary;
  SolveRobust(rp, opt.max_iterations, &summary);

  ScaleCalibration cal;
  cal.method = "pins";
  cal.scale_um_per_px = scale;
  cal.edge_bias_px = bias;
  cal.edge_bias_fitted = with_bias;
  double chi2 = 0;
  for (size_t i = 0; i < pins.size(); ++i) {
    const auto& p = pins[i];
    chi2 += AddResidual({p.name, p.diameter_um, p.width_px, p.diameter_um / scale + bias},
                        sigmas[i], &cal);
  }
  const int unknowns = with_bias ? 2 : 1;
  const int dof = static_cast<int>(pins.size()) - unknowns;
  // With no redundancy the residuals say nothing about the noise: use the measurement σ alone.
  const double residual_var = dof > 0 ? chi2 / dof : 1.0;
  std::vector<double*> blocks = {&scale};
  if (with_bias) blocks.push_back(&bias);
  std::vector<double> sig;
  const bool ok = ParameterSigmas(problem, blocks, residual_var, &sig);
  cal.scale_sigma_um_per_px = ok ? sig[0] : NAN;
  cal.edge_bias_sigma_px = ok && with_bias ? sig[1] : 0.0;
  Summarise(&cal, opt);
  const bool converged = summary.termination_type == ceres::CONVERGENCE;
  cal.usable = converged && ok;
  if (!converged) {
    cal.message = "the fit did not converge: " + summary.message;
  } else if (!ok) {
    cal.message = "scale and edge bias cannot be told apart (covariance rank-deficient)";
  } else if (!with_bias) {
    cal.message =
        "one pin: edge bias held at 0, the scale absorbs any edge bias; σ from the width alone";
  } else if (dof == 0) {
    cal.message =
        "two pins: no redundancy, σ from the widths' own σ (residuals are zero by construction)";
  }
  return cal;
}

std::vector<LineObservation> IndexLines(const std::vector<double>& pos,
                                        const std::vector<double>& sig, int image) {
  if (pos.size() < 2) throw std::invalid_argument("fewer than 2 lines to index");
  std::vector<double> gaps;
  for (size_t i = 1; i < pos.size(); ++i) gaps.push_back(pos[i] - pos[i - 1]);
  const double spacing = UpperMedian(gaps);
  if (!(spacing > 0)) throw std::invalid_argument("line positions are not increasing");
  std::vector<LineObservation> out;
  for (size_t i = 0; i < pos.size(); ++i) {
    const double k = (pos[i] - pos[0]) / spacing;
    const int idx = static_cast<int>(std::lround(k));
    if (std::abs(k - idx) > 0.25) {
      throw std::invalid_argument(
          fmt::format("line at {:.2f} px is {:.2f} spacings from its slot (spacing {:.2f} px): the "
                      "lines are not "
                      "evenly spaced, so no pitch fits them",
                      pos[i], k - idx, spacing));
    }
    if (!out.empty() && out.back().index == idx) {
      throw std::invalid_argument(
          fmt::format("two lines fall in slot {} (at {:.2f} px)", idx, pos[i]));
    }
    out.push_back({image, idx, pos[i], i < sig.size() ? sig[i] : 0.0});
  }
  return out;
}

ScaleCalibration FitMicrometerScale(const std::vector<LineObservation>& lines, double pitch_um,
                                    const ScaleFitOptions& opt) {
  std::string why;
  if (!opt.Validate(&why)) throw std::invalid_argument(why);
  // A stage micrometer's lines lie 1 µm to 10 mm apart; anything else is mistyped, and huge or
  // tiny values overflow the fit.
  if (!(pitch_um >= kMinPitchUm && pitch_um <= kMaxPitchUm)) {
    throw std::invalid_argument(fmt::format("--pitch-um {}: must be between {} and {} µm", pitch_um,
                                            kMinPitchUm, kMaxPitchUm));
  }
  std::set<std::pair<int, int>> seen;
  int kmin = lines[0].index, kmax = lines[0].index, images = 0;
  for (const auto& l : lines) {
    if (l.image < 0) throw std::invalid_argument("negative image number");
    if (!seen.insert({l.image, l.index}).second) {
      throw std::invalid_argument(
          fmt::format("line index {} repeated in image {}", l.index, l.image));
    }
    kmin = std::min(kmin, l.index);
    kmax = std::max(kmax, l.index);
    images = std::max(images, l.image + 1);
  }
  const int unknowns = 1 + images + (opt.fit_distortion ? 1 : 0);
  if (static_cast<int>(lines.size()) < unknowns + 1) {
    throw std::invalid_argument(
        fmt::format("{} line(s) found; the fit needs at least {}", lines.size(), unknowns + 1));
  }
  const double kmid = 0.5 * (kmin + kmax);
  // Start: the scale from the end lines of the first image; each offset from its own lines.
  double scale = 0;
  {
    const LineObservation *first = nullptr, *last = nullptr;
    for (const auto& l : lines) {
      if (l.image != lines[0].image) continue;
      if (!first || l.index < first->index) first = &l;
      if (!last || l.index > last->index) last = &l;
    }
    if (last->index == first->index || !(last->position_px > first->position_px)) {
      throw std::invalid_argument("line positions do not increase with their index");
    }
    scale = pitch_um * (last->index - first->index) / (last->position_px - first->position_px);
  }
  std::vector<double> x0(images, 0.0);
  std::vector<int> count(images, 0);
  for (const auto& l : lines) {
    x0[l.image] += l.position_px - (l.index - kmid) * pitch_um / scale;
    ++count[l.image];
  }
  for (int i = 0; i < images; ++i) {
    if (count[i] == 0) throw std::invalid_argument(fmt::format("image {} has no lines", i));
    x0[i] /= count[i];
  }
  double d2 = 0;

  RobustProblem rp;
  ceres::Problem& problem = rp.problem;
  for (const auto& l : lines) {
    const double sigma = LineSigma(l);
    rp.Add(new ceres::AutoDiffCostFunction<LineResidual, 1, 1, 1, 1>(
               new LineResidual{l.index - kmid, pitch_um, l.position_px, sigma}),
           {&scale, &x0[l.image], &d2});
  }
  problem.SetParameterLowerBound(&scale, 0, 1e-9);
  if (!opt.fit_distortion) problem.SetParameterBlockConstant(&d2);
  ceres::Solver::Summary summary;
  SolveRobust(rp, opt.max_iterations, &summary);

  ScaleCalibration cal;
  cal.method = "micrometer";
  cal.scale_um_per_px = scale;
  cal.distortion_px = d2;
  cal.distortion_fitted = opt.fit_distortion;
  double chi2 = 0;
  for (const auto& l : lines) {
    const double k = l.index - kmid;
    chi2 += AddResidual(
        {images > 1 ? fmt::format("image {} line {}", l.image, l.index)
                    : fmt::format("line {}", l.index),
         l.index * pitch_um, l.position_px, x0[l.image] + k * pitch_um / scale + d2 * k * k},
        LineSigma(l), &cal);
  }
  const int dof = static_cast<int>(lines.size()) - unknowns;
  std::vector<double*> blocks = {&scale};
  if (opt.fit_distortion) blocks.push_back(&d2);
  std::vector<double> sig;
  const bool ok = ParameterSigmas(problem, blocks, chi2 / dof, &sig);
  cal.scale_sigma_um_per_px = ok ? sig[0] : NAN;
  cal.distortion_sigma_px = ok && opt.fit_distortion ? sig[1] : 0.0;
  Summarise(&cal, opt);
  const bool converged = summary.termination_type == ceres::CONVERGENCE;
  cal.usable = converged && ok;
  cal.message = !converged ? "the fit did not converge: " + summary.message
                : !ok
                    ? "the unknowns cannot be told apart (covariance rank-deficient)"
                    : "a micrometer gives the scale only: edge bias 0 (line centres do not see it)";
  return cal;
}

}  // namespace clogscope::calib
