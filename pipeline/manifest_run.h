#pragma once

// A whole experiment from one manifest, without the command line: the pixel conversion (given, a
// calibration file, or calibrated from the manifest's reference images), every step measured, the
// tables, and (full pipeline) the prediction from the steps just measured and the summary.

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "model/prediction_run.h"
#include "pipeline/band.h"
#include "pipeline/experiment.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

struct ManifestRunOptions {
  std::string manifest;
  std::string out_dir;
  std::optional<int> samples;  // overrides the manifest
  int jobs = 0;                // 0: all cores
  bool resume = false;
  std::optional<double> scale_um_per_px;  // µm/px; overrides the manifest's scale or calibration
  std::string calib_path;
  bool full_pipeline = false;  // run: calibrate when the manifest says, measure, predict, summary
  // How frames are measured: the caliper, blur, contrast and shading settings as they are; the
  // ROI, polarity and target when given, else the manifest's; each part of the band asked for here
  // replaces the manifest's.
  vision::StrandMeasureOptions strand;
  bool roi_given = false, polarity_given = false, target_given = false;
  BandRequest band;
  std::string overlay_dir;              // empty: OUT/overlays
  std::atomic<bool>* cancel = nullptr;  // set (e.g. by Ctrl-C) to stop after the running steps
  // Called after each step (serialised), and with each line worth logging (calibration targets).
  std::function<void(const StepResult&, int done, int total)> on_step;
  std::function<void(const std::string&)> on_note;
  bool Validate(std::string* why) const;
};

struct ManifestRunReport {
  Manifest manifest;
  std::vector<StepResult> steps;
  std::optional<calib::ScaleCalibration> conversion;
  std::optional<model::PredictionRun> prediction;
  std::vector<std::string> files;  // written
  std::vector<std::string> warnings;
  bool cancelled = false;
};

// Loads the manifest, calibrates (full pipeline, when the manifest names reference images; writes
// OUT/calibration.yaml), measures every step, writes the tables, and (full pipeline) predicts from
// the steps' results into OUT/predict/ and writes summary.md/.json. `cancel` stops it early;
// finished steps are kept and their tables written. Throws std::invalid_argument for a bad
// manifest or options (or a calibration that is not usable); a step that fails is reported in
// its row.
ManifestRunReport RunManifest(const ManifestRunOptions& options);

// The predictor's steps from the measured ones, the numbers the diameter table holds (so they
// equal model::ReadDiameterTable of diameters.csv): failed steps left out, mean and feedstock
// diameter in µm at the table's precision. Throws std::invalid_argument for a step with no
// diameter in µm, or when every step failed.
std::vector<model::StepInput> PredictorSteps(const std::vector<StepResult>& steps);

}  // namespace clogscope::pipeline
