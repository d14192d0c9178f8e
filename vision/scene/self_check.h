#pragma once

#include <string>
#include <vector>

#include "vision/edges/grey_image.h"

namespace clogscope::vision {

// The self-checks after a strand is measured, each failing as `not_silhouette` with its reason: a
// silhouette has the background outside it, at matching levels on both sides, and both its edges
// fit a blurred step about as well. A thin object measured beside the real strand (a hair beside
// it, a pair made of a hair's edge and the strand's), a lamp's reflection behind an edge or an
// inner edge in a window fails one of them.
struct SelfCheck {
  bool passed = true;
  std::string why;  // when not passed
};

// Samples the band s0..s1 outward from each fitted edge (u = left_u0 + slope·s, right likewise,
// in axis frame f) beyond the edge's blur, over 20 px + 3 blurs, each px of distance the median
// over the band's rows: fails when more than 40 % of one side's distances sit nearer the object's
// level than that side's background, or when the two sides' backgrounds differ by more than the
// object's contrast. An object too thin to read its level 3 blurs and 2 px inside its edges is
// read along its middle, where 4 blurs wide or more, and its contrast is against the nearer side.
SelfCheck CheckOutsideIsBackground(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                   double left_u0, double right_u0, double slope, double blur_px);

// Looks outward from each fitted edge, over the band, for another edge just beyond its blur
// (InnerEdgeDistance turned outward: from 3.5 px past the edge's own gradient peak to 2.5 blurs
// and 4 px from the edge): the strand's own outline beyond a stripe measured as the object, or
// another object against it (a shadow, a hair). Fails when either side has one.
SelfCheck CheckNoEdgeJustOutside(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                 double left_u0, double right_u0, double slope, double blur_px,
                                 double min_step);

// Reads the band's inside across u, from 3 blurs and 2 px inside one edge to as far inside the
// other (each px the median over the band's rows, as above), against the background read just
// outside both edges (a straight line between the two: a background's gradient), the object's
// contrast the larger of the two ends' (nothing judged below min_step): fails when a run of it
// at the background's level has the object's body on one side and, on the other, only a thin
// part on the same side of the background that nowhere reaches half the contrast. That is the
// background between two objects, a hair beside the strand paired with it, too thin and blurred
// for the search's coarse scale to see the gap (and thick or sharp enough for its blurred tail to
// reach past 3 blurs and 2 px inside its edge); or when such a run starts at one end of the
// read, over at least a quarter of the width, with the body beyond it: the hair on that side is too
// thin for its tail to reach past the inset at all. With the body on both sides the run may be a
// stripe inside one object, judged here only where it covers over half the width with the body
// on one side under half as wide as on the other.
SelfCheck CheckInsideIsOneObject(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                 double left_u0, double right_u0, double slope, double blur_px,
                                 double min_step);

// Reads each side's outside on past the near background, out to 12 times the width (20 px at
// least; each px the median over the band's rows): fails when both sides step, sharply as an edge,
// to a farther level that holds beyond for the wider object's width, one background's on both
// sides, with the near levels on one side of it, and on one side at least at one distance in both
// halves of the band (parallel to the object). Then the silhouette lies on a wider object: a
// stripe inside the strand measured as the object, the strand's body on both sides of it. Fails
// too when one side steps so and the other side's outside is already at the farther level, the
// bright silhouette's body darker than the background and reaching at least the silhouette's
// width beyond it: the silhouette lies at the side of a wider object (a stripe by a dark strand's
// rim that the blur hides).
// `object_dark`: the silhouette is darker than its outside; one on a bright field ringed by dark
// (a backlight's disc, a microscope's vignette) is not judged.
SelfCheck CheckNotOnAWiderObject(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                 double left_u0, double right_u0, double slope, double blur_px,
                                 double min_step, bool object_dark);
// The calipers' residual RMS of each edge's fit (grey levels): fails when one edge's median is
// more than twice the other's and more than 1.5 grey levels above it (the noise is the frame's on
// both sides).
SelfCheck CheckEdgeResiduals(const std::vector<double>& left_rms,
                             const std::vector<double>& right_rms);

}  // namespace clogscope::vision
