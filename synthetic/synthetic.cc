#include "synthetic/synthetic.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <random>
#include <stdexcept>

#include "common/angle.h"
#include "common/atomic_file.h"
#include "synthetic/edge_profile.h"
#include "synthetic/synthetic_extras.h"
#include "vision/io/video_io.h"
#include "vision/io/video_writer.h"

namespace clogscope::synthetic {
namespace {

struct Vec2 {
  double x, y;
};
double Dot(Vec2 a, Vec2 b) { return a.x * b.x + a.y * b.y; }

// A soft half-plane: value 1 inside (t > 0), blurred and pixel-integrated exactly.
struct SoftHalfPlane {
  Vec2 normal;    // unit normal in the image frame, pointing inside
  double offset;  // t = normal · (p - origin) - offset
  double Eval(Vec2 d, double sigma) const {
    return PixelMeanOfBlurredStep(Dot(normal, d) - offset, sigma, normal.x, normal.y);
  }
};

// Per-frame random draws come from a generator seeded by (seed, frame) so any frame can be rendered
// on its own and still match the sequence.
std::mt19937_64 FrameRng(uint64_t seed, int frame, uint64_t stream) {
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32),
                    static_cast<uint32_t>(frame), static_cast<uint32_t>(stream)};
  return std::mt19937_64(seq);
}

}  // namespace

const char* RenderTargetName(RenderTarget t) {
  switch (t) {
    case RenderTarget::kStrand:
      return "strand";
    case RenderTarget::kPin:
      return "pin";
    case RenderTarget::kMicrometer:
      return "micrometer";
  }
  return "?";
}

RenderTarget ParseRenderTarget(const std::string& name) {
  if (name == "strand") return RenderTarget::kStrand;
  if (name == "pin") return RenderTarget::kPin;
  if (name == "micrometer") return RenderTarget::kMicrometer;
  throw std::invalid_argument("target '" + name + "': expected strand, pin or micrometer");
}

