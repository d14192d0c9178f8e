#include "vision/synthetic_extras.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "vision/edge_profile.h"

namespace clogscope::vision::render {
namespace {

// ∫ √(1 − t²) dt.
double CircleArea(double t) {
  t = std::clamp(t, -1.0, 1.0);
  return 0.5 * (t * std::sqrt(1 - t * t) + std::asin(t));
}

}  // namespace

Texture::Texture(double amplitude, double wavelength_px, uint64_t seed) {
  if (amplitude == 0) return;
  std::mt19937_64 rng(seed ^ 0x7e47u);
  std::uniform_real_distribution<double> angle(0, 2 * M_PI), scale(1.0, 4.0);
  constexpr int kWaves = 6;
  for (int i = 0; i < kWaves; ++i) {
    const double a = angle(rng), lambda = wavelength_px * scale(rng);
    const double k = 2 * M_PI / lambda;
    waves_.push_back({k * std::cos(a), k * std::sin(a), angle(rng), amplitude / std::sqrt(kWaves)});
  }
}

double Texture::At(double x, double y) const {
  double v = 0;
  for (const auto& w : waves_) v += w.weight * std::sin(w.kx * x + w.ky * y + w.phase);
  return v;
}

double ClutterObject::Coverage(double x, double y, double sigma_px) const {
  const double rx = x - cx, ry = y - cy;
  const double rho = std::hypot(rx, ry);
  const double reach = radius_px + tooth_depth_px + 1.0 + 9.0 * sigma_px;
  if (rho > reach) return 0.0;
  double r = radius_px, slope = 0;  // boundary radius and dr/dφ at this angle
  if (teeth > 0) {
    // Trapezoidal teeth: a clipped sine.
    const double phi = std::atan2(ry, rx);
    const double s = 1.6 * std::sin(teeth * phi + phase);
    const double c = std::clamp(s, -1.0, 1.0);
    r += 0.5 * tooth_depth_px * (1 + c);
    if (std::abs(s) < 1.0)
      slope = 0.5 * tooth_depth_px * 1.6 * teeth * std::cos(teeth * phi + phase);
  }
  if (rho < 1e-9) return 1.0;
  // Signed distance to the boundary, first order in its slope.
  const double t =
      (r - rho) / std::sqrt(1 + (slope / std::max(rho, 1.0)) * (slope / std::max(rho, 1.0)));
  return PixelMeanOfBlurredStep(t, sigma_px, rx / rho, ry / rho);
}

std::vector<ClutterObject> PlaceClutter(int discs, int gears, double x0, double y0, double dx,
                                        double dy, double width_px, double y_min, int image_width,
                                        int image_height, double avoid_level, uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0xc1077u);
  std::uniform_real_distribution<double> u01(0, 1);
  std::vector<ClutterObject> out;
  for (int i = 0; i < discs + gears; ++i) {
    ClutterObject o;
    o.radius_px = std::clamp((0.2 + 0.6 * u01(rng)) * width_px, 12.0, 0.25 * image_height);
    if (i >= discs) {
      o.teeth = 12 + static_cast<int>(u01(rng) * 20);
      o.tooth_depth_px = 0.15 * o.radius_px;
      o.phase = 2 * M_PI * u01(rng);
    }
    // Beside the strand, some reaching behind its edge (they are hidden there).
    const double side = u01(rng) < 0.5 ? -1.0 : 1.0;
    const double gap = (-0.3 + 1.3 * u01(rng)) * o.radius_px;
    const double along =
        y_min + o.radius_px + u01(rng) * std::max(1.0, image_height - y_min - o.radius_px);
    const double off = side * (0.5 * width_px + o.radius_px + o.tooth_depth_px + gap);
    o.cx = x0 + (along - y0) / dy * dx + off * dy;
    o.cy = along - off * dx;
    if (o.cx < -o.radius_px || o.cx > image_width + o.radius_px) o.cx = x0 - off;
    // A level well away from the strand's, so that the strand's edge stays visible in front.
    do {
      o.level = 12 + 231 * u01(rng);  // off the rails: a clipped distractor is another test
    } while (std::abs(o.level - avoid_level) < 40);
    out.push_back(o);
  }
  return out;
}

ShadingProfile::ShadingProfile(double width_px, double level, double ambient, double sigma_px,
                               double nx, double ny) {
  // Cells of h px with the edges at ±w/2 on cell boundaries.
  const int per_width = std::max(64, static_cast<int>(std::ceil(width_px * 16)));
  h_ = width_px / per_width;
  const double reach = 0.5 * (std::abs(nx) + std::abs(ny)) + 9.0 * sigma_px + 1.0;
  const int margin = static_cast<int>(std::ceil(reach / h_));
  // Cell averages of the change (negative inside the strand, 0 outside).
  const int n_cells = per_width;
  std::vector<double> d(n_cells);
  const double half = 0.5 * width_px;
  for (int j = 0; j < n_cells; ++j) {
    const double a = -half + j * h_, b = a + h_;
    const double mean_root = (CircleArea(b / half) - CircleArea(a / half)) * half / h_;
    d[j] = -level * (1 - ambient) * (1 - mean_root);
  }
  // Cell integrals of the kernel (PSF ⊗ footprint) from its CDF, the blurred step's pixel mean.
  std::vector<double> k(2 * margin + 1);
  for (int i = -margin; i <= margin; ++i) {
    k[i + margin] = PixelMeanOfBlurredStep((i + 0.5) * h_, sigma_px, nx, ny) -
                    PixelMeanOfBlurredStep((i - 0.5) * h_, sigma_px, nx, ny);
  }
  // Values at the cell centres from −w/2 − reach to w/2 + reach.
  u0_ = -half - margin * h_ + 0.5 * h_;
  values_.assign(n_cells + 2 * margin, 0.0);
  for (int i = 0; i < static_cast<int>(values_.size()); ++i) {
    double v = 0;
    // Cell i (value position) against strand cells j: the offset between centres is (i−margin−j)·h.
    for (int j = 0; j < n_cells; ++j) {
      const int o = i - margin - j;
      if (o < -margin || o > margin) continue;
      v += d[j] * k[o + margin];
    }
    values_[i] = v;
  }
}

double ShadingProfile::At(double u) const {
  const double x = (u - u0_) / h_;
  if (x <= 0 || x >= values_.size() - 1) return 0.0;
  const int i = static_cast<int>(x);
  const double t = x - i;
  return values_[i] * (1 - t) + values_[i + 1] * t;
}

}  // namespace clogscope::vision::render
