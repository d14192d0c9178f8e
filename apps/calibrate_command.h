#pragma once

// `clogscope calibrate`: the pixel scale from pin gauges or a stage micrometer.

#include <string>

#include "pipeline/calibrate_targets.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunCalibrate(int argc, char** argv);

struct CalibrateCommandOptions {
  pipeline::TargetCalibrationOptions targets;  // the reference images and how to read them
  std::string out;                             // calibration YAML
  std::string plot;                            // residual plot PNG; empty: next to out
  bool Validate(std::string* why) const;
};

}  // namespace clogscope::apps
