#pragma once

namespace clogscope::vision {

// One caliper: a thin slab across the strand. Positions are across (u) and along (s) the axis.
struct Caliper {
  double s_px = 0;       // slab centre below the tip
  double left_u_px = 0;  // fitted edges
  double right_u_px = 0;
  double width_px = 0;        // perpendicular width (edges corrected for the axis tilt)
  double width_sigma_px = 0;  // its standard error from the two edge fits' residuals
  bool fitted = false;        // both edges fitted
  bool inlier = false;        // used in the frame's width
};

}  // namespace clogscope::vision
