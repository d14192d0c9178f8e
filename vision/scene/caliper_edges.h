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

// A flat object's level just inside its two edges (each plain step's model three of its blurs
// inside the edge, the median over the calipers `use`d) is one level. A step of the object's
// level within the blur of one edge (a highlight at the rim) folds into that edge's fitted step
// and moves it by up to its share of the step times its distance, ≲ 2 blurs (further in it shows
// as an edge of its own, caliper_samples.h's InnerEdgeDistance). The width's doubt from the two
// levels' difference over the larger step, beyond kInnerLevelAllowance: that share of 2 blurs.
// 0 with fewer than 3 calipers.
inline constexpr double kInnerLevelAllowance = 0.1;
double InnerLevelDoubtPx(const std::vector<CaliperFit>& fits, const std::vector<bool>& use,
                         double blur_px);

}  // namespace clogscope::vision
