#include "vision/synthetic.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <random>
#include <stdexcept>

#include "common/atomic_file.h"
#include "vision/edge_profile.h"
#include "vision/video_io.h"

namespace clogscope::vision {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

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

const char* TargetName(Target t) {
  switch (t) {
    case Target::kStrand:
      return "strand";
    case Target::kPin:
      return "pin";
    case Target::kMicrometer:
      return "micrometer";
  }
  return "?";
}

Target ParseTarget(const std::string& name) {
  if (name == "strand") return Target::kStrand;
  if (name == "pin") return Target::kPin;
  if (name == "micrometer") return Target::kMicrometer;
  throw std::invalid_argument("target '" + name + "': expected strand, pin or micrometer");
}

const char* PolarityName(Polarity p) {
  switch (p) {
    case Polarity::kAuto:
      return "auto";
    case Polarity::kBrightOnDark:
      return "bright";
    case Polarity::kDarkOnBright:
      return "dark";
    case Polarity::kMixed:
      return "mixed";
  }
  return "?";
}

Polarity ParsePolarity(const std::string& name) {
  if (name == "auto") return Polarity::kAuto;
  if (name == "bright") return Polarity::kBrightOnDark;
  if (name == "dark") return Polarity::kDarkOnBright;
  throw std::invalid_argument("polarity '" + name + "': expected auto, bright or dark");
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
  if (target == Target::kStrand && nozzle_tip_width_um <= strand_width_um)
    return fail("nozzle_tip_width_um must exceed strand_width_um");
  if (!(nozzle_cone_half_angle_deg > 0 && nozzle_cone_half_angle_deg < 85))
    return fail("nozzle_cone_half_angle_deg must be in (0, 85)");
  if (bed && !(bed_gap_um > 0)) return fail("bed_gap_um must be positive");
  if (std::abs(gradient_fraction) >= 1) return fail("gradient_fraction must be within (-1, 1)");
  if (bit_depth != 8 && bit_depth != 16) return fail("bit_depth must be 8 or 16");
  if (std::abs(edge_bias_px) > 10) return fail("edge_bias_px must be within ±10 px");
  if (target == Target::kMicrometer) {
    if (!(line_width_um > 0)) return fail("line_width_um must be positive");
    if (!(pitch_um > 2 * line_width_um)) return fail("pitch_um must exceed twice the line width");
    if (pitch_um / scale_um_per_px < 4) return fail("micrometer lines closer than 4 px");
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

FrameTruth FrameTruthFor(const SceneParams& p, int frame_index) {
  FrameTruth t;
  t.frame = frame_index;
  auto rng = FrameRng(p.seed, frame_index, 1);
  std::normal_distribution<double> normal(0.0, 1.0);
  double sway = normal(rng) * p.sway_deg;
  double jitter = normal(rng) * p.width_jitter_um;
  t.width_um = p.strand_width_um + jitter;
  if (p.target == Target::kMicrometer) t.width_um = p.line_width_um;
  t.width_px = t.width_um / p.scale_um_per_px + p.edge_bias_px;
  t.angle_deg = p.tilt_deg + sway;
  t.tip_x_px = p.tip_x_px;
  t.tip_y_px = p.tip_y_px;
  return t;
}

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

  cv::Mat radiance(p.height_px, p.width_px, CV_64F);
  // Rows are independent: render them on all cores.
  cv::parallel_for_(cv::Range(0, p.height_px), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y) {
      double* row = radiance.ptr<double>(y);
      for (int x = 0; x < p.width_px; ++x) {
        const Vec2 d{x - p.tip_x_px, y - p.tip_y_px};
        double v;
        if (p.target == Target::kMicrometer) {
          // The nearest lines only: they are at least 4 px apart and the reach of one is 9 sigma.
          const double u = Dot(n_strand, d);
          const long k0 = std::lround(u / pitch_px);
          double cov = 0;
          for (long k = k0 - 2; k <= k0 + 2; ++k) {
            const double c = k * pitch_px;
            cov += PixelMeanOfBlurredStep(u - c + 0.5 * w, sigma, n_strand.x, n_strand.y) -
                   PixelMeanOfBlurredStep(u - c - 0.5 * w, sigma, n_strand.x, n_strand.y);
          }
          v = p.background_level + (p.strand_level - p.background_level) * cov;
        } else {
          const double cov = strand_left.Eval(d, sigma) - strand_right.Eval(d, sigma);
          v = p.background_level + (p.strand_level - p.background_level) * cov;
          if (p.highlight)
            v += p.highlight_gain * (hl_left.Eval(d, sigma) - hl_right.Eval(d, sigma));
        }
        if (p.target == Target::kStrand) {
          if (p.bed) {
            const double a = bed.Eval(d, sigma);
            v = v * (1 - a) + p.bed_level * a;
          }
          // The product of three soft half-planes is exact away from the two flank corners, which
          // lie far from the measurement band.
          double a = nozzle_face.Eval(d, sigma);
          if (a > 0) a *= nozzle_right.Eval(d, sigma) * nozzle_left.Eval(d, sigma);
          v = v * (1 - a) + p.nozzle_level * a;
        }
        if (p.gradient_fraction != 0) {
          const Vec2 c{x - centre.x, y - centre.y};
          v *= 1.0 - p.gradient_fraction * Dot(c, g_dir) / diag;
        }
        row[x] = v;
      }
    }
  });

