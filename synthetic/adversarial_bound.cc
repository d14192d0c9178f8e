#include "synthetic/adversarial_bound.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "synthetic/adversarial_optics.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::synthetic {
namespace {

// The unknowns: the left and right edges' places across, the background's level, the strand's
// brightness (a gain on its own light), the blur.
constexpr int kParams = 5;
using Vec = Eigen::Matrix<double, kParams, 1>;
using Mat = Eigen::Matrix<double, kParams, kParams>;

constexpr int kPhases = 4;        // pixel grids offset by a quarter px: rows see every phase
constexpr double kCellPx = 0.1;   // the cross-section's cells, far finer than any blur
constexpr double kStepPx = 0.02;  // finite differences in place and blur
constexpr double kRoundingVar = 1.0 / 12.0;  // grey levels²: rounding to 8 bit

// Φ on a table: the profiles cost millions of its values.
class NormalCdfTable {
 public:
  NormalCdfTable() {
    for (int i = 0; i < kSize; ++i)
      table_[i] = 0.5 * std::erfc(-(kLo + i * kStep) / std::sqrt(2.0));
  }
  double operator()(double z) const {
    const double t = (z - kLo) / kStep;
    if (t <= 0) return 0.0;
    if (t >= kSize - 1) return 1.0;
    const int i = static_cast<int>(t);
    const double f = t - i;
    return table_[i] + f * (table_[i + 1] - table_[i]);
  }

 private:
  static constexpr double kLo = -9.0, kStep = 1e-3;
  static constexpr int kSize = 18001;
  std::array<double, kSize> table_;
};

struct Shape {
  double width_px, centre_px, blur_px;
};

// What the strand does to the background (A: τ − 1, covering it) and adds to it (B: its own
// light, per unit gain), blurred and averaged over each pixel, at pixel centres u_i = u0 + i.
void Layers(const AdversarialScene& p, const Shape& s, int cells, double u0, int pixels,
            const NormalCdfTable& phi, std::vector<double>* a, std::vector<double>* b) {
  const double h = 0.5 * s.width_px, dx = s.width_px / cells;
  const double sigma = std::max(0.05, s.blur_px);
  const double reach = 9.0 * sigma + 1.0;
  a->assign(pixels, 0.0);
  b->assign(pixels, 0.0);
  for (int k = 0; k < cells; ++k) {
    const double x = s.centre_px - h + (k + 0.5) * dx;
    const double xr = (x - s.centre_px) / h;
    double cover = -1, own = 0;  // τ − 1 and the light per unit gain
    if (p.lens) {
      cover = LensTransmission(xr, p.lens_index, p.lens_acceptance_rad, p.lens_rim_floor) - 1.0;
    } else {
      own = StrandEmission(p, xr) / std::max(1e-9, p.strand_level);
    }
    // The stripe's light (grey levels) in the same units: per unit of the opaque strand's
    // brightness, as it is on a lens (whose gain is 1).
    const double stripe_gain =
        p.lens ? p.stripe_gain : p.stripe_gain / std::max(1e-9, p.strand_level);
    if (p.stripe_gain != 0 &&
        std::abs(x - s.centre_px - p.stripe_offset * s.width_px) < p.stripe_width * h)
      own += stripe_gain;
    const int i0 = std::max(0, static_cast<int>(std::floor(x - reach - u0)));
    const int i1 = std::min(pixels - 1, static_cast<int>(std::ceil(x + reach - u0)));
    for (int i = i0; i <= i1; ++i) {
      const double t = u0 + i - x;
      const double kernel = phi((t + 0.5) / sigma) - phi((t - 0.5) / sigma);
      (*a)[i] += cover * kernel * dx;
      (*b)[i] += own * kernel * dx;
    }
  }
}

}  // namespace

