#pragma once

// Internal to MeasureCalipers (calipers.h): each caliper's pair of edge fits, and the two parallel
// lines through the calipers' edges.
#include <vector>

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
