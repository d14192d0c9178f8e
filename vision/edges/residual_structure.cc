#include "vision/edges/residual_structure.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "common/robust.h"
#include "vision/edges/far_slopes.h"

namespace clogscope::vision {
namespace {

// The two-slope step's premise, a flat object: its side's slope at most this share of the
// background's. And one background slope: the move with the window reaching further into the
// background within 2σ of it or this share of it (a pixel's box is not quite a Gaussian's blur).
constexpr double kMaxObjectSlopeShare = 0.25, kSameMoveShare = 0.1;

// std::lround to the same integer, without a call into libm for every pooled sample's bin (1.6 %
// of a tracked frame's instructions). Exact for finite |x| < 2^52: x less its integer part is its
// fraction.
long RoundHalfAway(double x) {
  long r = static_cast<long>(x);
  const double fraction = x - static_cast<double>(r);
  if (fraction >= 0.5) ++r;
  if (fraction <= -0.5) --r;
  return r;
}

// The band's pooled profile about its calipers' own edges, from below_px before each to above_px
// after it, in 0.1 px bins (far finer than any blur: the fits then cost what two calipers' do, not
// what the whole band's samples would).
class PooledProfile {
 public:
  PooledProfile(double below_px, double above_px)
      : below_px_(below_px),
        above_px_(above_px),
        sum_(static_cast<size_t>(std::ceil((below_px + above_px) / kBinPx)) + 1, 0.0),
        sum2_(sum_.size(), 0.0),
        count_(sum_.size(), 0.0) {}
  void Add(double u_from_edge_px, float value) {
    // The same float distance for every sample at one place.
    const float u = static_cast<float>(u_from_edge_px);
    const long b = RoundHalfAway((u + below_px_) / kBinPx);
    if (b < 0 || b >= static_cast<long>(sum_.size())) return;
    sum_[b] += value;
    sum2_[b] += static_cast<double>(value) * value;
    count_[b] += 1;
  }
  // Each caliper's samples gathered again over this profile's reach.
  void Gather(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
              const std::vector<CaliperEdge>& edges) {
    std::vector<EdgeSample> samples;
    for (const CaliperEdge& c : edges) {
      const double e = c.fit.edge_px;
      if (!GatherEdgeSamples(img, f, c.s0_px, c.s1_px, e - below_px_, e + above_px_, clip,
                             &samples))
        continue;
      for (const EdgeSample& smp : samples) Add(smp.u_px - e, smp.value);
    }
  }
  // The plain and the two-slope step fitted to the profile: how far the edge moves between them,
  // and the two-slope fit's gain over the plain one in units of the bins' noise (χ² with one
  // degree of freedom when the sides slope alike).
  struct TwoSlopeMove {
    bool found = false;
    double move_px = 0, gain = 0;
    // The profile's slope toward −u and toward +u of the edge, grey levels per px.
    double slope_minus_per_px = 0, slope_plus_per_px = 0;
  };
  TwoSlopeMove FitTwoSlope(double blur_px) const;

