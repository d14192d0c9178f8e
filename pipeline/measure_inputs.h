#pragma once

// Strand width per frame from images, folders and videos: the per-frame CSV and overlays that
// `clogscope measure INPUTS` and the Python module's measure() write.

#include <opencv2/core.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "pipeline/band.h"
#include "vision/motion/feed_speed.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

struct MeasureInputsOptions {
  std::vector<std::string> inputs;                     // images, directories of images, videos
  std::optional<double> scale_um_per_px;               // converts widths to µm when given
  std::optional<calib::ScaleCalibration> calibration;  // or a calibration (--calib): scale and bias
  BandRequest band;                     // in µm (needs a scale) or px; default: DefaultBand
  vision::StrandMeasureOptions strand;  // band fields are filled from the above
  std::string out_frames;               // per-frame CSV; empty or "-": standard output
  std::string overlay_dir;              // empty: no overlays
  int overlay_every = 0;                // 0: every image, every 25th video frame
  bool flag_outliers = true;
  bool feed_speed = false;  // filament target: feed speed between consecutive video frames
  vision::FeedSpeedOptions feed;
  std::optional<cv::Rect> gear_roi;           // with feed_speed: the drive gear's surface speed
  std::optional<cv::Point2d> gear_centre_px;  // default: the ROI's centre
  std::optional<double> gear_radius_mm;       // required with gear_roi
  bool Validate(std::string* why) const;
  // The band in px from the µm or px options (throws std::invalid_argument on a conflict).
  void ResolveBand();
  // Widths to µm: the calibration's (w − b)·s with its σ, or a plain scale, or none.
  std::optional<calib::ScaleCalibration> Conversion() const;
  // Whether the per-frame CSV goes to standard output (out_frames empty or "-").
  bool WritesToStdout() const;
};

struct MeasureSummary {
  int inputs_ok = 0;
  int inputs_failed = 0;
  int frames = 0;
  int valid_frames = 0;
  int overlays_written = 0;
  int overlay_frames_held_peak = 0;  // most frames kept at once for overlays still to be drawn
  double seconds = 0;
  std::vector<std::string> errors;  // one line per input that could not be read
};

// Measures every frame of every input and writes the per-frame CSV (atomically) and overlays.
// An input that cannot be opened is reported in the summary and skipped. With `table`, the CSV
// goes there instead of to out_frames (the Python module's measure reads it back).
MeasureSummary MeasureInputs(MeasureInputsOptions options, std::ostream* table = nullptr);

// The per-frame CSV's columns, in order (without the feed-speed columns).
const std::vector<std::string>& FrameCsvColumns();
// What --speed appends to them, and --gear-roi after those.
const std::vector<std::string>& FeedSpeedCsvColumns();
const std::vector<std::string>& GearCsvColumns();

}  // namespace clogscope::pipeline