  const double full_scale = p.bit_depth == 16 ? 65535.0 : 255.0;
  const double level_scale = full_scale / 255.0;
  const int depth = p.bit_depth == 16 ? CV_16U : CV_8U;
  cv::RNG noise_rng(static_cast<uint64_t>(FrameRng(p.seed, frame_index, 2)()));
  auto to_image = [&](const cv::Mat& plane_radiance) {
    cv::Mat noisy = plane_radiance * level_scale;
    if (p.noise_sigma > 0) {
      cv::Mat noise(noisy.size(), CV_64F);
      noise_rng.fill(noise, cv::RNG::NORMAL, 0.0, p.noise_sigma * level_scale);
      noisy += noise;
    }
    cv::Mat out;
    noisy.convertTo(out, depth);  // rounds and saturates
    return out;
  };
  cv::Mat image;
  if (p.colour) {
    // Orange PLA under white light: the red channel carries most of the signal.
    const double tint[3] = {0.45, 0.75, 1.0};  // B, G, R
    std::vector<cv::Mat> planes;
    for (double t : tint) planes.push_back(to_image(radiance * t));
    cv::merge(planes, image);
  } else {
    image = to_image(radiance);
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
      {"target", TargetName(p.target)},
      {"edge_bias_px", p.edge_bias_px},
      {"pitch_um", p.pitch_um},
      {"line_width_um", p.line_width_um},
      {"colour", p.colour},
      {"bit_depth", p.bit_depth},
      {"seed", p.seed},
  };
  auto frames = nlohmann::ordered_json::array();
  for (const auto& t : truth) {
    frames.push_back({{"frame", t.frame},
                      {"width_um", t.width_um},
                      {"width_px", t.width_px},
                      {"angle_deg", t.angle_deg},
                      {"tip_x_px", t.tip_x_px},
                      {"tip_y_px", t.tip_y_px}});
  }
  j["frames"] = frames;
  return j.dump(2) + "\n";
}

std::vector<FrameTruth> RenderSequence(const SceneParams& p, int frame_count, double fps,
                                       const std::string& out_path, const std::string& truth_path) {
  std::string why;
  if (!p.Validate(&why)) throw std::invalid_argument("scene: " + why);
  if (frame_count < 1) throw std::invalid_argument("--frames: must be at least 1");
  namespace fs = std::filesystem;
  std::vector<FrameTruth> truth;
  const VideoKind kind = VideoKindForPath(out_path);
  if (kind != VideoKind::kNone) {
    if (p.bit_depth != 8)
      throw std::invalid_argument(out_path + ": video output needs bit_depth 8");
    VideoFileWriter writer(out_path, kind, fps, cv::Size(p.width_px, p.height_px));
    for (int i = 0; i < frame_count; ++i) {
      FrameTruth t;
      writer.Write(RenderFrame(p, i, &t));
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
      cv::Mat img = RenderFrame(p, i, &t);
      std::string name = (fs::path(out_path) / fmt::format("frame_{:06d}.png", i)).string();
      WriteImageAtomically(name, img);
      truth.push_back(t);
    }
  }
  if (!truth_path.empty()) WriteFileAtomically(truth_path, TruthToJson(p, truth));
  return truth;
}

}  // namespace clogscope::vision
