#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace clogscope::vision {

struct MicrometerOptions {
  cv::Rect roi;                         // empty = whole image
  double max_tilt_deg = 15.0;           // lines may lean this much from image vertical
  double min_contrast_fraction = 0.04;  // line depth below this fraction of full scale: not a line
  bool Validate(std::string* why) const;
};

// One line of the scale: its centre across the lines, measured from the image's centre point along
// the lines' normal, with the fit's standard error.
struct MicrometerLine {
  double position_px = 0;
  double sigma_px = 0;
  double depth = 0;  // grey levels
  int samples = 0;
};

struct MicrometerLines {
  bool ok = false;
  std::string reason;                 // when not ok
  double angle_deg = 0;               // the lines' direction from image vertical
  double spacing_px = 0;              // median distance between neighbouring lines
  std::vector<MicrometerLine> lines;  // sorted by position
};

// Finds the lines of a stage micrometer image (dark lines on a bright field or the reverse) to
// sub-pixel precision: the lines' tilt from line centres tracked across horizontal strips, then
// each line's centre from a fit of its profile to every pixel near it, at the exact distance across
// the lines. Lines cut by the image or ROI border are left out. Throws std::invalid_argument for an
// unsupported pixel type.
MicrometerLines FindMicrometerLines(const cv::Mat& image, const MicrometerOptions& options);

}  // namespace clogscope::vision
