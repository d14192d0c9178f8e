#pragma once

// Surface speed of a drive gear from consecutive frames: the region around the gear is unwrapped
// into polar coordinates about its centre (cv::warpPolar), averaged over the outer part of the
// radius into an angular profile (teeth and the marks on its face), and the rotation between two
// frames is the circular shift of that profile (profile_shift.h).
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "vision/motion/feed_speed.h"

namespace clogscope::vision {

struct GearSpeedOptions {
  cv::Rect roi;                          // around the gear, full-frame px
  std::optional<cv::Point2d> centre_px;  // its axis, full-frame px; default the ROI's centre
  int angle_samples = 1440;              // around the full turn (0.25° each)
  // The band's outer radius: the gear's tip radius when known (keeps what stands still beyond the
  // teeth out of it), else the largest circle inside the ROI.
  std::optional<double> outer_radius_px;
  double inner_radius_fraction = 0.5;  // the radial band averaged: from this share of the
                                       // largest circle inside the ROI to its edge
  double max_rotation_deg = 30;        // search range per frame pair
  double min_correlation = 0.6;
  bool Validate(std::string* why) const;
};

// One frame's rotation against the frame before it.
struct GearSpeedSample {
  bool valid = false;
  SpeedReason reason = SpeedReason::kNone;  // first_frame, no_time, bad_time, no_gear, too_fast
  std::string detail;
  double rotation_rad = 0;  // signed: + clockwise in the image (y down)
  double sigma_rad = 0;
  double dt_s = 0;
  double RadPerS() const { return rotation_rad / dt_s; }
  double SigmaRadPerS() const { return sigma_rad / dt_s; }
};

// The gear's surface speed |ω|·R and the slip 1 − v_filament / v_gear (%), each with its σ, from
// one frame pair's two speeds (mm_per_px converts the filament's). The slip only where the gear
// turns measurably (over 3σ) and the filament's speed is valid.
struct GearAndSlip {
  std::optional<double> gear_mm_s, gear_sigma_mm_s, slip_pct, slip_sigma_pct;
};
GearAndSlip GearAndSlipOf(const FeedSpeedSample& filament, const GearSpeedSample& gear,
                          double mm_per_px, double radius_mm);

// The gear's angular profile in one frame (empty when the ROI leaves the frame).
std::vector<double> GearAngularProfile(const cv::Mat& grey, const GearSpeedOptions& options);

class GearSpeedTracker {
 public:
  // Throws std::invalid_argument when the options do not validate.
  explicit GearSpeedTracker(const GearSpeedOptions& options);
  // Frames of any supported type (colour as grey); time_s < 0: none (still images).
  GearSpeedSample Next(const cv::Mat& frame, double time_s);

 private:
  GearSpeedOptions options_;
  std::vector<double> previous_;
  double previous_t_ = -1;
};

}  // namespace clogscope::vision
