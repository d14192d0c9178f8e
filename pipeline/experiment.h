#pragma once

#include <atomic>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "model/step_status.h"
#include "pipeline/feedstock.h"
#include "pipeline/manifest.h"
#include "pipeline/statistics.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

// One measured frame of a step.
struct FrameRecord {
  std::string source;
  int frame = 0;
  double time_s = -1;
  vision::StrandMeasurement m;
  bool used = false;  // valid and kept by the outlier rejection
  std::vector<std::string>
      fields;  // its per-frame CSV fields (kept for steps read back by --resume)
};

// A step's outcome: the diameter table's row and the frames behind it.
struct StepResult {
  StepSpec spec;
  model::StepStatus status = model::StepStatus::kFailed;  // until measured
  std::string detail;
  int n_examined = 0, n_valid = 0, n_used = 0, n_rejected = 0;
  double mean_px = 0, std_px = 0;
  // In µm through the conversion (empty table cells without one).
  bool has_um = false;
  double mean_um = 0, std_um = 0, sem_um = 0;
  double cal_sigma_um = 0;  // the calibration's share of the mean's uncertainty (systematic)
  double ci95_um = 0;       // half-width: t·SEM and 1.96·cal_sigma in quadrature
  std::vector<FrameRecord> frames;
  bool resumed = false;  // read back from an earlier run
  // The step's feedstock filament, when the manifest films it (pipeline/feedstock.h).
  std::optional<FeedstockResult> feedstock;
};

struct ExperimentOptions {
  int samples = 50;
  int jobs = 0;  // steps measured at once; 0 = all cores
  bool resume = false;
  std::string out_dir;
  std::string overlay_dir;  // empty: out_dir/overlays
  int overlays_per_step = 3;
  double outlier_mad_k = 3.5;
  vision::StrandMeasureOptions strand;
  std::optional<calib::ScaleCalibration> conversion;  // a calibration, or a plain scale as one
  // How steps naming a feedstock video measure it; without, their feedstock is not measured.
  std::optional<FeedstockOptions> feedstock;
  std::atomic<bool>* cancel = nullptr;  // set (e.g. by Ctrl-C) to stop early
  // Called after each step (from the worker that ran it, serialised).
  std::function<void(const StepResult&, int done, int total)> on_step;
  bool Validate(std::string* why) const;
};

// Measures one step: N valid frames spread evenly over its settled part (the first valid frame from
// the middle of each of N equal slots on), outliers rejected by MAD. Video parts are reached by
// seeking. An unreadable source gives status kFailed, never an exception.
StepResult MeasureStep(const StepSpec& spec, const ExperimentOptions& options,
                       int decoder_threads = 0,
                       std::vector<std::pair<int, cv::Mat>>* overlay_frames = nullptr);

// Runs every step (in parallel, `jobs` at a time), writing each finished step to
// out_dir/steps/step_N.json at once (so --resume and an interrupted run keep it) and its overlays
// to out_dir/overlays/. Returns the results in step order: finished ones only when cancelled.
std::vector<StepResult> RunExperiment(const Manifest& manifest, const ExperimentOptions& options);

// The tables: out_dir/frames.csv, diameters.csv, diameters.json and diameter_vs_temperature.png,
// each written atomically. Returns the files written; a plot problem goes to `warnings`.
std::vector<std::string> WriteExperimentTables(const Manifest& manifest,
                                               const std::vector<StepResult>& results,
                                               const ExperimentOptions& options,
                                               std::vector<std::string>* warnings);

// The per-frame CSV's columns (for `measure` on plain inputs too), and one row.
const std::vector<std::string>& FrameColumns();
std::vector<std::string> FrameFields(const std::string& source, int frame, double time_s,
                                     const vision::StrandMeasurement& m,
                                     const std::optional<calib::ScaleCalibration>& conversion);

// The 95 % half-width (µm) of the mean width of `st`: its own (t(0.975, n−1)·SEM, or one frame's
// noise when the frames repeat, and 1.96 × the frames' model doubt) and 1.96 × the calibration's
// share (scale and edge-bias σ at that width, the same for every frame) in quadrature; that share
// goes to *cal_sigma_um. NaN with fewer than two widths.
double MeanCi95Um(const WidthStats& st, const calib::ScaleCalibration& c, double* cal_sigma_um);

// The diameter table's precision: µm to 3 decimals, temperatures to 2. The predictor is given the
// values as the table holds them (TableValue), so `run` and `predict --diameters` agree to the
// byte.
constexpr int kTableUmDecimals = 3, kTableTemperatureDecimals = 2;
// `value` as the table writes it (CsvNumber with `decimals`), read back as a number.
double TableValue(double value, int decimals);

// A plain scale as a calibration with no bias and no uncertainty.
calib::ScaleCalibration PlainScale(double scale_um_per_px);

}  // namespace clogscope::pipeline