bool SceneParams::Validate(std::string* why) const {
  auto fail = [&](const std::string& msg) {
    if (why) *why = msg;
    return false;
  };
  if (width_px < 16 || height_px < 16 || width_px > 16384 || height_px > 16384)
    return fail(fmt::format("frame size {}x{} px is outside 16..16384", width_px, height_px));
  if (!(scale_um_per_px > 0)) return fail("scale_um_per_px must be positive");
  if (!(strand_width_um > 0)) return fail("strand_width_um must be positive");
  if (!(blur_sigma_px >= 0) || blur_sigma_px > 50) return fail("blur_sigma_px must be in 0..50");
  if (!(noise_sigma >= 0)) return fail("noise_sigma must not be negative");
  if (std::abs(tilt_deg) > 60) return fail("tilt_deg must be within ±60");
  if (!(sway_deg >= 0) || !(width_jitter_um >= 0))
    return fail("sway_deg and width_jitter_um must not be negative");
  if (!(surface_texture_amplitude >= 0) || !std::isfinite(feed_speed_mm_s) ||
      !(frame_rate_hz > 0 && std::isfinite(frame_rate_hz)))
    return fail("surface texture must be ≥ 0, feed speed a number, frame rate positive");
  if (drive_gear && !(gear_radius_px > gear_tooth_depth_px && gear_tooth_depth_px >= 0 &&
                      gear_teeth >= 3 && std::isfinite(gear_surface_speed_mm_s)))
    return fail("drive gear: radius > tooth depth ≥ 0, at least 3 teeth, a finite speed");
  if (!(knurl_depth_px >= 0) || !(knurl_pitch_px > 0) || !std::isfinite(knurl_start_px))
    return fail("knurl: depth ≥ 0, pitch > 0, a finite start");
  for (double w : frame_width_um) {
    if (!(w > 0) || !std::isfinite(w)) return fail("frame_width_um: every width must be positive");
    if (target == RenderTarget::kStrand && nozzle && nozzle_tip_width_um <= w)
      return fail("nozzle_tip_width_um must exceed every scheduled width");
  }
  if (target == RenderTarget::kStrand && nozzle && nozzle_tip_width_um <= strand_width_um)
    return fail("nozzle_tip_width_um must exceed strand_width_um");
  if (!(nozzle_cone_half_angle_deg > 0 && nozzle_cone_half_angle_deg < 85))
    return fail("nozzle_cone_half_angle_deg must be in (0, 85)");
  if (bed && !(bed_gap_um > 0)) return fail("bed_gap_um must be positive");
  if (std::abs(gradient_fraction) >= 1) return fail("gradient_fraction must be within (-1, 1)");
  if (bit_depth != 8 && bit_depth != 16) return fail("bit_depth must be 8 or 16");
  if (std::abs(edge_bias_px) > 10) return fail("edge_bias_px must be within ±10 px");
  if (target == RenderTarget::kMicrometer) {
    if (!(line_width_um > 0)) return fail("line_width_um must be positive");
    if (!(pitch_um > 2 * line_width_um)) return fail("pitch_um must exceed twice the line width");
    if (pitch_um / scale_um_per_px < 4) return fail("micrometer lines closer than 4 px");
    if (!(tick_length_um >= 0)) return fail("tick_length_um must not be negative");
    if (numerals && tick_length_um == 0) return fail("numerals need tick_length_um");
  }
  if (dust_specks < 0 || dust_fibres < 0 || dust_specks + dust_fibres > 200)
    return fail("dust: 0 to 200 specks and fibres");
  if (target != RenderTarget::kMicrometer &&
      (tick_length_um > 0 || numerals || dust_specks > 0 || dust_fibres > 0))
    return fail("ticks, numerals and dust go with the micrometer target");
  if (data_bits != 0 && !(bit_depth == 16 && data_bits >= 9 && data_bits <= 16))
    return fail("data_bits: 9 to 16, with bit_depth 16");
  if (!(texture_amplitude >= 0 && texture_amplitude <= 100))
    return fail("texture_amplitude must be within 0..100 grey levels");
  if (!(texture_wavelength_px >= 8)) return fail("texture_wavelength_px must be at least 8");
  if (clutter_discs < 0 || clutter_gears < 0 || clutter_discs + clutter_gears > 20)
    return fail("clutter: 0 to 20 discs and gears");
  if (!(shading_ambient >= 0 && shading_ambient <= 1))
    return fail("shading_ambient must be within 0..1");
  if (!(vignetting >= 0 && vignetting < 1)) return fail("vignetting must be within [0, 1)");
  for (const double* tint : {strand_tint, background_tint, nozzle_tint}) {
    for (int c = 0; c < 3; ++c)
      if (!(tint[c] >= 0 && tint[c] <= 1.5)) return fail("colour tints must be within 0..1.5");
  }
  for (double level : {background_level, strand_level, nozzle_level, bed_level}) {
    if (level < 0 || level > 255) return fail("grey levels must be within 0..255 (8-bit scale)");
  }
  return true;
}

void SceneParams::SetSilhouette() {
  background_level = 215.0;
  strand_level = 55.0;
  nozzle_level = 45.0;
  bed_level = 60.0;
}

SceneParams FeedstockScene(double feed_speed_mm_s, std::optional<double> gear_surface_speed_mm_s) {
  SceneParams p;
  p.width_px = 640;
  p.height_px = 480;
  p.scale_um_per_px = 20;
  p.strand_width_um = 1750;
  p.nozzle = false;
  p.tip_x_px = 320;
  p.tip_y_px = 0;
  p.surface_texture_amplitude = 8;
  p.feed_speed_mm_s = feed_speed_mm_s;
  p.frame_rate_hz = 30;
  p.seed = 5;
  if (gear_surface_speed_mm_s) {
    p.drive_gear = true;
    p.gear_centre_x_px = 176;
    p.gear_centre_y_px = 240;
    p.gear_radius_px = 100;
    p.gear_teeth = 20;
    p.gear_surface_speed_mm_s = *gear_surface_speed_mm_s;
  }
  return p;
}