double WidthBoundSigmaPx(const AdversarialScene& p, double width_px) {
  static const NormalCdfTable phi;
  const double inf = std::numeric_limits<double>::infinity();
  if (!(width_px > 0) || !p.strand) return inf;
  const double blur_px = std::max(0.05, p.blur_sigma_px);
  const double margin_px = 9.0 * blur_px + 3.0;
  const int pixels = static_cast<int>(std::ceil(width_px + 2 * margin_px)) + 1;
  const int cells = std::max(200, static_cast<int>(std::ceil(width_px / kCellPx)));
  // The strand's own light is a gain on B (1 on a lit strand's axis); a lens's is its stripe's.
  const double gain = p.lens ? 1.0 : p.strand_level;
  const double bg = p.background_level;

  struct Channel {
    double share, tint_bg, tint_strand;
  };
  std::vector<Channel> channels;
  if (p.colour) {  // an RGGB mosaic: a quarter of the pixels blue, half green, a quarter red
    const double share[3] = {0.25, 0.5, 0.25};
    for (int c = 0; c < 3; ++c) channels.push_back({share[c], kBackgroundTint[c], kStrandTint[c]});
  } else {
    channels.push_back({1.0, 1.0, 1.0});
  }

  // An edge moves the light within its transition (the blur's reach and a px) with it: the
  // strand's light further in is its own unknown, whose shape (a lit cylinder's ramp, a lens's
  // core, a stripe) says nothing of where the silhouette is.
  const double reach_px = 3.0 * blur_px + 2.5;
  Mat info = Mat::Zero();
  std::vector<double> a, b, a_lo, b_lo, a_hi, b_hi;
  std::array<std::vector<double>, 2> da, db;  // ∂/∂centre, ∂/∂blur
  for (int ph = 0; ph < kPhases; ++ph) {
    const double u0 = -0.5 * width_px - margin_px + static_cast<double>(ph) / kPhases;
    const Shape base{width_px, 0.0, blur_px};
    Layers(p, base, cells, u0, pixels, phi, &a, &b);
    for (int q = 0; q < 2; ++q) {
      Shape lo = base, hi = base;
      (q == 0 ? lo.centre_px : lo.blur_px) -= kStepPx;
      (q == 0 ? hi.centre_px : hi.blur_px) += kStepPx;
      Layers(p, lo, cells, u0, pixels, phi, &a_lo, &b_lo);
      Layers(p, hi, cells, u0, pixels, phi, &a_hi, &b_hi);
      da[q].resize(pixels);
      db[q].resize(pixels);
      for (int i = 0; i < pixels; ++i) {
        da[q][i] = (a_hi[i] - a_lo[i]) / (2 * kStepPx);
        db[q][i] = (b_hi[i] - b_lo[i]) / (2 * kStepPx);
      }
    }
    for (const Channel& ch : channels) {
      for (int i = 0; i < pixels; ++i) {
        // radiance = bg·tint_bg·(1 + A) + gain·tint_strand·B
        const double value = bg * ch.tint_bg * (1 + a[i]) + gain * ch.tint_strand * b[i];
        if (value >= kFullScale || value <= 0) continue;  // clipped: tells nothing
        const auto d = [&](int q) {
          return bg * ch.tint_bg * da[q][i] + gain * ch.tint_strand * db[q][i];
        };
        const double u = u0 + i;
        const bool left = u < 0 && std::abs(u + 0.5 * width_px) <= reach_px;
        const bool right = u >= 0 && std::abs(u - 0.5 * width_px) <= reach_px;
        Vec g;
        g << (left ? d(0) : 0.0), (right ? d(0) : 0.0), ch.tint_bg * (1 + a[i]),
            ch.tint_strand * b[i], d(1);
        const double var = NoiseVariance(p.noise_sigma, value) + kRoundingVar;
        info += (ch.share / kPhases) * g * g.transpose() / var;
      }
    }
  }
  // Every px along the band's length holds one such row of pixels across it.
  info *= vision::DefaultBand(vision::MeasureTarget::kStrand, p.scale_um_per_px).height_px;
  // A lens has no light of its own to be unknown (only its stripe's, if any, taken as known), nor
  // has a black strand.
  if (p.lens || !(p.strand_level > 0)) {
    info.row(3).setZero();
    info.col(3).setZero();
    info(3, 3) = 1.0;
  }
  const Eigen::FullPivLU<Mat> lu(info);
  if (!lu.isInvertible()) return inf;
  const Mat cov = lu.inverse();
  const double var_width = cov(0, 0) + cov(1, 1) - 2 * cov(0, 1);
  return var_width > 0 ? std::sqrt(var_width) : inf;
}

}  // namespace clogscope::synthetic
