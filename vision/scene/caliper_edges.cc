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

double InnerLevelDoubtPx(const std::vector<CaliperFit>& fits, const std::vector<bool>& use,
                         double blur_px) {
  std::vector<double> inner[2], step[2];
  for (size_t k = 0; k < fits.size(); ++k) {
    if (!use[k]) continue;
    for (int side = 0; side < 2; ++side) {
      const EdgeFit& fit = side == 0 ? fits[k].left : fits[k].right;
      const double inward = (side == 0 ? 1.0 : -1.0) * 3.0 * fit.sigma_px;
      const double in = EdgeModelValue(fit, fit.edge_px + inward);
      inner[side].push_back(in);
      step[side].push_back(in - EdgeModelValue(fit, fit.edge_px - inward));
    }
  }
  if (inner[0].size() < 3) return 0;
  const double larger = std::max(std::abs(Median(step[0])), std::abs(Median(step[1])));
  if (larger <= 0) return 0;
  const double share = std::abs(Median(inner[0]) - Median(inner[1])) / larger;
  return std::max(0.0, share - kInnerLevelAllowance) * 2.0 * blur_px;
}

}  // namespace clogscope::vision
