#include "synthetic/synthetic_extras.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "synthetic/edge_profile.h"

namespace clogscope::synthetic::render {
namespace {

// ∫ √(1 − t²) dt.
double CircleArea(double t) {
  t = std::clamp(t, -1.0, 1.0);
  return 0.5 * (t * std::sqrt(1 - t * t) + std::asin(t));
}

}  // namespace

PlaneWaves::PlaneWaves(const std::vector<Wave>& waves, int width_px, int height_px)
    : waves_(static_cast<int>(waves.size())), width_(width_px), height_(height_px) {
  sx_.resize(waves.size() * width_);
  cx_.resize(waves.size() * width_);
  sy_.resize(waves.size() * height_);
  cy_.resize(waves.size() * height_);
  for (int i = 0; i < waves_; ++i) {
    const Wave& w = waves[i];
    for (int x = 0; x < width_; ++x) {
      sx_[i * width_ + x] = w.amplitude * std::sin(w.kx * x + w.phase);
      cx_[i * width_ + x] = w.amplitude * std::cos(w.kx * x + w.phase);
    }
    for (int y = 0; y < height_; ++y) {
      sy_[i * height_ + y] = std::sin(w.ky * y);
      cy_[i * height_ + y] = std::cos(w.ky * y);
    }
  }
}

double PlaneWaves::At(int x, int y) const {
  double v = 0;
  for (int i = 0; i < waves_; ++i)
    v += sx_[i * width_ + x] * cy_[i * height_ + y] + cx_[i * width_ + x] * sy_[i * height_ + y];
  return v;
}

PlaneWaves Texture(double amplitude, double wavelength_px, uint64_t seed, int width_px,
                   int height_px) {
  std::vector<PlaneWaves::Wave> waves;
  if (amplitude != 0) {
    std::mt19937_64 rng(seed ^ 0x7e47u);
    std::uniform_real_distribution<double> angle(0, 2 * M_PI), scale(1.0, 4.0);
    constexpr int kWaves = 6;
    for (int i = 0; i < kWaves; ++i) {
      const double a = angle(rng), lambda = wavelength_px * scale(rng);
      const double k = 2 * M_PI / lambda;
      waves.push_back(
          {k * std::cos(a), k * std::sin(a), angle(rng), amplitude / std::sqrt(kWaves)});
    }
  }
  return PlaneWaves(waves, width_px, height_px);
}

double ClutterObject::Coverage(double x, double y, double sigma_px) const {
  const double rx = x - cx, ry = y - cy;
  const double reach = radius_px + tooth_depth_px + 1.0 + 9.0 * sigma_px;
  if (rx * rx + ry * ry > reach * reach) return 0.0;  // most pixels: no hypot for them
  const double rho = std::hypot(rx, ry);
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

MicrometerMarks::MicrometerMarks(const MicrometerMarkParams& p)
    : p_(p),
      reach_px_(1 + 6 * p.sigma_px),
      fibre_sigma_px_(std::sqrt(p.sigma_px * p.sigma_px + 1.0 / 12)) {
  const double tick = p.tick_length_px;
  digit_h_ = 0.5 * tick;
  digit_w_ = 0.6 * digit_h_;
  digit_gap_ = 0.35 * digit_w_;
  numeral_bottom_ = -1.25 * tick;  // long ticks reach up to s = −tick
  std::mt19937_64 rng(p.seed ^ 0xd057u);
  std::uniform_real_distribution<double> u01(0, 1);
  for (int i = 0; i < p.dust_specks; ++i) {
    ClutterObject o;
    o.cx = u01(rng) * p.image_width;
    o.cy = u01(rng) * p.image_height;
    o.radius_px = std::max(1.5, p.line_width_px * (1 + 2 * u01(rng)));
    specks_.push_back(o);
  }
  for (int i = 0; i < p.dust_fibres; ++i) {
    Fibre f;
    f.width_px = std::max(1.0, 0.5 * p.line_width_px);
    double x = u01(rng) * p.image_width, y = u01(rng) * p.image_height;
    double angle = M_PI * u01(rng);
    const int segments = 10;
    const double step = (0.1 + 0.2 * u01(rng)) * std::min(p.image_width, p.image_height) / segments;
    for (int j = 0; j <= segments; ++j) {
      f.x.push_back(x);
      f.y.push_back(y);
      x += step * std::cos(angle);
      y += step * std::sin(angle);
      angle += 0.4 * (u01(rng) - 0.5);
    }
    const double r = f.width_px + reach_px_;
    f.x_min = *std::min_element(f.x.begin(), f.x.end()) - r;
    f.x_max = *std::max_element(f.x.begin(), f.x.end()) + r;
    f.y_min = *std::min_element(f.y.begin(), f.y.end()) - r;
    f.y_max = *std::max_element(f.y.begin(), f.y.end()) + r;
    fibres_.push_back(f);
  }
}

double MicrometerMarks::BoxCoverage(const Box& b, double u, double s) const {
  const double r = reach_px_;
  if (u < b.u0 - r || u > b.u1 + r || s < b.s0 - r || s > b.s1 + r) return 0;
  // Across: exact for the pixel's footprint; along: the same with the footprint's other
  // projection (the product is exact away from the box's corners).
  const double across = PixelMeanOfBlurredStep(u - b.u0, p_.sigma_px, p_.nx, p_.ny) -
                        PixelMeanOfBlurredStep(u - b.u1, p_.sigma_px, p_.nx, p_.ny);
  const double along = PixelMeanOfBlurredStep(s - b.s0, p_.sigma_px, -p_.ny, p_.nx) -
                       PixelMeanOfBlurredStep(s - b.s1, p_.sigma_px, -p_.ny, p_.nx);
  return across * along;
}

double MicrometerMarks::NumeralCoverage(long tick, double du, double s) const {
  // Seven segments a–g, bit i for segment 'a' + i, for the digits 0–9.
  static const int kSegments[10] = {0x3f, 0x06, 0x5b, 0x4f, 0x66, 0x6d, 0x7d, 0x07, 0x7f, 0x6f};
  // Called for every pixel: the label is written out only near it.
  const long value = std::labs(tick);
  int n = 1;
  for (long v = value; v >= 10; v /= 10) ++n;
  const double total = n * digit_w_ + (n - 1) * digit_gap_;
  const double r = reach_px_;
  const double sb = numeral_bottom_, st = sb - digit_h_, sm = 0.5 * (st + sb);
  if (std::abs(du) > 0.5 * total + r || s < st - r || s > sb + r) return 0;
  const std::string label = std::to_string(value);
  const double t = p_.line_width_px;
  double clear = 1;
  for (int i = 0; i < n; ++i) {
    const double ul = -0.5 * total + i * (digit_w_ + digit_gap_), ur = ul + digit_w_;
    const Box boxes[7] = {{ul, ur, st, st + t},
                          {ur - t, ur, st, sm},
                          {ur - t, ur, sm, sb},
                          {ul, ur, sb - t, sb},
                          {ul, ul + t, sm, sb},
                          {ul, ul + t, st, sm},
                          {ul, ur, sm - 0.5 * t, sm + 0.5 * t}};
    const int mask = kSegments[label[i] - '0'];
    for (int seg = 0; seg < 7; ++seg)
      if (mask & (1 << seg)) clear *= 1 - BoxCoverage(boxes[seg], du, s);
  }
  return 1 - clear;
}

double MicrometerMarks::Coverage(double x, double y) const {
  const double dx = x - p_.tip_x_px, dy = y - p_.tip_y_px;
  const double u = p_.nx * dx + p_.ny * dy, s = -p_.ny * dx + p_.nx * dy;
  const double pitch = p_.pitch_px, tick = p_.tick_length_px, w = p_.line_width_px;
  double clear = 1;  // the uncovered fraction: marks overlap as independent coverages
  const long k0 = std::lround(u / pitch);
  for (long k = k0 - 2; k <= k0 + 2; ++k) {
    const double length = k % 10 == 0 ? 2 * tick : k % 5 == 0 ? 1.5 * tick : tick;
    const double s0 = tick > 0 ? tick - length : -1e9, s1 = tick > 0 ? tick : 1e9;  // 0: lines
    clear *= 1 - BoxCoverage({k * pitch - 0.5 * w, k * pitch + 0.5 * w, s0, s1}, u, s);
  }
  if (p_.numerals) {
    const long k10 = 10 * std::lround(u / (10 * pitch));
    clear *= 1 - NumeralCoverage(k10, u - k10 * pitch, s);
  }
  for (const auto& o : specks_) {
    const double a = o.Coverage(x, y, p_.sigma_px);
    if (a > 0) clear *= 1 - a;
  }
  // A fibre's profile across it is a blurred box at the distance to its centre line.
  const double se = fibre_sigma_px_;
  for (const auto& f : fibres_) {
    if (x < f.x_min || x > f.x_max || y < f.y_min || y > f.y_max) continue;
    double d2 = 1e30;
    for (size_t j = 1; j < f.x.size(); ++j) {
      const double ax = f.x[j - 1], ay = f.y[j - 1], bx = f.x[j] - ax, by = f.y[j] - ay;
      const double h = std::clamp(((x - ax) * bx + (y - ay) * by) / (bx * bx + by * by), 0.0, 1.0);
      d2 = std::min(d2, std::pow(x - ax - h * bx, 2) + std::pow(y - ay - h * by, 2));
    }
    const double d = std::sqrt(d2);
    clear *= 1 - (NormalCdf((d + 0.5 * f.width_px) / se) - NormalCdf((d - 0.5 * f.width_px) / se));
  }
  return 1 - clear;
}

}  // namespace clogscope::synthetic::render