 private:
  static constexpr double kBinPx = 0.1;
  double below_px_, above_px_;
  std::vector<double> sum_, sum2_, count_;
};

PooledProfile::TwoSlopeMove PooledProfile::FitTwoSlope(double blur_px) const {
  std::vector<EdgeSample> profile;
  double within = 0, n = 0;
  for (size_t b = 0; b < sum_.size(); ++b) {
    if (count_[b] == 0) continue;
    profile.push_back(
        {static_cast<float>(b * kBinPx - below_px_), static_cast<float>(sum_[b] / count_[b])});
    within += sum2_[b] - sum_[b] * sum_[b] / count_[b];
    n += count_[b];
  }
  const double occupied = static_cast<double>(profile.size());
  // A bin mean's noise: the samples' variance within the bins over the samples a bin holds.
  const double mean_var = n > occupied ? within / (n - occupied) / (n / occupied) : 0.0;
  TwoSlopeMove out;
  if (!(mean_var > 0)) return out;
  const EdgeFit one = FitBlurredStep(profile, 0.0, blur_px, 0.0);
  const EdgeFit two = FitTwoSlopeStep(profile, 0.0, blur_px, 0.0);
  if (!one.converged || !two.converged || std::abs(two.edge_px) >= std::min(below_px_, above_px_))
    return out;
  out.found = true;
  out.move_px = two.edge_px - one.edge_px;
  out.gain = (one.rms * one.rms - two.rms * two.rms) * occupied / mean_var;
  out.slope_minus_per_px = two.slope_per_px;
  out.slope_plus_per_px = two.slope_per_px + two.slope_change_per_px;
  return out;
}

}  // namespace

ResidualStructure::ResidualStructure(double half_width_px)
    : half_width_px_(half_width_px),
      sum_(2 * static_cast<size_t>(std::ceil(half_width_px)) + 1, 0.0),
      count_(sum_.size(), 0.0) {
  assert(half_width_px > 0);
}

void ResidualStructure::Add(double u_from_edge_px, double residual) {
  if (!(std::abs(u_from_edge_px) <= half_width_px_) || !std::isfinite(residual)) return;
  const size_t bin = static_cast<size_t>(RoundHalfAway(u_from_edge_px + std::ceil(half_width_px_)));
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

BandEdgeDoubt JudgeBandEdge(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                            const std::vector<CaliperEdge>& edges, double below_px, double above_px,
                            int background_side, double object_reach_px) {
  EdgeStructureDoubt doubt(std::max(below_px, above_px));
  PooledProfile pooled(below_px, above_px);
  std::vector<EdgeSample> samples;
  std::vector<double> blur, rms;
  bool plain = true;
  for (const CaliperEdge& c : edges) {
    const EdgeFit& e = c.fit;
    rms.push_back(e.rms);  // every caliper's, as the far slopes pool every caliper
    const double u0 = e.edge_px - below_px, u1 = e.edge_px + above_px;
    if (!GatherEdgeSamples(img, f, c.s0_px, c.s1_px, u0, u1, clip, &samples)) continue;
    // Clipped pixels keep their residuals, a censored fit's excess over the clip included: what
    // the frame cannot confirm of the model is doubt. (Left out, a stripe clipped at white beside
    // an edge through JPEG, whose smeared clip the censoring misses, lost its doubt: specular
    // stripe 4033, 0.47 px wide at sigma 0.12.)
    for (const EdgeSample& smp : samples) {
      doubt.structure().Add(smp.u_px - e.edge_px, smp.value - EdgeModelValue(e, smp.u_px));
      pooled.Add(smp.u_px - e.edge_px, smp.value);
    }
    doubt.AddCaliper(e.rms, e.edge_sigma_px, e.samples, u1 - u0);
    blur.push_back(e.sigma_px);
    plain = plain && e.object_side == 0 && e.inner_step == 0;
  }
  BandEdgeDoubt out;
  if (doubt.calipers() < 2) return out;
  const double shared_px = doubt.DoubtPx();
  double slopes_px = 0;
  if (plain) {
    // Both models on the pooled profile, where the noise has averaged down: their difference is
    // the model's, not the noise's.
    const double sigma = Median(blur);
    const PooledProfile::TwoSlopeMove here = pooled.FitTwoSlope(sigma);
    // The slopes on the background's side and on the object's.
    const auto background_slope = [&](const PooledProfile::TwoSlopeMove& t) {
      return background_side < 0 ? t.slope_minus_per_px : t.slope_plus_per_px;
    };
    const auto object_slope = [&](const PooledProfile::TwoSlopeMove& t) {
      return background_side < 0 ? t.slope_plus_per_px : t.slope_minus_per_px;
    };
    // The window sees a background's slope only where the noise is low; the slopes read along
    // the band well past it see it through noise (a background textured 15 grey levels deep by a
    // 37-level step, under noise of 8: the window's two-slope gain 0.1, the slope read past it
    // −0.40 ± 0.05 against −0.37 without the noise, both edges 0.1 px outward), and tell better
    // whether the background is one slope. A sample's noise: the edge fits' residuals (their
    // misfit too, which only makes a curve harder to tell from it).
    const FarSlopes far = JudgeFarSlopes(img, f, clip, edges, below_px, above_px, background_side,
                                         object_reach_px, sigma, Median(rms));
    // The move is the slope change's, which the gain measures in its own σ: the move's σ is the
    // move over √gain. It is taken only where the two-slope step's premise holds: the slope is
    // the background's and the object is flat (a stripe's tail inside the object slopes the
    // other side), and the background is one slope, the move the same with the window reaching
    // further into it (a lamp's spot curves the background, and the move then changes with the
    // reach; a gradient or a long wave of texture does not) and, read along the band past it,
    // one line (a spot 37 px wide by the edge of a 30 px strand moved it 0.4 px outward).
    if (here.found && here.gain >= kTwoSlopeEvidence &&
        std::abs(object_slope(here)) <= kMaxObjectSlopeShare * std::abs(background_slope(here))) {
      const double move_sigma_px = std::abs(here.move_px) / std::sqrt(here.gain);
      const double further_px = std::max(4.0, 0.5 * (background_side < 0 ? below_px : above_px));
      PooledProfile further(below_px + (background_side < 0 ? further_px : 0.0),
                            above_px + (background_side > 0 ? further_px : 0.0));
      further.Gather(img, f, clip, edges);
      const PooledProfile::TwoSlopeMove wider = further.FitTwoSlope(sigma);
      const double same_px = std::max(2.0 * move_sigma_px, kSameMoveShare * std::abs(here.move_px));
      if (wider.found && std::abs(wider.move_px - here.move_px) <= same_px &&
          (!far.background_read || far.background_one_slope)) {
        // Its σ, and the two reaches' disagreement: how far the background is from one slope.
        out.shift_px = here.move_px;
        slopes_px = std::hypot(move_sigma_px, wider.move_px - here.move_px);
      } else {
        slopes_px = std::abs(here.move_px);
      }
    } else if (here.found && here.gain > 1) {
      // Below the evidence, only the part of the move the gain cannot put down to noise counts
      // (its square less the noise's share).
      slopes_px = std::abs(here.move_px) * std::sqrt(1 - 1 / here.gain);
    }
    // Where the edge was not moved, the far slopes' doubt, if larger. (Doubt only: a texture's
    // slope by the edge is not quite its slope farther out.)
    if (out.shift_px == 0) slopes_px = std::max(slopes_px, far.doubt_px);
  }
  out.structure_px = shared_px;
  out.two_slope_px = slopes_px;
  return out;
}

}  // namespace clogscope::vision
