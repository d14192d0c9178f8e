#pragma once

#include <cmath>
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/edge_fit.h"
#include "vision/edges/grey_image.h"

namespace clogscope::vision {

// The part of an edge model's residuals that the calipers along a band share. Each caliper's
// residuals are noise plus whatever the model does not describe; noise differs from caliper to
// caliper, but a textured background, a smeared nozzle or a stripe near the silhouette repeats
// along the band at the same distance from the edge. Residuals are pooled in 1 px bins of that
// distance: the bins' means keep the shared structure and lose the noise (minus what the noise
// leaves in a mean of n samples, σ²/n).
class ResidualStructure {
 public:
  // Distances from the edge within ±half_width_px are kept.
  explicit ResidualStructure(double half_width_px);
  void Add(double u_from_edge_px, double residual);
  int samples() const { return samples_; }
  // RMS of all residuals added.
  double ResidualRms() const;
  // RMS of the structure shared by the samples (bin means above the noise's share); 0 when
  // nothing is shared or fewer than 3 samples fell in every occupied bin on average.
  double SharedRms() const;

 private:
  double half_width_px_;
  std::vector<double> sum_, count_;
  double sum_sq_ = 0;
  int samples_ = 0;
};

// How far a shared residual structure of RMS `shared_rms` may have moved an edge whose fit gave
// edge_sigma_px from residuals of RMS `rms` over `samples` samples spread across `window_px` px:
// the structure counts as noise that every row of the band repeats, so it averages over the
// window's px, not over its samples.
double SharedStructureEdgeDoubtPx(double shared_rms, double rms, double edge_sigma_px, int samples,
                                  double window_px);

// One edge's shared-structure doubt over a band's calipers: each caliper's residuals placed about
// its own fitted edge (structure()), and what one grey level of shared RMS would move that edge
// (AddCaliper, SharedStructureEdgeDoubtPx); DoubtPx is their median times the shared RMS, 0 with
// fewer than two calipers.
class EdgeStructureDoubt {
 public:
  explicit EdgeStructureDoubt(double half_width_px) : structure_(half_width_px) {}
  ResidualStructure& structure() { return structure_; }
  void AddCaliper(double rms, double edge_sigma_px, int samples, double window_px) {
    per_unit_.push_back(SharedStructureEdgeDoubtPx(1.0, rms, edge_sigma_px, samples, window_px));
  }
  int calipers() const { return static_cast<int>(per_unit_.size()); }
  double DoubtPx() const;

 private:
  ResidualStructure structure_;
  std::vector<double> per_unit_;
};

// One caliper's fitted edge: the slab s0..s1 along the axis and its edge model.
struct CaliperEdge {
  double s0_px = 0, s1_px = 0;
  EdgeFit fit;  // FitBlurredStep or FitShadedStep
};

// One edge of a band judged on its pooled profile (each caliper's samples placed about its own
// fitted edge, below_px before it and above_px after it along u), which shows what one caliper's
// cannot:
// - the structure the calipers share in their residuals;
// - when every caliper took the plain step, whether the edge's two sides slope differently
//   (FitTwoSlopeStep: a textured or graded background stopping at a flat object), which pulls a
//   plain step's edge. Where the pooled profile's gain from that slope is beyond its noise
//   (kTwoSlopeEvidence) and the background is one slope (the move stays the same with the window
//   reaching further into the background, on background_side: −1 toward −u, +1 toward +u), the
//   edge is moved by what the two-slope step says (shift_px, along u) and only that move's own σ
//   is left as doubt; where it is not one slope, the whole move is doubt; below the evidence, the
//   part of the move the noise cannot explain. And where the edge was not moved, the doubt from
//   the slopes read along the band well past the window (JudgeFarSlopes, far_slopes.h; the
//   object's no further than object_reach_px), if larger.
struct BandEdgeDoubt {
  double structure_px = 0;  // the shared residual structure's σ
  double two_slope_px = 0;  // the two-slope step's move (or its σ where the edge was moved)
  double shift_px = 0;      // where the edge lies from the calipers' mean, along u
  double doubt_px() const { return std::hypot(structure_px, two_slope_px); }  // the two as one σ
};
// Gain (χ² with one degree of freedom without a slope change) from which the two-slope step is
// taken: 5σ.
inline constexpr double kTwoSlopeEvidence = 25.0;
// Zero with fewer than two calipers.
BandEdgeDoubt JudgeBandEdge(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                            const std::vector<CaliperEdge>& edges, double below_px, double above_px,
                            int background_side, double object_reach_px);

}  // namespace clogscope::vision
