#pragma once

#include <algorithm>

#include "vision/edges/grey_image.h"

namespace clogscope::vision {

// Where a strand meets the nozzle. The walk that finds a pair's ends follows straight edge lines;
// a strand that swells below the die (a polymer melt leaving a nozzle is 10–50 % wider just below
// it) leaves those lines before the nozzle, and the walk would put the tip where the edges become
// parallel. Following each edge up as a curve finds where the object's outline ends at the nozzle.
struct TipTrace {
  bool found = false;  // both edges followed up to a common end
  // Neither edge ended where it was followed (as far as twice the width, or to the image's
  // side): the outline curves on above the straight edges, a strand bending above them.
  bool runs_on = false;
  double s_tip_px = 0;   // the common end, along the axis (the caller's frame)
  double widest_px = 0;  // the widest separation of the two curves between the tip and s_from
  // On how many sides of the strand the nozzle's face shows (0–2): a strand hangs from the face,
  // with the nozzle on both sides; a hair behind a nozzle's flank ends at it on one side at most.
  int face_sides = 0;
  // Where the face shows on both sides: the largest |step| among its readings, grey levels.
  double face_step = 0;
  // The doubt about s_tip_px where the nozzle's face on both sides or the object's own end (where
  // the nozzle's level differs from the strand's) fixed it; < 0 where only the followed edges or
  // a face on one side did.
  double tip_sigma_px = -1;
};

// How far apart along the axis two ends of one strand's outline may lie and still be one tip:
// a nozzle's face ends both edges together, square to a strand hanging up to ~8° off its axis.
inline double MaxTipMismatchPx(double width_px) { return std::max(4.0, 0.14 * width_px); }

// Follows the edges u = left_u0 + slope·s and right_u0 + slope·s of axis frame `a` upward (−s)
// from s_from, each re-found every px within ±3 px of where its curve is heading, until its
// contrast (sign·step, `ref_*` the edge's usual contrast) stays below half for three px, or the
// level inside it changes; then refines the end on the nozzle's face beside the strand, and on
// the object's own end along its axis, where either steps by at least min_face_step.
TipTrace TraceToNozzle(const GreyImage& img, const AxisFrame& a, double left_u0, double right_u0,
                       double slope, int left_sign, int right_sign, double ref_l, double ref_r,
                       double s_from, double min_face_step);

}  // namespace clogscope::vision
