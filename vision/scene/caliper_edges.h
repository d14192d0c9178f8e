#pragma once

// Internal to MeasureCalipers (calipers.h): each caliper's pair of edge fits, and the two parallel
// lines through the calipers' edges.
#include <vector>

#include "vision/edges/edge_fit.h"

namespace clogscope::vision {

// One caliper's fits of its two edges.
struct CaliperFit {
  EdgeFit left, right;
  EdgeFit left_shaded, right_shaded;  // while the model is undecided
  double width_sigma_px = -1;         // set by a joint fit of both edges (their errors correlate)
  bool inside_roi = true;
  int saturated = 0;
  int samples = 0;
};

// The two edges as lines u = u0 + slope·s with a shared slope (parallel edges), least squares over
// the calipers whose width agrees with the median (an occluded or damaged caliper must not tilt the
// lines: the width's tilt correction depends on the slope).
struct EdgeLines {
  double left_u0 = 0, right_u0 = 0, slope = 0;
  int calipers = 0;
};

EdgeLines FitEdgeLines(const std::vector<CaliperFit>& fits, double band_s0, double spacing);

}  // namespace clogscope::vision
