#pragma once

// The pixels a caliper works on: one slab of the strand, across one edge or both.
#include <vector>

#include "vision/edge_fit.h"
#include "vision/grey_image.h"

namespace clogscope::vision {

// The values at which a frame's data is clipped: 0 and the data's full scale, or where a codec
// put them. A clipped plateau passed through a codec keeps a spike in the histogram below full
// scale (H.264 in TV range decodes clipped white at ~252 of 255); such a spike is the clip level.
struct ClipLevels {
  float low = 0, high = 255;
  double clipped_fraction = 0;  // of the slab's pixels at or beyond them
};

// The clip levels of the slab s0 <= s < s1, u0 <= u <= u1: data_max and 0, or a spike in the
// top (bottom) 4 % of the range holding ≥ 2 % of the slab's pixels, ≥ 5× the pixels of the values
// just inside it and ≥ 2× those beyond it.
ClipLevels FindClipLevels(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                          double u1, double data_max);

// Gathers the pixels of the slab s0 <= s < s1, u0 <= u <= u1 (axis frame f) in (u, value) form,
// counting those at or beyond the clip levels in *saturated. Returns false when the slab leaves
// the image.
bool GatherEdgeSamples(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                       double u1, const ClipLevels& clip, std::vector<EdgeSample>* out,
                       int* saturated);

// Sub-pixel start for an edge fit: along the normal at s, from u_guess - half to u_guess + half in
// half-pixel steps, the crossing of the local mid-level (between the profile's extremes) nearest to
// u_guess. Returns u_guess when the profile has no clear step (extremes closer than min_step).
double RefineEdgeGuess(const GreyImage& img, const AxisFrame& f, double s, double u_guess,
                       double half, double min_step);

}  // namespace clogscope::vision
