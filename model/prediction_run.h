#pragma once

// A prediction from a diameter table's steps: the extruder with its overrides, an optional fit of
// unknowns to measurements, the prediction, and its files. `predict` gives it the steps it reads
// from a CSV; `run` the steps it has just measured (pipeline/manifest_run.h).

#include <optional>
#include <string>
#include <vector>

#include "model/fit.h"
#include "model/parameters.h"
#include "model/predictor.h"

namespace clogscope::model {

// The extruder preset or YAML file with "name=value" overrides applied in order, validated. Throws
// std::invalid_argument naming --set or the parameter.
ExtruderParams LoadExtruderWithOverrides(const std::string& extruder,
                                         const std::vector<std::string>& set);

// What to fit: the measured CSV (step or temperature_c, amplitude_m_s2 and/or current_ma) and the
// names of the unknowns. Both empty: no fit.
struct FitRequest {
  std::string measured_csv;
  std::vector<std::string> params;
};

struct PredictionRun {
  ExtruderParams params;  // as loaded and overridden (the fit's start)
  std::vector<StepInput> steps;
  std::optional<FitSummary> fit;
  Prediction prediction;  // with the fitted parameters when a fit was asked for and usable
};

// Checks the steps against the parameters, fits when asked and predicts; writes nothing. Throws
// std::invalid_argument naming the step, file or parameter for bad input. A fit that is not usable
// comes back with fit->usable false and no prediction.
PredictionRun PredictSteps(const ExtruderParams& params, std::vector<StepInput> steps,
                           const FitRequest& fit = {});

// Writes predictions.csv/.json, plots, and with a fit fitted_params.yaml and fit_residuals.png into
// out_dir (created), each atomically. Returns the files written; plot problems go to `warnings`.
std::vector<std::string> WritePredictionOutputs(const PredictionRun& result,
                                                const std::string& out_dir, bool plots,
                                                std::vector<std::string>* warnings);

}  // namespace clogscope::model
