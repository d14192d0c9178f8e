#include "vision/edges/far_slopes.h"

#include <algorithm>
#include <cmath>

#include "common/robust.h"

namespace clogscope::vision {
namespace {

// Window reaches the slopes are read over, on each side.
constexpr double kFarReaches = 3.0;
// A bin beyond this many robust σ of a line's residuals is not the slope (a hair's trough); bins
// scattered about the line beyond this many σ of their χ² are not one slope.
constexpr double kOutlierSigmas = 3.0, kOneSlopeSigmas = 3.0;
// Bins (1 px each) a slope needs.
constexpr int kMinSlopeBins = 4;
// The least noise a sample has: its level's rounding, 1/√12.
constexpr double kRoundingSigma = 0.28867513459481287;

// A side's slope as read: per px along the distance from the edge, its σ, and whether its bins
// were one slope.
struct SideSlope {
  bool read = false;
  double slope_per_px = 0, slope_sigma_per_px = 0;
  bool straight = false;
  bool whole = false;  // over the whole reach asked for
};

// The band's samples in 1 px bins of the distance d from each caliper's own edge toward `dir`
// (d = dir·(u − edge)), from gap_px to reach_px; clipped samples left out.
class FarBins {
 public:
  FarBins(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
          const std::vector<CaliperEdge>& edges, double gap_px, double reach_px, int dir)
      : gap_px_(gap_px),
        sum_(std::max(0, static_cast<int>(std::floor(reach_px - gap_px))), 0.0),
        count_(sum_.size(), 0.0) {
    if (sum_.empty()) return;
    const double far_px = gap_px + static_cast<double>(sum_.size());
    std::vector<EdgeSample> samples;
    for (const CaliperEdge& c : edges) {
      const double e = c.fit.edge_px;
      const double u0 = dir < 0 ? e - far_px : e + gap_px, u1 = dir < 0 ? e - gap_px : e + far_px;
      if (!GatherEdgeSamples(img, f, c.s0_px, c.s1_px, u0, u1, clip, &samples)) continue;
      for (const EdgeSample& smp : samples) {
        if (Clipped(smp.value, clip)) continue;
        // (Gathered from gap_px out: truncation is the floor, but for a sample a rounding short.)
        const double d = dir * (smp.u_px - e) - gap_px;
        const long b = static_cast<long>(d);
        if (d < 0 || b >= static_cast<long>(sum_.size())) continue;
        sum_[b] += smp.value;
        count_[b] += 1;
      }
    }
  }

  // A line through the bins out to far_px: least squares, then again without the bins beyond
  // kOutlierSigmas of its residuals' robust σ. Its slope's σ is the larger of what the bins'
  // scatter about it and what the noise alone would give.
  SideSlope Line(double far_px, double noise_sigma) const {
    SideSlope out;
    const int bins =
        std::min(static_cast<int>(sum_.size()), static_cast<int>(std::floor(far_px - gap_px_)));
    std::vector<bool> keep(std::max(bins, 0));
    for (int b = 0; b < bins; ++b) keep[b] = count_[b] > 0;
    double b0 = 0, b1 = 0, n = 0, den = 0, mean_x = 0;
    std::vector<double> residual(keep.size(), 0.0);
    for (int pass = 0; pass < 2; ++pass) {
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      n = 0;
      for (int b = 0; b < bins; ++b) {
        if (!keep[b]) continue;
        const double x = X(b), y = sum_[b] / count_[b];
        n += 1, sx += x, sy += y, sxx += x * x, sxy += x * y;
      }
      den = n * sxx - sx * sx;
      if (n < kMinSlopeBins || !(den > 0)) return out;
      b1 = (n * sxy - sx * sy) / den;
      b0 = (sy - b1 * sx) / n;
      mean_x = sx / n;
      std::vector<double> abs_residuals;
      for (int b = 0; b < bins; ++b) {
        if (!keep[b]) continue;
        residual[b] = sum_[b] / count_[b] - b0 - b1 * X(b);
        abs_residuals.push_back(std::abs(residual[b]));
      }
      if (pass == 1) break;
      const double robust_sigma = kMadToSigma * Median(abs_residuals);
      for (int b = 0; b < bins && robust_sigma > 0; ++b)
        if (keep[b] && std::abs(residual[b]) > kOutlierSigmas * robust_sigma) keep[b] = false;
    }
    // The residuals against what the noise leaves in each bin's mean.
    double ss = 0, chi2 = 0, weighted_sxx = 0;
    for (int b = 0; b < bins; ++b) {
      if (!keep[b]) continue;
      ss += residual[b] * residual[b];
      chi2 += residual[b] * residual[b] * count_[b];
      weighted_sxx += count_[b] * (X(b) - mean_x) * (X(b) - mean_x);
    }
    const double dof = n - 2, noise_var = noise_sigma * noise_sigma;
    out.read = true;
    out.straight = chi2 / noise_var / dof <= 1.0 + kOneSlopeSigmas * std::sqrt(2.0 / dof);
    out.slope_per_px = b1;
    out.slope_sigma_per_px = std::max(std::sqrt(ss / dof * n / den),
                                      std::sqrt(noise_var / std::max(weighted_sxx, 1e-12)));
    return out;
  }

