#pragma once

// `clogscope predict`: diameter table -> predicted vibration and motor current; fits.

#include <optional>
#include <string>
#include <vector>

#include "model/prediction_run.h"

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

// Reads the diameter table and predicts from it (model::PredictSteps): the extruder, steps, fit
// and prediction; writes nothing. Throws std::invalid_argument naming the file, row or parameter
// for bad input. A fit that is not usable comes back with fit->usable false and no prediction.
model::PredictionRun ComputePrediction(const PredictCommandOptions& options);

}  // namespace clogscope::apps
