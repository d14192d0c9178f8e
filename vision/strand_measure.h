#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/synthetic.h"

namespace clogscope::vision {

// How the strand is found and measured in one frame. Lengths are in px of the frame.
struct StrandMeasureOptions {
  cv::Rect roi;  // region to search; empty = whole frame
  Polarity polarity = Polarity::kAuto;
  // The measurement band, along the strand axis below the nozzle tip. Defaults are the reference
  // 50 µm and 150 µm at the nominal 3 µm/px.
  double band_start_px = 50.0 / 3.0;
  double band_height_px = 50.0;
  double caliper_spacing_px = 4.0;      // thickness of one caliper along the axis
  double min_contrast_fraction = 0.06;  // edge step below this fraction of full scale: low contrast
  double max_blur_px = 6.0;             // fitted PSF sigma above this: out of focus
  double max_tilt_deg = 45.0;           // strand axes leaning more than this are not strands
  // False for objects across the whole frame (calibration pins): without a nozzle tip the band
  // starts band_start_px below where the object leaves the frame, and runs as far as it can.
  bool require_tip = true;
  double min_caliper_fraction = 0.5;     // fewer consistent calipers than this: occluded
  double max_saturated_fraction = 0.05;  // more clipped pixels at the edges than this: saturated

  bool Validate(std::string* why) const;
};

// Why a frame gives no width. kValid when it does.
enum class FrameStatus {
  kValid,
  kUnreadable,        // the frame could not be decoded
  kNoStrand,          // nothing strand-like in the frame or ROI
  kNoTip,             // a strand but no nozzle tip above it
  kTouchesBorder,     // the strand's edges in the band reach the frame or ROI border
  kBandOutsideFrame,  // the band leaves the frame/ROI or runs into the bed or an obstacle
  kLowContrast,
  kOutOfFocus,
  kSaturated,
  kOccluded,      // too few calipers agree
  kWidthOutlier,  // far from the neighbouring frames' widths (set by FlagWidthOutliers)
};
const char* FrameStatusName(FrameStatus status);

// One caliper: a thin slab across the strand. Positions are across (u) and along (s) the axis.
struct Caliper {
  double s_px = 0;       // slab centre below the tip
  double left_u_px = 0;  // fitted edges
  double right_u_px = 0;
  double width_px = 0;  // perpendicular width (edges corrected for the axis tilt)
  bool fitted = false;  // both edges fitted
  bool inlier = false;  // used in the frame's width
};

// The result for one frame. Geometry is in full-frame pixel coordinates (ROI offset added).
struct StrandMeasurement {
  FrameStatus status = FrameStatus::kNoStrand;
  std::string detail;  // human-readable reason when not valid
  bool valid() const { return status == FrameStatus::kValid; }

  double width_px = 0;
  double width_sigma_px = 0;  // standard error of width_px from the calipers' spread
  double angle_deg = 0;       // strand axis from image vertical, + leaning to +x going down
  double contrast = 0;        // median edge step, grey levels of the frame's bit depth
  double blur_px = 0;         // median PSF sigma, pixel footprint removed
  double tip_x_px = 0;
  double tip_y_px = 0;
  Polarity polarity = Polarity::kAuto;
  int calipers_used = 0;
  int calipers_total = 0;

  // Measurement frame for overlays: origin at the tip, axis direction (down the strand), and the
  // fitted edge lines u = left_u0_px + edge_slope·s (right likewise) in that frame.
  bool has_geometry = false;
  double axis_dx = 0, axis_dy = 1;
  double band_start_px = 0, band_end_px = 0;
  double left_u0_px = 0, right_u0_px = 0, edge_slope = 0;
  std::vector<Caliper> calipers;
};

// Measures the strand width in one frame (8- or 16-bit; grey, BGR or BGRA). Expected failures come
// back as a status with a reason; throws std::invalid_argument for frames of another pixel type or
// options that do not validate.
StrandMeasurement MeasureStrand(const cv::Mat& frame, const StrandMeasureOptions& options);

// Marks valid frames whose width is far from the median of the valid frames within ±half_window
// frames (robust: more than k·1.4826·MAD and more than min_deviation_px away) as kWidthOutlier.
// Returns how many it marked.
int FlagWidthOutliers(std::vector<StrandMeasurement>& frames, int half_window = 25, double k = 6.0,
                      double min_deviation_px = 1.0);

}  // namespace clogscope::vision