SceneParams RandomRealisticScene(uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9e3779b97f4a7c15ull + 17);
  std::uniform_real_distribution<double> u01(0, 1);
  const auto uni = [&](double a, double b) { return a + (b - a) * u01(rng); };
  SceneParams p;
  p.seed = seed;
  const bool lit = u01(rng) < 0.6;
  if (lit) {
    p.background_level = uni(15, 80);
    p.strand_level = uni(p.background_level + 70, 235);
  } else {
    p.background_level = uni(170, 240);
    p.strand_level = uni(20, p.background_level - 90);
  }
  p.nozzle = u01(rng) >= 0.2;
  p.nozzle_level = uni(0, 255);
  p.strand_width_um = uni(250, 450);
  p.tilt_deg = uni(-20, 20);
  p.blur_sigma_px = uni(0.8, 3.0);
  p.noise_sigma = uni(1.0, 4.0);
  p.tip_x_px = uni(520, 760);
  p.tip_y_px = uni(120, 300);
  p.texture_amplitude = uni(0, 20);
  p.texture_wavelength_px = uni(80, 250);
  p.clutter_discs = static_cast<int>(uni(0, 3.99));
  p.clutter_gears = static_cast<int>(uni(0, 2.99));
  if (lit && u01(rng) < 0.5) p.shading_ambient = uni(0.4, 1.0);
  if (!lit && u01(rng) < 0.25) {
    p.clear_strand = true;
    p.clear_line_gain = uni(30, 255 - p.strand_level);
  }
  if (lit && u01(rng) < 0.3) p.highlight = true;
  if (p.nozzle && u01(rng) < 0.2) p.bed = true;
  p.gradient_fraction = uni(0, 0.2);
  p.gradient_angle_deg = uni(0, 360);
  p.vignetting = uni(0, 0.3);
  if (u01(rng) < 0.3) {
    // An orange strand on a blue background.
    p.colour = true;
    const double strand[3] = {0.25, 0.6, 1.0}, background[3] = {1.0, 0.55, 0.2};
    for (int c = 0; c < 3; ++c) {
      p.strand_tint[c] = strand[c];
      p.background_tint[c] = background[c];
      p.nozzle_tint[c] = uni(0.3, 1.0);
    }
  }
  // Headroom: the gradient brightens one side by up to half its fraction, noise adds 3σ; a
  // clipped edge is a fair "saturated", but not what this scene is for.
  p.strand_level =
      std::min(p.strand_level, (250.0 - 3 * p.noise_sigma) / (1 + 0.5 * p.gradient_fraction));
  p.background_level =
      std::min(p.background_level, (250.0 - 3 * p.noise_sigma) / (1 + 0.5 * p.gradient_fraction));
  // And at the dark end, after texture, vignetting and the gradient have darkened it.
  const double floor = (3 * p.noise_sigma + 8 + p.texture_amplitude) /
                       ((1 - p.vignetting) * (1 - 0.5 * p.gradient_fraction));
  p.background_level = std::max(p.background_level, floor);
  p.strand_level = std::max(p.strand_level, floor);
  return p;
}

FrameTruth FrameTruthFor(const SceneParams& p, int frame_index) {
  FrameTruth t;
  t.frame = frame_index;
  auto rng = FrameRng(p.seed, frame_index, 1);
  std::normal_distribution<double> normal(0.0, 1.0);
  double sway = normal(rng) * p.sway_deg;
  double jitter = normal(rng) * p.width_jitter_um;
  const double base =
      p.frame_width_um.empty()
          ? p.strand_width_um
          : p.frame_width_um[std::min<size_t>(frame_index, p.frame_width_um.size() - 1)];
  t.width_um = base + jitter;
  if (p.target == RenderTarget::kMicrometer) t.width_um = p.line_width_um;
  t.width_px = t.width_um / p.scale_um_per_px + p.edge_bias_px;
  t.angle_deg = p.tilt_deg + sway;
  t.tip_x_px = p.tip_x_px;
  t.tip_y_px = p.tip_y_px;
  t.time_s = frame_index / p.frame_rate_hz;
  t.feed_offset_px = p.feed_speed_mm_s * 1e3 * t.time_s / p.scale_um_per_px;
  if (p.drive_gear) {
    t.gear_angle_rad =
        p.gear_surface_speed_mm_s * 1e3 * t.time_s / p.scale_um_per_px / p.gear_radius_px;
  }
  return t;
}

