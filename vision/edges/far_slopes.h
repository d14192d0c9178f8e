#pragma once

#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/grey_image.h"
#include "vision/edges/residual_structure.h"

namespace clogscope::vision {

// What the slopes read along the band well past a plain step's window say of its edge, where the
// window's own pixels cannot tell a slope from the noise (a textured background under noise), and
// whether its background is one slope (the premise of moving the edge by a two-slope step).
//
// The band's calipers' samples are pooled in 1 px bins of the distance from each caliper's fitted
// edge, from the blurred step's reach (BlurredStepReachPx) out to kFarReaches window reaches on
// each side (the object's no further than object_reach_px: short of an edge inside it, and of its
// middle). Each side's slope is a line through its bins, over the longest of that reach and its
// halves toward the edge that is one slope (its bins' scatter what the noise leaves in them: not
// a hair, a spot's flank or a halo farther out), or over the shortest. The plain step fitted over
// the window [−below_px, above_px] to a step with those two slopes moves by the doubt: less the
// part the slopes' noise explains where both sides were one slope, whole where one was not. An
// object side that cannot be read is flat, the plain step's own premise.
//
// background_side: −1 where the background lies toward −u, +1 toward +u. blur_px: the edge fits'
// blur (EdgeFit::sigma_px); noise_sigma: a sample's noise, grey levels.
struct FarSlopes {
  bool background_read = false;       // no doubt without it
  bool background_one_slope = false;  // out to the whole reach
  double doubt_px = 0;
};
FarSlopes JudgeFarSlopes(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                         const std::vector<CaliperEdge>& edges, double below_px, double above_px,
                         int background_side, double object_reach_px, double blur_px,
                         double noise_sigma);

}  // namespace clogscope::vision
