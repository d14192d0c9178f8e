#pragma once

// The pixels a caliper works on: one slab of the strand, across one edge or both.
#include <vector>

#include "vision/edge_fit.h"
#include "vision/grey_image.h"

namespace clogscope::vision {

// Gathers the pixels of the slab s0 <= s < s1, u0 <= u <= u1 (axis frame f) in (u, value) form,
// counting those at 0 or data_max in *saturated. Returns false when the slab leaves the image.
bool GatherEdgeSamples(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                       double u1, double data_max, std::vector<EdgeSample>* out, int* saturated);

// Sub-pixel start for an edge fit: along the normal at s, from u_guess - half to u_guess + half in
// half-pixel steps, the crossing of the local mid-level (between the profile's extremes) nearest to
// u_guess. Returns u_guess when the profile has no clear step (extremes closer than min_step).
double RefineEdgeGuess(const GreyImage& img, const AxisFrame& f, double s, double u_guess,
                       double half, double min_step);

}  // namespace clogscope::vision