namespace {

constexpr double kPi = 3.14159265358979323846;

// A filament's surface along its axis: a sum of sinusoids of random wavelength and phase, each
// rendered exactly through the Gaussian PSF (exp(−2π²σ²k²)) and the pixel's box (sinc per axis).
class SurfaceTexture {
 public:
  SurfaceTexture(double amplitude, uint64_t seed, double sigma, double dir_x, double dir_y) {
    if (amplitude <= 0) return;
    auto rng = FrameRng(seed, -1, 7);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    const int n = 24;
    for (int j = 0; j < n; ++j) {
      const double wavelength = 6 * std::pow(80.0 / 6, uni(rng));
      const double k = 1 / wavelength;
      const auto sinc = [](double x) { return std::abs(x) < 1e-12 ? 1.0 : std::sin(x) / x; };
      const double att = std::exp(-2 * kPi * kPi * sigma * sigma * k * k) * sinc(kPi * k * dir_x) *
                         sinc(kPi * k * dir_y);
      waves_.push_back({2 * kPi * k, 2 * kPi * uni(rng), amplitude * std::sqrt(2.0 / n) * att});
    }
  }
  double At(double s) const {
    double v = 0;
    for (const auto& w : waves_) v += w.amp * std::cos(w.omega * s + w.phase);
    return v;
  }
  bool empty() const { return waves_.empty(); }

 private:
  struct Wave {
    double omega, phase, amp;
  };
  std::vector<Wave> waves_;
};

// A toothed gear turned by `angle`: teeth where cos(N·θ′) > 0 at the tip radius, gaps tooth_depth
// lower with smooth flanks, and marks on its face (low harmonics of θ′) that turn with it. The
// rim is a blurred radial step (σ with the pixel's footprint): close to exact for radii ≫ σ.
class DriveGear {
 public:
  DriveGear(const SceneParams& p, double angle_rad, double sigma)
      : p_(p), angle_(angle_rad), sigma_(std::sqrt(sigma * sigma + 1.0 / 12)) {
    auto rng = FrameRng(p.seed, -2, 9);
    std::uniform_real_distribution<double> uni(0.0, 1.0);
    for (int h = 1; h <= 8; ++h) marks_.push_back({h, 2 * kPi * uni(rng), 25.0 * uni(rng) / h});
  }
  bool enabled() const { return p_.drive_gear; }
  // Coverage in [0, 1] and the gear's grey level at the pixel.
  double Coverage(double x, double y, double* level) const {
    const double dx = x - p_.gear_centre_x_px, dy = y - p_.gear_centre_y_px;
    const double reach = p_.gear_radius_px + 5 * sigma_;
    if (dx * dx + dy * dy > reach * reach) return 0;  // most pixels: no hypot for them
    const double r = std::hypot(dx, dy);
    const double theta = std::atan2(dy, dx) - angle_;
    const double tooth = 0.5 * (1 + std::tanh(3 * std::cos(p_.gear_teeth * theta)));
    const double edge = p_.gear_radius_px - p_.gear_tooth_depth_px * (1 - tooth);
    double v = p_.gear_level;
    for (const auto& m : marks_)
      v += m.amp * (r / p_.gear_radius_px) * std::cos(m.h * theta + m.phase);
    *level = v;
    return 0.5 * std::erfc((r - edge) / (std::sqrt(2.0) * sigma_));
  }

 private:
  struct Mark {
    int h;
    double phase, amp;
  };
  const SceneParams& p_;
  double angle_, sigma_;
  std::vector<Mark> marks_;
};

}  // namespace

