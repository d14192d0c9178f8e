#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/parameters.h"
#include "model/predictor.h"

namespace clogscope::model {

// What was measured at one step (matched to the diameter table by step number).
struct Measurement {
  int step = 0;
  std::optional<double> amplitude_m_s2;  // accelerometer peak at the natural frequency
  std::optional<double> current_ma;      // feeding motor current
  int source_line = 0;
};

struct FitOptions {
  std::vector<Param> params;  // the unknowns
  int max_iterations = 200;
  double max_solver_time_in_seconds = 30;
  bool Validate(std::string* why) const;
};

struct FittedValue {
  Param param;
  double initial = 0;
  double value = 0;
  double sigma = 0;  // from the covariance scaled by the residual variance; NaN when not separable
  bool at_bound = false;
};

struct FitResidual {
  int step = 0;
  std::string quantity;  // "amplitude_m_s2" or "current_ma"
  double measured = 0;
  double model = 0;
  double relative = 0;  // (model − measured) / measured
};

// The fit's outcome. `usable` is false, with `message` saying why, when the solver did not converge
// or the unknowns cannot be told apart.
struct FitSummary {
  bool usable = false;
  std::string message;
  std::vector<FittedValue> values;
  std::vector<FitResidual> residuals;
  double rms_relative = 0;
  double worst_relative = 0;  // largest |relative residual|
  int worst_index = -1;       // into residuals
  int iterations = 0;
  ExtruderParams fitted;      // the start with the fitted values put in
  std::string solver_report;  // Ceres' brief report
};

// Least squares on relative residuals with each unknown bounded to its physical range (Ceres,
// automatic derivatives). Throws std::invalid_argument for contract violations: no unknowns, more
// unknowns than measurements, a measurement without a step in the table, an amplitude without any
// way to know the gain, a non-positive measured value.
FitSummary FitParameters(const ExtruderParams& start, const std::vector<StepInput>& steps,
                         const std::vector<Measurement>& measurements, const FitOptions& options);

}  // namespace clogscope::model
