#pragma once

// Internal to MeasureCalipers (calipers.h): each caliper's pair of edge fits, and the two parallel
// lines through the calipers' edges.
#include <vector>

#include "vision/edges/caliper.h"
#include "vision/edges/edge_fit.h"
#include "vision/edges/grey_image.h"

namespace clogscope::vision {

// One caliper's fits of its two edges.
struct CaliperFit {
  EdgeFit left, right;
  EdgeFit left_shaded, right_shaded;  // while the model is undecided
  double width_sigma_px = -1;         // set by a joint fit of both edges (their errors correlate)
  // A lit cylinder's dark strip by its far rim (cylinder_fit.h).
  double terminator_px = 0;
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

// How far the axis of the pair found in a frame may turn from a straight strand's band, rad (σ).
// Measured on the straight strands of four adversarial sets (plain, stripe, lens, saturated,
// blur gradient, motion; 1862 frames): beyond the band middles' own scatter the turn is 0.001
// rad by maximum likelihood, but its tails reach 0.013 (the 99th percentile where the width
// changed) and 0.022. At 0.005 rad (0.3°, as far as H.264 tilts a 50 px band's edge lines in
// testdata's jitter_sway.mp4) none of them is beyond 3σ.
inline constexpr double kPairAxisAngleSigmaRad = 0.005;

// A width changing along the band (width_slope_px_per_px, already judged real) is a swell when
// the edges move apart alike, the strand's axis staying put; when the band's middle also turns
// off the strand's axis (the frame's u = 0, from the whole strand) by more than 3σ (the inlier
// calipers' middles' scatter and kPairAxisAngleSigmaRad), one edge may be drifting alone: a lamp's
// spot or a texture lifting one side's background toward the rim's level, a lit strand's edge
// sliding in. The slope one edge alone would make is the smaller of the width's slope and twice
// the middle's turn, counted by how far the two agree (min²/max); over the band's length, half of
// it is one σ of the band's mean width. 0 without such a turn.
double OneEdgeDriftDoubtPx(const std::vector<Caliper>& calipers, int begin, int end,
                           double width_slope_px_per_px, double band_length_px);

// A flat object's level just inside its two edges (each plain step's model kLevelBlurs of its
// blurs inside the edge, the median over the calipers `use`d; caliper k spans s from band_s0 +
// k·spacing in axis frame f) is one level, but for the light's slope across the object: the trend
// between the medians of its middle's two halves (0.2–0.4 and 0.6–0.8 of the width) carried out
// to where the levels are read (taken only where it lessens their disagreement: a stripe in the
// middle has a trend of its own). A step of the object's level within the blur of one edge (a
// highlight at the rim) folds into that edge's fitted step and moves it by up to its share of the
// step times its distance, up to kHiddenStepBlurs blurs (further in it shows as an edge of its
// own: InnerEdgeDistance). The width's doubt, px: the levels' disagreement beyond the trend, over
// the larger step, less an allowance (the correct frames of two matrices came to 0.09 at most),
// times that distance. 0 with fewer than 3 calipers.
double InnerLevelDoubtPx(const GreyImage& img, const AxisFrame& f, double band_s0, double spacing,
                         const std::vector<CaliperFit>& fits, const std::vector<bool>& use,
                         double blur_px);

// An edge's blur over the calipers: the median of their fitted PSF sigmas and its standard error,
// px (0, 0 when none).
struct EdgeBlur {
  double median_px = 0;
  double sigma_px = 0;
};
EdgeBlur MedianBlur(const std::vector<double>& caliper_blurs_px);

// How a strand's two edges were fitted (BlurMismatchDoubtPx).
enum class EdgeModels {
  kBothPlain,
  kOneShaded,   // the other plain: the shaded step's blur also takes up the rim's curvature
  kBothShaded,  // one model on both sides
};

// The two edges of one strand lie at one depth and are blurred alike: where one edge's blur
// exceeds the other's, a step within its blur (a highlight or a stripe at the rim) has folded into
// it, moving it by up to the excess blur (in quadrature). The width's doubt, px: that excess
// beyond what the two medians' noise explains (each taken kBlurNoiseSigmas of its σ toward the
// other) and an allowance of the sharper edge's blur, by how alike the two edges' models are
// (caliper_edges.cc). 0 when either blur is unknown.
double BlurMismatchDoubtPx(const EdgeBlur& left, const EdgeBlur& right, EdgeModels models);

}  // namespace clogscope::vision