cv::Mat RenderFrame(const SceneParams& p, int frame_index, FrameTruth* truth_out) {
  std::string why;
  if (!p.Validate(&why)) throw std::invalid_argument("scene: " + why);
  const FrameTruth truth = FrameTruthFor(p, frame_index);
  if (truth.width_um <= 0) throw std::invalid_argument("scene: width jitter made the width <= 0");

  const double sigma = p.blur_sigma_px;
  const double w = truth.width_px;
  const double pitch_px = p.pitch_um / p.scale_um_per_px;
  const double th_strand = truth.angle_deg * kDegToRad;
  const double th_scene = p.tilt_deg * kDegToRad;
  const Vec2 n_strand{std::cos(th_strand), -std::sin(th_strand)};
  const Vec2 n_scene{std::cos(th_scene), -std::sin(th_scene)};
  const Vec2 d_scene{std::sin(th_scene), std::cos(th_scene)};

  // Strand: between two parallel edges at u = -w/2 and u = +w/2 across the strand axis.
  const SoftHalfPlane strand_left{n_strand, -0.5 * w};
  const SoftHalfPlane strand_right{n_strand, 0.5 * w};
  const double hl_c = p.highlight_offset_fraction * w;
  const double hl_h = 0.5 * p.highlight_width_fraction * w;
  const SoftHalfPlane hl_left{n_strand, hl_c - hl_h};
  const SoftHalfPlane hl_right{n_strand, hl_c + hl_h};
  // Bed: below s = gap along the scene axis.
  const SoftHalfPlane bed{d_scene, p.bed_gap_um / p.scale_um_per_px};
  // Nozzle: above the tip face (s < 0) and between the two flanks.
  const double half_tip = 0.5 * p.nozzle_tip_width_um / p.scale_um_per_px;
  const double phi = p.nozzle_cone_half_angle_deg * kDegToRad;
  const SoftHalfPlane nozzle_face{{-d_scene.x, -d_scene.y}, 0.0};
  // Right flank: inside when (half_tip - s tan(phi) - u) cos(phi) > 0.
  const SoftHalfPlane nozzle_right{{-std::cos(phi) * n_scene.x - std::sin(phi) * d_scene.x,
                                    -std::cos(phi) * n_scene.y - std::sin(phi) * d_scene.y},
                                   -half_tip * std::cos(phi)};
  const SoftHalfPlane nozzle_left{{std::cos(phi) * n_scene.x - std::sin(phi) * d_scene.x,
                                   std::cos(phi) * n_scene.y - std::sin(phi) * d_scene.y},
                                  -half_tip * std::cos(phi)};

  const double ga = p.gradient_angle_deg * kDegToRad;
  const Vec2 g_dir{std::cos(ga), std::sin(ga)};
  const double diag = std::hypot(p.width_px, p.height_px);
  const Vec2 centre{0.5 * (p.width_px - 1), 0.5 * (p.height_px - 1)};

  // The realistic extras: texture and clutter behind the strand, its shading, clear-strand lines.
  const render::PlaneWaves texture = render::Texture(p.texture_amplitude, p.texture_wavelength_px,
                                                     p.seed, p.width_px, p.height_px);
  const std::vector<render::ClutterObject> clutter = render::PlaceClutter(
      p.clutter_discs, p.clutter_gears, p.tip_x_px, p.tip_y_px, -n_strand.y, n_strand.x, w,
      p.nozzle ? p.tip_y_px : 0.0, p.width_px, p.height_px, p.strand_level, p.seed);
  const bool shaded = p.shading_ambient < 1.0 && p.target != RenderTarget::kMicrometer;
  const render::ShadingProfile shading(shaded ? w : 1.0, p.strand_level, p.shading_ambient, sigma,
                                       n_strand.x, n_strand.y);
  const double cl_h = 0.03 * w;
  const SoftHalfPlane clear_l1{n_strand, -0.3 * w - cl_h}, clear_r1{n_strand, -0.3 * w + cl_h};
  const SoftHalfPlane clear_l2{n_strand, 0.3 * w - cl_h}, clear_r2{n_strand, 0.3 * w + cl_h};
  const bool has_nozzle = p.target == RenderTarget::kStrand && p.nozzle;
  const Vec2 d_strand{std::sin(th_strand), std::cos(th_strand)};
  const SurfaceTexture surface(
      p.target == RenderTarget::kMicrometer ? 0 : p.surface_texture_amplitude, p.seed, sigma,
      d_strand.x, d_strand.y);
  const DriveGear gear(p, truth.gear_angle_rad, sigma);
  render::MicrometerMarkParams mp;
  mp.pitch_px = pitch_px;
  mp.line_width_px = w;
  mp.tick_length_px = p.tick_length_um / p.scale_um_per_px;
  mp.numerals = p.numerals;
  mp.dust_specks = p.dust_specks;
  mp.dust_fibres = p.dust_fibres;
  mp.sigma_px = sigma;
  mp.nx = n_strand.x;
  mp.ny = n_strand.y;
  mp.tip_x_px = p.tip_x_px;
  mp.tip_y_px = p.tip_y_px;
  mp.image_width = p.width_px;
  mp.image_height = p.height_px;
  mp.seed = p.seed;
  const bool marked = p.target == RenderTarget::kMicrometer &&
                      (p.tick_length_um > 0 || p.dust_specks > 0 || p.dust_fibres > 0);
  const render::MicrometerMarks marks(mp);
  const int nc = p.colour ? 3 : 1;
  static const double kGrey[3] = {1.0, 1.0, 1.0};
  const double* tb = p.colour ? p.background_tint : kGrey;
  const double* ts = p.colour ? p.strand_tint : kGrey;
  const double* tn = p.colour ? p.nozzle_tint : kGrey;
  const double corner2 = centre.x * centre.x + centre.y * centre.y;

  // Live-watch events in front of the scene at this frame's time.
  std::vector<render::ClutterObject> events;
  if (p.purge_start_s >= 0 && truth.time_s >= p.purge_start_s &&
      truth.time_s < p.purge_start_s + p.purge_duration_s) {
    const double r = p.purge_radius_px > 0 ? p.purge_radius_px : 1.5 * w;
    events.push_back({p.tip_x_px + d_strand.x * r, p.tip_y_px + d_strand.y * r, r, p.strand_level});
  }
  for (double t0 : p.occlusion_start_s) {
    if (truth.time_s >= t0 && truth.time_s < t0 + p.occlusion_duration_s) {
      events.push_back({p.tip_x_px + d_strand.x * 3 * w, p.tip_y_px + d_strand.y * 3 * w, 3 * w,
                        p.background_level < 128 ? 5.0 : 250.0});
      break;
    }
  }
  std::vector<cv::Mat> radiance(nc);
  for (auto& r : radiance) r.create(p.height_px, p.width_px, CV_64F);
  // Rows are independent: render them on all cores.
  cv::parallel_for_(cv::Range(0, p.height_px), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      for (int x = 0; x < p.width_px; ++x) {
        const Vec2 d{x - p.tip_x_px, y - p.tip_y_px};
        // Background with its texture and the objects standing in it.
        double bg = p.background_level + texture.At(x, y);
        for (const auto& o : clutter) {
          const double a = o.Coverage(x, y, sigma);
          if (a > 0) bg = bg * (1 - a) + o.level * a;
        }
        if (gear.enabled()) {
          double level = 0;
          const double a = gear.Coverage(x, y, &level);
          if (a > 0) bg = bg * (1 - a) + level * a;
        }
        double cov, front;  // strand coverage, and the strand's light where it covers
        if (marked) {
          cov = marks.Coverage(x, y);
          front = p.strand_level * cov;
        } else if (p.target == RenderTarget::kMicrometer) {
          // The nearest lines only: they are at least 4 px apart and the reach of one is 9 sigma.
          const double u = Dot(n_strand, d);
          const long k0 = std::lround(u / pitch_px);
          cov = 0;
          for (long k = k0 - 2; k <= k0 + 2; ++k) {
            const double c = k * pitch_px;
            cov += PixelMeanOfBlurredStep(u - c + 0.5 * w, sigma, n_strand.x, n_strand.y) -
                   PixelMeanOfBlurredStep(u - c - 0.5 * w, sigma, n_strand.x, n_strand.y);
          }
          front = p.strand_level * cov;
        } else {
          double left = strand_left.Eval(d, sigma);
          const double s_axis = Dot(d_strand, d), u = Dot(n_strand, d);
          double shading_u = u;
          if (p.knurl_depth_px > 0 && s_axis > p.knurl_start_px) {
            const double ph = (s_axis - truth.feed_offset_px) / p.knurl_pitch_px;
            const double out = p.knurl_depth_px * (ph - std::floor(ph) - 1.0 / 3.0);
            left = SoftHalfPlane{n_strand, -0.5 * w - out}.Eval(d, sigma);
            // The left half's shading follows the marked edge.
            shading_u = u + out * std::clamp(-2.0 * u / w, 0.0, 1.0);
          }
          cov = p.strand ? left - strand_right.Eval(d, sigma) : 0.0;
          front = p.strand_level * cov;
          if (shaded && p.strand) front += shading.At(shading_u);
          if (!surface.empty() && cov > 0)
            front += cov * surface.At(Dot(d_strand, d) - truth.feed_offset_px);
          if (p.highlight && p.strand)
            front += p.highlight_gain * (hl_left.Eval(d, sigma) - hl_right.Eval(d, sigma));
          if (p.clear_strand && p.strand) {
            front += p.clear_line_gain * (clear_l1.Eval(d, sigma) - clear_r1.Eval(d, sigma) +
                                          clear_l2.Eval(d, sigma) - clear_r2.Eval(d, sigma));
          }
        }
        double bed_a = 0, nozzle_a = 0;
        if (p.target == RenderTarget::kStrand && p.bed) bed_a = bed.Eval(d, sigma);
        if (has_nozzle) {
          // The product of three soft half-planes is exact away from the two flank corners, which
          // lie far from the measurement band.
          nozzle_a = nozzle_face.Eval(d, sigma);
          if (nozzle_a > 0) nozzle_a *= nozzle_right.Eval(d, sigma) * nozzle_left.Eval(d, sigma);
        }
        double gain = 1.0;
        if (p.gradient_fraction != 0) {
          const Vec2 c{x - centre.x, y - centre.y};
          gain *= 1.0 - p.gradient_fraction * Dot(c, g_dir) / diag;
        }
        if (p.vignetting != 0) {
          const double r2 = (x - centre.x) * (x - centre.x) + (y - centre.y) * (y - centre.y);
          gain *= 1.0 - p.vignetting * r2 / corner2;
        }
        for (int c = 0; c < nc; ++c) {
          double v = bg * tb[c] * (1 - cov) + front * ts[c];
          v = v * (1 - bed_a) + p.bed_level * tb[c] * bed_a;
          v = v * (1 - nozzle_a) + p.nozzle_level * tn[c] * nozzle_a;
          for (const auto& o : events) {
            const double a = o.Coverage(x, y, sigma);
            if (a > 0) v = v * (1 - a) + o.level * tb[c] * a;
          }
          radiance[c].ptr<double>(y)[x] = v * gain;
        }
      }
    }
  });

  const double full_scale = p.bit_depth == 8  ? 255.0
                            : p.data_bits > 0 ? (1 << p.data_bits) - 1.0
                                              : 65535.0;
  const double level_scale = full_scale / 255.0;
  const int depth = p.bit_depth == 16 ? CV_16U : CV_8U;
  cv::RNG noise_rng(static_cast<uint64_t>(FrameRng(p.seed, frame_index, 2)()));
  std::vector<cv::Mat> planes;
  for (const cv::Mat& r : radiance) {
    cv::Mat noisy = r * level_scale;
    if (p.noise_sigma > 0) {
      cv::Mat noise(noisy.size(), CV_64F);
      noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, p.noise_sigma * level_scale);
      noisy += noise;
    }
    planes.emplace_back();
    noisy.convertTo(planes.back(), depth);  // rounds and saturates
  }
  cv::Mat image;
  if (nc == 3) {
    cv::merge(planes, image);
  } else {
    image = planes[0];
  }
  if (truth_out) *truth_out = truth;
  return image;
}

