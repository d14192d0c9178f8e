#pragma once

// `clogscope run` (and `clogscope measure --manifest`): a whole experiment from one manifest.

#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "apps/band.h"
#include "apps/predict_command.h"
#include "calib/pixel_scale.h"
#include "pipeline/experiment.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunRun(int argc, char** argv);

struct ExperimentCommandOptions {
  std::string manifest;
  std::string out_dir;
  std::optional<int> samples;  // overrides the manifest
  int jobs = 0;                // 0: all cores
  bool resume = false;
  std::optional<double> scale_um_per_px;  // overrides the manifest's scale or calibration
  std::string calib_path;
  bool full_pipeline = false;  // run: calibrate when the manifest says, measure, predict, summary
  // How frames are measured (`measure --manifest` takes them from its command line): the caliper,
  // blur, contrast and shading settings as they are; the ROI, polarity and target when given, else
  // the manifest's; each part of the band asked for here replaces the manifest's.
  vision::StrandMeasureOptions strand;
  bool roi_given = false, polarity_given = false, target_given = false;
  BandRequest band;
  std::string overlay_dir;  // empty: OUT/overlays
  bool Validate(std::string* why) const;
};

struct ExperimentReport {
  pipeline::Manifest manifest;
  std::vector<pipeline::StepResult> steps;
  std::optional<calib::ScaleCalibration> conversion;
  std::optional<PredictResult> prediction;
  std::vector<std::string> files;  // written
  std::vector<std::string> warnings;
  bool cancelled = false;
};

// Loads the manifest, calibrates (run only, when the manifest names reference images), measures
// every step, writes the tables, and (run only) predicts and writes summary.md/.json. `cancel`
// stops it early; finished steps are kept and their tables written. Throws std::invalid_argument
// for a bad manifest or options; a step that fails is reported in its row.
ExperimentReport RunExperimentCommand(const ExperimentCommandOptions& options,
                                      std::atomic<bool>* cancel);

// The command-line side shared by `run` and `measure --manifest`: Ctrl-C handling, the printed
// table, the exit status.
int RunExperimentCli(const ExperimentCommandOptions& options);

}  // namespace clogscope::apps