 private:
  double X(int b) const { return gap_px_ + b + 0.5; }
  double gap_px_;
  std::vector<double> sum_, count_;
};

// Over the longest of reach_px and its halves toward the edge that is one slope, or the
// shortest that could be read.
SideSlope NearestOneSlope(const FarBins& bins, double gap_px, double reach_px, double noise_sigma) {
  SideSlope out;
  for (double far_px = reach_px; far_px - gap_px >= kMinSlopeBins;
       far_px = 0.5 * (gap_px + far_px)) {
    SideSlope line = bins.Line(far_px, noise_sigma);
    line.whole = far_px == reach_px;
    if (line.read) out = line;
    if (line.read && line.straight) break;
  }
  return out;
}

}  // namespace

FarSlopes JudgeFarSlopes(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                         const std::vector<CaliperEdge>& edges, double below_px, double above_px,
                         int background_side, double object_reach_px, double blur_px,
                         double noise_sigma) {
  FarSlopes out;
  if (edges.empty()) return out;
  noise_sigma = std::max(noise_sigma, kRoundingSigma);
  const double gap_px = BlurredStepReachPx(blur_px);
  const double background_window_px = background_side < 0 ? below_px : above_px;
  const double object_window_px = background_side < 0 ? above_px : below_px;
  const double background_reach_px = kFarReaches * background_window_px;
  const double object_reach_limit_px = std::min(object_reach_px, kFarReaches * object_window_px);
  const FarBins background_bins(img, f, clip, edges, gap_px, background_reach_px, background_side);
  const SideSlope background =
      NearestOneSlope(background_bins, gap_px, background_reach_px, noise_sigma);
  if (!background.read) return out;
  out.background_read = true;
  out.background_one_slope = background.straight && background.whole;
  const FarBins object_bins(img, f, clip, edges, gap_px, object_reach_limit_px, -background_side);
  SideSlope object = NearestOneSlope(object_bins, gap_px, object_reach_limit_px, noise_sigma);
  if (!object.read) object.straight = true;  // flat, the plain step's premise
  // Per px of the distance away from the edge on each side, as slopes along u.
  const double background_per_px = background_side * background.slope_per_px;
  const double object_per_px = -background_side * object.slope_per_px;
  const double change_per_px =
      background_side < 0 ? object_per_px - background_per_px : background_per_px - object_per_px;
  std::vector<double> steps;
  for (const CaliperEdge& c : edges) steps.push_back(c.fit.step);
  // The move is linear in the slopes' difference, and so is its σ.
  const double move_per_change =
      PlainStepMovePerSlopeChange(Median(steps), blur_px, below_px, above_px);
  const double move_px = move_per_change * change_per_px;
  if (!(background.straight && object.straight)) {
    out.doubt_px = std::abs(move_px);
    return out;
  }
  const double move_sigma_px = std::abs(move_per_change) *
                               std::hypot(background.slope_sigma_per_px, object.slope_sigma_per_px);
  out.doubt_px = std::sqrt(std::max(0.0, move_px * move_px - move_sigma_px * move_sigma_px));
  return out;
}

}  // namespace clogscope::vision
