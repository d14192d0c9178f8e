#pragma once

// The feedstock filament of a step (the feedstock issue): its diameter, feed speed and, with a
// drive gear in view, the gear's surface speed and the slip, from a video of the filament where it
// enters the extruder.
#include <optional>
#include <string>

#include "calib/pixel_scale.h"
#include "vision/motion/gear_speed.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

struct FeedstockOptions {
  int pairs = 50;  // frame pairs spread evenly over the step's part
  // The filament's measurement (target filament; roi, polarity as for any filament).
  vision::StrandMeasureOptions strand;
  // With a gear: its ROI, centre and tip radius; the gear's radius where it grips, in mm.
  std::optional<vision::GearSpeedOptions> gear;
  double gear_radius_mm = 0;
  // The feedstock camera's pixel scale (it may film at another magnification than the strand's);
  // speeds and µm need it.
  std::optional<calib::ScaleCalibration> conversion;
  bool Validate(std::string* why) const;
};

enum class FeedstockStatus {
  kOk,           // as many valid diameters as pairs asked
  kTooFewPairs,  // fewer valid diameters than pairs asked
  kFailed,       // no diameter (an unreadable video, no valid pair, an error)
};
const char* FeedstockStatusName(FeedstockStatus status);  // "ok", "too_few_pairs", "failed"
// The status FeedstockStatusName gives `name`; throws std::invalid_argument ("unknown feedstock
// status 'x'") for any other text.
FeedstockStatus ParseFeedstockStatus(const std::string& name);

struct FeedstockResult {
  FeedstockStatus status = FeedstockStatus::kFailed;  // until measured
  std::string detail;
  std::string video;
  int n_pairs = 0;  // pairs examined
  // Diameter: mean of the valid first frames of the pairs after robust outlier rejection.
  int n_diameter = 0;
  double diameter_px = 0, diameter_std_px = 0;
  bool has_um = false;
  double diameter_um = 0, diameter_ci95_um = 0;  // t·SEM and the calibration's σ in quadrature
  // Speeds (mm/s, need a scale) and slip (%), mean ± 95 % CI half-width over the pairs that have
  // them; empty when none has.
  int n_speed = 0, n_gear = 0, n_slip = 0;
  std::optional<double> speed_mm_s, speed_ci95_mm_s;
  std::optional<double> gear_mm_s, gear_ci95_mm_s;
  std::optional<double> slip_pct, slip_ci95_pct;
};

// Measures `pairs` pairs of consecutive frames of `video` spread over [start_s, end_s) (end_s < 0:
// to the end): the filament's width on the first frame of each (tracked from pair to pair), its
// feed speed and the gear's from each pair, the slip 1 − v_filament / v_gear where the gear turns
// measurably (over 3σ). Speeds need the options' conversion. An unreadable video, or no valid
// pair, gives status kFailed with the reason; throws std::invalid_argument only for options that
// do not validate.
FeedstockResult MeasureFeedstock(const std::string& video, double start_s, double end_s,
                                 const FeedstockOptions& options);

}  // namespace clogscope::pipeline