std::string TruthToJson(const SceneParams& p, const std::vector<FrameTruth>& truth) {
  nlohmann::ordered_json j;
  j["scene"] = {
      {"width_px", p.width_px},
      {"height_px", p.height_px},
      {"scale_um_per_px", p.scale_um_per_px},
      {"strand_width_um", p.strand_width_um},
      {"tip_x_px", p.tip_x_px},
      {"tip_y_px", p.tip_y_px},
      {"tilt_deg", p.tilt_deg},
      {"blur_sigma_px", p.blur_sigma_px},
      {"noise_sigma", p.noise_sigma},
      {"background_level", p.background_level},
      {"strand_level", p.strand_level},
      {"nozzle_level", p.nozzle_level},
      {"bed_level", p.bed_level},
      {"gradient_fraction", p.gradient_fraction},
      {"gradient_angle_deg", p.gradient_angle_deg},
      {"highlight", p.highlight},
      {"bed", p.bed},
      {"bed_gap_um", p.bed_gap_um},
      {"sway_deg", p.sway_deg},
      {"width_jitter_um", p.width_jitter_um},
      {"surface_texture_amplitude", p.surface_texture_amplitude},
      {"feed_speed_mm_s", p.feed_speed_mm_s},
      {"frame_rate_hz", p.frame_rate_hz},
      {"drive_gear", p.drive_gear},
      {"gear_centre_px", {p.gear_centre_x_px, p.gear_centre_y_px}},
      {"gear_radius_px", p.gear_radius_px},
      {"gear_teeth", p.gear_teeth},
      {"gear_surface_speed_mm_s", p.gear_surface_speed_mm_s},
      {"knurl_px", {p.knurl_depth_px, p.knurl_pitch_px, p.knurl_start_px}},
      {"target", RenderTargetName(p.target)},
      {"edge_bias_px", p.edge_bias_px},
      {"pitch_um", p.pitch_um},
      {"line_width_um", p.line_width_um},
      {"tick_length_um", p.tick_length_um},
      {"numerals", p.numerals},
      {"dust", {p.dust_specks, p.dust_fibres}},
      {"colour", p.colour},
      {"nozzle", p.nozzle},
      {"strand", p.strand},
      {"texture_amplitude", p.texture_amplitude},
      {"texture_wavelength_px", p.texture_wavelength_px},
      {"clutter_discs", p.clutter_discs},
      {"clutter_gears", p.clutter_gears},
      {"shading_ambient", p.shading_ambient},
      {"clear_strand", p.clear_strand},
      {"vignetting", p.vignetting},
      {"strand_tint", {p.strand_tint[0], p.strand_tint[1], p.strand_tint[2]}},
      {"background_tint", {p.background_tint[0], p.background_tint[1], p.background_tint[2]}},
      {"bit_depth", p.bit_depth},
      {"data_bits", p.data_bits},
      {"seed", p.seed},
  };
  auto frames = nlohmann::ordered_json::array();
  for (const auto& t : truth) {
    frames.push_back({{"frame", t.frame},
                      {"width_um", t.width_um},
                      {"width_px", t.width_px},
                      {"angle_deg", t.angle_deg},
                      {"tip_x_px", t.tip_x_px},
                      {"tip_y_px", t.tip_y_px},
                      {"time_s", t.time_s},
                      {"feed_offset_px", t.feed_offset_px},
                      {"gear_angle_rad", t.gear_angle_rad}});
  }
  j["frames"] = frames;
  return j.dump(2) + "\n";
}

