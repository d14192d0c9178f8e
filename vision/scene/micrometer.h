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

// One mark across the scale: a line (a tick of any length) or something line-like (a numeral's
// stroke, dust). Its centre across the lines, measured from the image's centre point along the
// lines' normal, with the fit's standard error, and how long it is along the lines.
struct MicrometerLine {
  double position_px = 0;
  double sigma_px = 0;
  double depth = 0;  // grey levels
  double length_px = 0;
  int samples = 0;
};

struct MicrometerLines {
  bool ok = false;
  std::string reason;                 // when not ok
  double angle_deg = 0;               // the lines' direction from image vertical
  double spacing_px = 0;              // median distance between neighbouring line centres
  std::vector<MicrometerLine> lines;  // every mark found, sorted by position
};

// Finds the marks of a stage micrometer image (dark lines on a bright field or the reverse) to
// sub-pixel precision: line centres in every horizontal strip, followed from strip to strip into
// marks (a tick of any length, a numeral's stroke, dust); the tilt from the marks' slopes; then
// each mark's centre from fits of its profile to the pixels near it, strip by strip over its own
// rows only, at the exact distance across the lines, leaving out strips whose centre disagrees
// (dust on the line). Which marks are the lattice's lines is for calib::IndexLinesOnLattice.
// Strips cut by the image or ROI border are left out. Throws std::invalid_argument for an
// unsupported pixel type.
MicrometerLines FindMicrometerLines(const cv::Mat& image, const MicrometerOptions& options);

}  // namespace clogscope::vision
