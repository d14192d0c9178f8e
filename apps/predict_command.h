#pragma once

// `clogscope predict`: diameter table -> predicted vibration and motor current; fits.

#include <optional>
#include <string>
#include <vector>

#include "model/fit.h"
#include "model/parameters.h"
#include "model/predictor.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunPredict(int argc, char** argv);

struct PredictCommandOptions {
  std::string extruder = "direct-pla";  // preset name or YAML file
  std::vector<std::string> set;         // "name=value" overrides, applied in order
  std::string diameters;                // diameter table CSV (step, temperature_c, mean_um, …)
  std::string out_dir = "predict-out";
  std::string fit_measured;             // measured CSV; empty: no fit
  std::vector<std::string> fit_params;  // names of the unknowns
  bool plots = true;
  bool Validate(std::string* why) const;
};

struct PredictResult {
  model::ExtruderParams params;  // as loaded and overridden (the fit's start)
  std::vector<model::StepInput> steps;
  std::optional<model::FitSummary> fit;
  model::Prediction prediction;  // with the fitted parameters when a fit was asked for and usable
};

// Reads the inputs, fits when asked and predicts; writes nothing. Throws std::invalid_argument
// naming the file, row or parameter for bad input. A fit that is not usable comes back with
// fit->usable false and no prediction.
PredictResult ComputePrediction(const PredictCommandOptions& options);

// Writes predictions.csv/.json, plots, and with a fit fitted_params.yaml and fit_residuals.png into
// out_dir, each atomically. Returns the files written; plot problems go to `warnings`.
std::vector<std::string> WritePredictionOutputs(const PredictResult& result,
                                                const std::string& out_dir, bool plots,
                                                std::vector<std::string>* warnings);

// The extruder preset or YAML file with "name=value" overrides applied in order, validated. Throws
// std::invalid_argument naming --set or the parameter.
model::ExtruderParams LoadExtruderWithOverrides(const std::string& extruder,
                                                const std::vector<std::string>& set);

}  // namespace clogscope::apps