std::vector<FrameTruth> RenderSequence(const SceneParams& p, int frame_count, double fps,
                                       const std::string& out_path, const std::string& truth_path) {
  std::string why;
  if (!p.Validate(&why)) throw std::invalid_argument("scene: " + why);
  if (frame_count < 1) throw std::invalid_argument("--frames: must be at least 1");
  SceneParams timed = p;  // the motion follows the sequence's own frame rate
  timed.frame_rate_hz = fps;
  namespace fs = std::filesystem;
  std::vector<FrameTruth> truth;
  const vision::VideoKind kind = vision::VideoKindForPath(out_path);
  if (kind != vision::VideoKind::kNone) {
    if (p.bit_depth != 8)
      throw std::invalid_argument(out_path + ": video output needs bit_depth 8");
    vision::VideoFileWriter writer(out_path, kind, fps, cv::Size(p.width_px, p.height_px));
    for (int i = 0; i < frame_count; ++i) {
      FrameTruth t;
      writer.Write(RenderFrame(timed, i, &t));
      truth.push_back(t);
    }
    writer.Commit();
  } else {
    std::error_code ec;
    fs::create_directories(out_path, ec);
    if (ec || !fs::is_directory(out_path))
      throw std::invalid_argument(out_path + ": cannot create output directory");
    for (int i = 0; i < frame_count; ++i) {
      FrameTruth t;
      cv::Mat img = RenderFrame(timed, i, &t);
      std::string name = (fs::path(out_path) / fmt::format("frame_{:06d}.png", i)).string();
      vision::WriteImageAtomically(name, img);
      truth.push_back(t);
    }
  }
  if (!truth_path.empty()) WriteFileAtomically(truth_path, TruthToJson(timed, truth));
  return truth;
}

}  // namespace clogscope::synthetic
