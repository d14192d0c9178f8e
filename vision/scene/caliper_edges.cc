#include "vision/scene/caliper_edges.h"

#include <algorithm>
#include <cmath>

#include "common/robust.h"

namespace clogscope::vision {

EdgeLines FitEdgeLines(const std::vector<CaliperFit>& fits, double band_s0, double spacing) {
  std::vector<double> widths;
  for (const auto& cf : fits) {
    if (cf.left.converged && cf.right.converged)
      widths.push_back(cf.right.edge_px - cf.left.edge_px);
  }
  EdgeLines out;
  if (widths.size() < 2) return out;
  const double med = Median(widths);
  const double tol = std::max(4.0 * kMadToSigma * Mad(widths, med), 0.1);
  double n = 0, ss = 0, sss = 0, sl = 0, sr = 0, sls = 0, srs = 0;
  for (size_t k = 0; k < fits.size(); ++k) {
    const CaliperFit& cf = fits[k];
    if (!cf.left.converged || !cf.right.converged) continue;
    if (std::abs(cf.right.edge_px - cf.left.edge_px - med) > tol) continue;
    const double s = band_s0 + (k + 0.5) * spacing;
    n += 1;
    ss += s;
    sss += s * s;
    sl += cf.left.edge_px;
    sr += cf.right.edge_px;
    sls += cf.left.edge_px * s;
    srs += cf.right.edge_px * s;
  }
  if (n < 2) return out;
  const double var_s = sss - ss * ss / n;
  out.slope = var_s > 1e-9 ? ((sls - sl * ss / n) + (srs - sr * ss / n)) / (2 * var_s) : 0.0;
  out.left_u0 = (sl - out.slope * ss) / n;
  out.right_u0 = (sr - out.slope * ss) / n;
  out.calipers = static_cast<int>(n);
  return out;
}

double OneEdgeDriftDoubtPx(const std::vector<Caliper>& calipers, int begin, int end,
                           double width_slope_px_per_px, double band_length_px) {
  if (width_slope_px_per_px == 0) return 0.0;
  // The inlier calipers' middles against s: their line's slope and its σ from their scatter.
  double n = 0, ss = 0, sss = 0, sm = 0, sms = 0, smm = 0;
  for (int k = begin; k < end; ++k) {
    const Caliper& c = calipers[k];
    if (!c.inlier) continue;
    const double mid = 0.5 * (c.left_u_px + c.right_u_px);
    n += 1;
    ss += c.s_px;
    sss += c.s_px * c.s_px;
    sm += mid;
    sms += mid * c.s_px;
    smm += mid * mid;
  }
  if (n < 4) return 0.0;
  const double var_s = sss - ss * ss / n;
  if (!(var_s > 1e-9)) return 0.0;
  const double turn = (sms - sm * ss / n) / var_s;  // px across per px along
  const double residual = std::max(0.0, (smm - sm * sm / n) - turn * turn * var_s);
  // The turn is taken against the strand's axis from the pair found in the frame, whose own angle
  // is uncertain too: its σ adds to the middles' scatter.
  const double turn_sigma =
      std::hypot(std::sqrt(residual / (n - 2) / var_s), kPairAxisAngleSigmaRad);
  if (std::abs(turn) <= 3.0 * turn_sigma) return 0.0;
  // One edge alone moves the middle by half the width's change: the width's slope and twice the
  // turn agree. A swell (the turn ≪) or a turning strand whose width barely changes (a bend
  // below the band, the width's slope ≪) is another thing that fits only as far as the smaller
  // of the two goes, and only by their ratio.
  const double a = std::abs(width_slope_px_per_px), b = 2.0 * std::abs(turn);
  const double alone = std::min(a, b) * std::min(a, b) / std::max(a, b);
  return 0.5 * alone * band_length_px;
}

double InnerLevelDoubtPx(const GreyImage& img, const AxisFrame& f, double band_s0, double spacing,
                         const std::vector<CaliperFit>& fits, const std::vector<bool>& use,
                         double blur_px) {
  constexpr double kLevelBlurs = 3.0;       // where each edge's inner level is read
  constexpr double kHiddenStepBlurs = 2.0;  // how far inside a step may hide in an edge's blur
  constexpr double kAllowance = 0.1;        // of the larger step
  constexpr double kHalves[2][2] = {{0.2, 0.4}, {0.6, 0.8}};  // the middle's halves, of the width
  constexpr int kRows = 4, kPerHalf = 5;  // samples of each half in each caliper
  std::vector<double> inner[2], step[2], middle[2], at[2];
  for (size_t k = 0; k < fits.size(); ++k) {
    if (!use[k]) continue;
    const EdgeFit& l = fits[k].left;
    const EdgeFit& r = fits[k].right;
    const double width = r.edge_px - l.edge_px;
    if (width <= 0) continue;
    for (int side = 0; side < 2; ++side) {
      const EdgeFit& fit = side == 0 ? l : r;
      const double inward = (side == 0 ? 1.0 : -1.0) * kLevelBlurs * fit.sigma_px;
      const double in = EdgeModelValue(fit, fit.edge_px + inward);
      inner[side].push_back(in);
      step[side].push_back(in - EdgeModelValue(fit, fit.edge_px - inward));
      at[side].push_back((side == 0 ? inward : width + inward) / width);
    }
    for (int half = 0; half < 2; ++half) {
      for (int r_i = 0; r_i < kRows; ++r_i) {
        const double s = band_s0 + (k + (r_i + 0.5) / kRows) * spacing;
        for (int q = 0; q < kPerHalf; ++q) {
          const double frac =
              kHalves[half][0] + (kHalves[half][1] - kHalves[half][0]) * (q + 0.5) / kPerHalf;
          const double u = l.edge_px + frac * width;
          const double x = f.ImageX(s, u), y = f.ImageY(s, u);
          if (img.InsideForBilinear(x, y)) middle[half].push_back(img.Bilinear(x, y));
        }
      }
    }
  }
  if (inner[0].size() < 3 || middle[0].empty() || middle[1].empty()) return 0;
  const double larger = std::max(std::abs(Median(step[0])), std::abs(Median(step[1])));
  if (larger <= 0) return 0;
  // The light's slope across the object, per width, from the middle's halves (their centres 0.4
  // apart), carried to the places the levels are read. A stripe in the middle makes a slope of
  // its own: the disagreement is the smaller of the two, with the slope and without.
  const double centre[2] = {0.5 * (kHalves[0][0] + kHalves[0][1]),
                            0.5 * (kHalves[1][0] + kHalves[1][1])};
  const double trend = (Median(middle[1]) - Median(middle[0])) / (centre[1] - centre[0]);
  const double expected = trend * (Median(at[1]) - Median(at[0]));
  const double apart = Median(inner[1]) - Median(inner[0]);
  const double share = std::min(std::abs(apart), std::abs(apart - expected)) / larger;
  return std::max(0.0, share - kAllowance) * kHiddenStepBlurs * blur_px;
}

EdgeBlur MedianBlur(const std::vector<double>& caliper_blurs_px) {
  EdgeBlur b;
  if (caliper_blurs_px.empty()) return b;
  b.median_px = Median(caliper_blurs_px);
  b.sigma_px = MedianStandardError(caliper_blurs_px, b.median_px);
  return b;
}

double BlurMismatchDoubtPx(const EdgeBlur& left, const EdgeBlur& right, EdgeModels models) {
  // Correct frames of three matrices: the blurrier plain edge at most 1.3 times the sharper, bar
  // a few with texture in the window; a shaded side beside a plain one up to 1.45 (the two models
  // take up a lit rim's curvature differently). A stripe 4 px inside a shaded edge made it 1.7
  // times as blurred and moved it 1.4 px; one 3.6 px inside the rim of a strand shaded alike on
  // both sides (seed 2715) 1.18 times, and moved it 0.75 px: one model on both sides is held to
  // less. Each median is taken one σ toward the other: at two, a stripe by the rim of a noisy
  // strand went unseen in half its frames; with none, noisy strands with nothing by their rims
  // were doubted by 1-2 px.
  constexpr double kBlurAllowance = 0.3, kShadedBlurAllowance = 0.5, kBothShadedAllowance = 0.15;
  constexpr double kBlurNoiseSigmas = 1.0;
  // Below this a PSF's fitted sigma is poorly determined beside the pixel's footprint: no ratio
  // of it means anything.
  constexpr double kMinBlurPx = 0.5;
  if (left.median_px <= 0 || right.median_px <= 0) return 0;
  const EdgeBlur& sharp = left.median_px < right.median_px ? left : right;
  const EdgeBlur& blurred = left.median_px < right.median_px ? right : left;
  const double sharp_px = std::max(kMinBlurPx, sharp.median_px + kBlurNoiseSigmas * sharp.sigma_px);
  const double blurred_px = blurred.median_px - kBlurNoiseSigmas * blurred.sigma_px;
  const double allowance = models == EdgeModels::kBothShaded  ? kBothShadedAllowance
                           : models == EdgeModels::kOneShaded ? kShadedBlurAllowance
                                                              : kBlurAllowance;
  const double allowed_px = (1 + allowance) * sharp_px;
  if (blurred_px <= allowed_px) return 0;
  return std::sqrt(blurred_px * blurred_px - allowed_px * allowed_px);
}

}  // namespace clogscope::vision
