#pragma once

#include <string>

#include "vision/grey_image.h"

namespace clogscope::vision {

// The self-check after a strand is measured: a silhouette has the background outside it, at
// matching levels on both sides. A thin object measured beside the real strand (a hair beside it,
// a pair made of a hair's edge and the strand's) has the strand, or another object like it, just
// outside one edge.
struct OutsideCheck {
  bool passed = true;
  std::string why;  // when not passed
};

// Samples the band s0..s1 outward from each fitted edge (u = left_u0 + slope·s, right likewise,
// in axis frame f) beyond the edge's blur, over 20 px + 3 blurs, each px of distance the median
// over the band's rows: fails when more than 40 % of one side's distances sit nearer the object's
// level than that side's background, or when the two sides' backgrounds differ by more than the
// object's contrast.
OutsideCheck CheckOutsideIsBackground(const GreyImage& img, const AxisFrame& f, double s0,
                                      double s1, double left_u0, double right_u0, double slope,
                                      double blur_px);

}  // namespace clogscope::vision
