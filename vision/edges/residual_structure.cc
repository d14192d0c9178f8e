#include "vision/edges/residual_structure.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/robust.h"

namespace clogscope::vision {

ResidualStructure::ResidualStructure(double half_width_px)
    : half_width_px_(half_width_px),
      sum_(2 * static_cast<size_t>(std::ceil(half_width_px)) + 1, 0.0),
      count_(sum_.size(), 0.0) {
  assert(half_width_px > 0);
}

void ResidualStructure::Add(double u_from_edge_px, double residual) {
  if (!(std::abs(u_from_edge_px) <= half_width_px_) || !std::isfinite(residual)) return;
  const size_t bin = static_cast<size_t>(std::lround(u_from_edge_px + std::ceil(half_width_px_)));
  sum_[bin] += residual;
  count_[bin] += 1;
  sum_sq_ += residual * residual;
  ++samples_;
}

double ResidualStructure::ResidualRms() const {
  return samples_ > 0 ? std::sqrt(sum_sq_ / samples_) : 0.0;
}

double ResidualStructure::SharedRms() const {
  int bins = 0;
  double between = 0;  // Σ n_j·mean_j²
  for (size_t j = 0; j < sum_.size(); ++j) {
    if (count_[j] == 0) continue;
    ++bins;
    between += sum_[j] * sum_[j] / count_[j];
  }
  if (bins == 0 || samples_ < 3 * bins) return 0.0;
  // Pure noise of variance σ² leaves E[Σ n_j·mean_j²] = bins·σ², with σ² from what the bins'
  // means do not explain.
  const double within = (sum_sq_ - between) / (samples_ - bins);
  const double shared_sq = (between - bins * within) / samples_;
  return shared_sq > 0 ? std::sqrt(shared_sq) : 0.0;
}

double SharedStructureEdgeDoubtPx(double shared_rms, double rms, double edge_sigma_px, int samples,
                                  double window_px) {
  if (!(rms > 0) || samples <= 0 || !(window_px > 0)) return 0.0;
  // edge_sigma_px·√(samples / window_px) / rms: the edge's σ per unit of noise for one sample per
  // px of the window.
  const double per_unit = edge_sigma_px / rms * std::sqrt(samples / std::max(1.0, window_px));
  return per_unit * shared_rms;
}

double EdgeStructureDoubt::DoubtPx() const {
  return per_unit_.size() < 2 ? 0.0 : Median(per_unit_) * structure_.SharedRms();
}

double BandEdgeDoubtPx(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                       const std::vector<CaliperEdge>& edges, double below_px, double above_px) {
  EdgeStructureDoubt doubt(std::max(below_px, above_px));
  // The pooled profile in 0.1 px bins, far finer than any blur: the fits then cost what two
  // calipers' do, not what the whole band's samples would.
  constexpr double kBinPx = 0.1;
  const int bins = static_cast<int>(std::ceil((below_px + above_px) / kBinPx)) + 1;
  std::vector<double> sum(bins, 0.0), sum2(bins, 0.0), count(bins, 0.0);
  std::vector<EdgeSample> samples;
  std::vector<double> blur;
  bool plain = true;
  for (const CaliperEdge& c : edges) {
    const EdgeFit& e = c.fit;
    const double u0 = e.edge_px - below_px, u1 = e.edge_px + above_px;
    if (!GatherEdgeSamples(img, f, c.s0_px, c.s1_px, u0, u1, clip, &samples)) continue;
    for (const EdgeSample& smp : samples) {
      const double u = smp.u_px - e.edge_px;
      doubt.structure().Add(u, smp.value - EdgeModelValue(e, smp.u_px));
      // The same float distance the pooled samples were binned by.
      const int b = static_cast<int>(std::lround((static_cast<float>(u) + below_px) / kBinPx));
      if (b < 0 || b >= bins) continue;
      sum[b] += smp.value;
      sum2[b] += static_cast<double>(smp.value) * smp.value;
      count[b] += 1;
    }
    doubt.AddCaliper(e.rms, e.edge_sigma_px, e.samples, u1 - u0);
    blur.push_back(e.sigma_px);
    plain = plain && e.object_side == 0;
  }
  if (doubt.calipers() < 2) return 0.0;
  const double shared_px = doubt.DoubtPx();
  double slopes_px = 0;
  if (plain) {
    // Both models on the pooled profile, where the noise has averaged down: their difference is
    // the model's, not the noise's.
    std::vector<EdgeSample> profile;
    for (int b = 0; b < bins; ++b) {
      if (count[b] > 0)
        profile.push_back(
            {static_cast<float>(b * kBinPx - below_px), static_cast<float>(sum[b] / count[b])});
    }
    const double sigma = Median(blur);
    const EdgeFit one = FitBlurredStep(profile, 0.0, sigma, 0.0);
    const EdgeFit two = FitTwoSlopeStep(profile, 0.0, sigma, 0.0);
    // The bins' means carry the samples' noise over the samples per bin: the two-slope fit's
    // gain over the plain one in units of it is χ² with one degree of freedom when the sides
    // slope alike, and the edges' difference is then noise too. Only the part of the difference
    // the gain cannot put down to noise counts (its square less the noise's share, as above).
    double within = 0, n = 0;
    int occupied = 0;
    for (int b = 0; b < bins; ++b) {
      if (count[b] == 0) continue;
      within += sum2[b] - sum[b] * sum[b] / count[b];
      n += count[b];
      ++occupied;
    }
    const double mean_var = n > occupied ? within / (n - occupied) / (n / occupied) : 0.0;
    if (one.converged && two.converged && std::abs(two.edge_px) < std::min(below_px, above_px) &&
        mean_var > 0) {
      const double gain = (one.rms * one.rms - two.rms * two.rms) * profile.size() / mean_var;
      if (gain > 1) slopes_px = std::abs(two.edge_px - one.edge_px) * std::sqrt(1 - 1 / gain);
    }
  }
  return std::hypot(shared_px, slopes_px);
}

}  // namespace clogscope::vision
