#include "synthetic/adversarial.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <stdexcept>

#include "common/angle.h"
#include "synthetic/adversarial_optics.h"
#include "synthetic/synthetic_extras.h"
#include "synthetic/x264_clip.h"
#include "vision/io/image_codec.h"
#include "vision/io/video_decoder.h"

namespace clogscope::synthetic {
namespace {

constexpr int kOversample = 3;  // hi-res samples per pixel along each axis

double Clamp01(double v) { return std::clamp(v, 0.0, 1.0); }

// The strand's shape along its axis s (px below the tip): half width and the axis's offset.
struct StrandShape {
  double half_px, swell, swell_len_px, bend_s_px, bend_k;
  double Half(double s) const {
    return swell == 1 ? half_px : half_px * (1 + (swell - 1) * std::exp(-s / swell_len_px));
  }
  double Centre(double s) const {
    return s > bend_s_px ? bend_k * (s - bend_s_px) * (s - bend_s_px) : 0.0;
  }
};

// A normalised box kernel of `length_px` (hi-res px) along (dx, dy), sampled finely and spread
// bilinearly: symmetric about its centre, so it blurs without shifting.
cv::Mat LineKernel(double length_px, double dx, double dy) {
  const int half = static_cast<int>(std::ceil(0.5 * length_px)) + 1;
  cv::Mat k = cv::Mat::zeros(2 * half + 1, 2 * half + 1, CV_32F);
  const int steps = std::max(8, static_cast<int>(8 * length_px));
  for (int i = 0; i <= steps; ++i) {
    const double t = (i / static_cast<double>(steps) - 0.5) * length_px;
    const double x = half + t * dx, y = half + t * dy;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    k.at<float>(y0, x0) += static_cast<float>((1 - fx) * (1 - fy));
    k.at<float>(y0, x0 + 1) += static_cast<float>(fx * (1 - fy));
    k.at<float>(y0 + 1, x0) += static_cast<float>((1 - fx) * fy);
    k.at<float>(y0 + 1, x0 + 1) += static_cast<float>(fx * fy);
  }
  return k / cv::sum(k)[0];
}

// The scene's objects at hi-res: how much of the background shows (τ) and what the objects add
// (e, 8-bit grey levels), both anti-aliased by signed distance.
void RenderLayers(const AdversarialScene& p, cv::Mat* tau, cv::Mat* emit) {
  const int F = kOversample;
  tau->create(p.height_px * F, p.width_px * F, CV_32F);
  emit->create(p.height_px * F, p.width_px * F, CV_32F);
  const double th = p.tilt_deg * kDegToRad;
  const double dx = std::sin(th), dy = std::cos(th);  // down the axis
  const double nx = dy, ny = -dx;                     // across it
  const StrandShape shape{0.5 * p.width_um / p.scale_um_per_px, p.swell_ratio,
                          p.swell_length_um / p.scale_um_per_px,
                          p.bend_start_um / p.scale_um_per_px, p.bend_curvature_per_px};
  const double half_tip = 0.5 * p.nozzle_tip_um / p.scale_um_per_px;
  const double tan_phi = std::tan(p.nozzle_half_angle_deg * kDegToRad);
  const double cos_phi = std::cos(p.nozzle_half_angle_deg * kDegToRad);
  const double hair_half = 0.5 * p.hair_um / p.scale_um_per_px;
  const double hair_tan = std::tan(p.hair_slant_deg * kDegToRad);
  const double hair_cos = std::cos(p.hair_slant_deg * kDegToRad);
  const auto cover = [&](double sd_px) { return Clamp01(0.5 + sd_px * F); };
  cv::parallel_for_(cv::Range(0, tau->rows), [&](const cv::Range& rows) {
    for (int Y = rows.start; Y < rows.end; ++Y) {
      float* t_row = tau->ptr<float>(Y);
      float* e_row = emit->ptr<float>(Y);
      const double y = (Y + 0.5) / F - 0.5 - p.tip_y_px;
      for (int X = 0; X < tau->cols; ++X) {
        const double x = (X + 0.5) / F - 0.5 - p.tip_x_px;
        const double s = x * dx + y * dy, u = x * nx + y * ny;
        double t = 1, e = 0;
        const auto over = [&](double a, double obj_tau, double obj_emit) {
          t = t * (1 - a) + a * obj_tau;
          e = e * (1 - a) + a * obj_emit;
        };
        if (p.strand && s > -1.0) {
          const double h = shape.Half(std::max(s, 0.0)), c = shape.Centre(s);
          const double a = cover(std::min(h - std::abs(u - c), s));
          if (a > 0) {
            const double xr = (u - c) / h;
            double obj_tau = 0, obj_emit = 0;
            if (p.lens) {
              obj_tau = LensTransmission(xr, p.lens_index, p.lens_acceptance_rad, p.lens_rim_floor);
            } else {
              obj_emit = StrandEmission(p, xr);
            }
            if (p.stripe_gain != 0) {
              const double sc = p.stripe_offset * 2 * h, sh = p.stripe_width * h;
              obj_emit += p.stripe_gain * cover(sh - std::abs(u - c - sc));
            }
            over(a, obj_tau, obj_emit);
          }
        }
        if (p.hair_um > 0 && (!p.hair_attached || s > -1.0)) {
          const double uh = p.hair_offset_px + std::max(s, 0.0) * hair_tan;
          double sd = (hair_half - std::abs(u - uh)) * hair_cos;
          if (p.hair_attached) sd = std::min(sd, s);
          const double a = cover(sd);
          if (a > 0) over(a, 0, p.hair_level);
        }
        if (s < 1.0) {
          const double sd = std::min(-s, (half_tip - s * tan_phi - std::abs(u)) * cos_phi);
          const double a = cover(sd);
          if (a > 0) over(a, 0, p.nozzle_level);
        }
        t_row[X] = static_cast<float>(t);
        e_row[X] = static_cast<float>(e);
      }
    }
  });
}

// Blur (depth of field, motion) and pixel averaging of one hi-res layer.
cv::Mat Optics(const AdversarialScene& p, const cv::Mat& hires) {
  const int F = kOversample;
  cv::Mat src = hires;
  if (p.motion_blur_px > 0) {
    // Before the Gaussian (both are convolutions, which commute; only the frame's edges differ).
    const double th = p.tilt_deg * kDegToRad;
    cv::filter2D(hires, src, -1, LineKernel(p.motion_blur_px * F, std::sin(th), std::cos(th)),
                 cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  }
  if (p.blur_sigma_bottom_px <= 0) return BlurAndBin(src, F, p.blur_sigma_px * F);
  // Blur growing down the frame from the tip: two blurs blended row by row.
  std::vector<float> bottom(src.rows);
  for (int Y = 0; Y < src.rows; ++Y) {
    const double y = (Y + 0.5) / F - 0.5;
    bottom[Y] =
        static_cast<float>(Clamp01((y - p.tip_y_px) / std::max(1.0, p.height_px - 1 - p.tip_y_px)));
  }
  return BlurAndBin(src, F, p.blur_sigma_px * F, p.blur_sigma_bottom_px * F, bottom);
}

// The lit background at pixel resolution: level, slope, texture and a lamp's reflection.
cv::Mat Background(const AdversarialScene& p) {
  cv::Mat bg(p.height_px, p.width_px, CV_32F);
  std::mt19937_64 rng(p.seed * 31 + 7);
  std::uniform_real_distribution<double> uni(0, 1);
  std::vector<render::PlaneWaves::Wave> waves;
  for (int i = 0; i < 6; ++i) {
    const double ang = 2 * M_PI * uni(rng), k = 2 * M_PI / (60 + 300 * uni(rng));
    waves.push_back({k * std::cos(ang), k * std::sin(ang), 2 * M_PI * uni(rng),
                     p.background_texture / std::sqrt(3.0)});
  }
  const render::PlaneWaves texture(waves, p.width_px, p.height_px);
  for (int y = 0; y < bg.rows; ++y) {
    float* row = bg.ptr<float>(y);
    for (int x = 0; x < bg.cols; ++x) {
      double v =
          p.background_level * (1 + p.background_slope * (x - 0.5 * p.width_px) / p.width_px) +
          texture.At(x, y);
      if (p.spot_level != 0) {
        const double r2 =
            (x - p.spot_x_px) * (x - p.spot_x_px) + (y - p.spot_y_px) * (y - p.spot_y_px);
        v += p.spot_level * std::exp(-0.5 * r2 / (p.spot_sigma_px * p.spot_sigma_px));
      }
      row[x] = static_cast<float>(std::max(0.0, v));
    }
  }
  return bg;
}

cv::Mat Quantise(const cv::Mat& radiance, double noise_sigma, cv::RNG& rng) {
  // Read noise plus shot noise growing with the signal (NoiseVariance, per pixel).
  cv::Mat noise(radiance.size(), CV_32FC(radiance.channels()));
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::Mat sigma;
  cv::sqrt(kReadShare + radiance / 255.0, sigma);
  cv::Mat noisy = radiance + noise.mul(sigma) * (noise_sigma / std::sqrt(kReadShare + 1.0));
  cv::Mat out;
  noisy.convertTo(out, CV_8U);  // rounds and clips at 0 and 255
  return out;
}

cv::Mat BayerRoundTrip(const cv::Mat& bgr) {
  // An RGGB-family mosaic (OpenCV's "BG" names the 2×2 pattern's second row), then OpenCV's
  // bilinear demosaic: the colour fringes of a cheap colour camera.
  cv::Mat mosaic(bgr.size(), CV_8U);
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b v = bgr.at<cv::Vec3b>(y, x);
      const int c = (y % 2 == 0) ? (x % 2 == 0 ? 2 : 1) : (x % 2 == 0 ? 1 : 0);
      mosaic.at<uint8_t>(y, x) = v[c];
    }
  }
  cv::Mat out;
  cv::cvtColor(mosaic, out, cv::COLOR_BayerBG2BGR);
  return out;
}

}  // namespace

const char* TroubleClassName(TroubleClass c) {
  switch (c) {
    case TroubleClass::kPlain:
      return "plain";
    case TroubleClass::kSpecularStripe:
      return "specular stripe";
    case TroubleClass::kBacklitLens:
      return "backlit lens";
    case TroubleClass::kStringer:
      return "stringer";
    case TroubleClass::kDieSwell:
      return "die swell";
    case TroubleClass::kSaturated:
      return "saturated";
    case TroubleClass::kBayer:
      return "bayer colour";
    case TroubleClass::kBend:
      return "bend below band";
    case TroubleClass::kBackgroundSpot:
      return "background spot";
    case TroubleClass::kBlurGradient:
      return "blur gradient";
    case TroubleClass::kMotionBlur:
      return "motion blur";
    case TroubleClass::kNoStrand:
      return "no strand";
  }
  return "?";
}

const char* CodecName(Codec c) {
  switch (c) {
    case Codec::kPng:
      return "png";
    case Codec::kJpeg:
      return "jpeg";
    case Codec::kH264:
      return "h264";
  }
  return "?";
}

AdversarialScene RandomAdversarialScene(TroubleClass trouble, uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9e3779b97f4a7c15ull + static_cast<uint64_t>(trouble) * 977 + 3);
  std::uniform_real_distribution<double> u01(0, 1);
  const auto uni = [&](double a, double b) { return a + (b - a) * u01(rng); };
  AdversarialScene p;
  p.trouble = trouble;
  p.seed = seed;
  static const int kSizes[4][2] = {{640, 480}, {800, 600}, {1024, 768}, {1280, 720}};
  const int size = static_cast<int>(uni(0, 3.999));
  p.width_px = kSizes[size][0];
  p.height_px = kSizes[size][1];
  p.scale_um_per_px = uni(2, 6);
  p.width_um = uni(150, 600);
  // Keep the strand within reason for the frame: 20 px up to 40 % of its width.
  p.width_um = std::clamp(p.width_um, 20 * p.scale_um_per_px, 0.4 * p.width_px * p.scale_um_per_px);
  p.tilt_deg = uni(-20, 20);
  p.blur_sigma_px = uni(0.5, 3);
  p.noise_sigma = uni(1, 12);
  const double codec = u01(rng);
  p.codec = codec < 0.3 ? Codec::kPng : codec < 0.7 ? Codec::kJpeg : Codec::kH264;
  p.jpeg_quality = static_cast<int>(uni(40, 95));
  p.tip_x_px = p.width_px * uni(0.35, 0.65);
  p.tip_y_px = p.height_px * uni(0.12, 0.35);
  const bool lit = u01(rng) < 0.5;
  if (lit) {
    p.background_level = uni(10, 90);
    p.strand_level = uni(p.background_level + 40, 245);
    if (u01(rng) < 0.5) p.shading_ambient = uni(0.3, 1);
  } else {
    p.background_level = uni(150, 245);
    p.strand_level = uni(5, p.background_level - 40);
  }
  p.nozzle_level = uni(0, 255);
  p.background_slope = uni(-0.3, 0.3);
  p.background_texture = uni(0, 15);
  double widest_um = p.width_um;

  switch (trouble) {
    case TroubleClass::kPlain:
    case TroubleClass::kNoStrand:
      p.strand = trouble != TroubleClass::kNoStrand;
      break;
    case TroubleClass::kSpecularStripe: {
      // A glossy strand under a lamp: darker than the background (or lit), a brighter stripe
      // of any contrast, up to saturation.
      if (u01(rng) < 0.6) {
        p.background_level = uni(90, 240);
        p.strand_level = uni(5, p.background_level - 40);
        p.shading_ambient = 1;
      }
      p.stripe_width = uni(0.05, 0.3);
      const double room = 0.48 - 0.5 * p.stripe_width;
      p.stripe_offset = uni(-room, room);
      p.stripe_gain = uni(10, 300 - p.strand_level);
      break;
    }
    case TroubleClass::kBacklitLens:
      p.lens = true;
      p.background_level = uni(140, 245);
      p.lens_index = uni(1.4, 1.6);
      p.lens_acceptance_rad = uni(0.12, 0.35);
      p.lens_rim_floor = uni(0.03, 0.3);
      p.nozzle_level = uni(5, 60);
      break;
    case TroubleClass::kStringer: {
      p.hair_um = uni(10, 50);
      const double hair_px = std::max(1.2, p.hair_um / p.scale_um_per_px);
      p.hair_um = hair_px * p.scale_um_per_px;
      const double side = u01(rng) < 0.5 ? -1 : 1;
      const double w_px = p.width_um / p.scale_um_per_px;
      p.hair_offset_px = side * (0.5 * w_px + uni(0.2, 3.0) * w_px);
      p.hair_slant_deg = uni(-8, 8);
      p.hair_attached = u01(rng) < 0.6;
      p.hair_level = p.strand_level + uni(-20, 20);
      if (u01(rng) < 0.5) p.nozzle_level = p.background_level + uni(-6, 6);
      break;
    }
    case TroubleClass::kDieSwell:
      p.swell_ratio = uni(1.1, 1.5);
      // Relaxing over a fraction of a diameter (~100 µm for a 400 µm strand).
      p.swell_length_um = std::max(20.0, uni(0.1, 0.4) * p.width_um);
      widest_um = p.width_um * p.swell_ratio;
      break;
    case TroubleClass::kSaturated:
      p.strand_level = lit ? uni(260, 400) : p.strand_level;
      if (!lit) p.background_level = uni(260, 400);
      if (p.codec == Codec::kPng) p.codec = Codec::kJpeg;
      break;
    case TroubleClass::kBayer:
      p.colour = true;
      break;
    case TroubleClass::kBend: {
      const double band_end_um = kBandStartUm + kBandLengthUm;
      p.bend_start_um = band_end_um + uni(0.5, 2.0) * p.width_um;
      p.bend_curvature_per_px = (u01(rng) < 0.5 ? -1 : 1) * uni(0.001, 0.01);
      break;
    }
    case TroubleClass::kBackgroundSpot: {
      const double w_px = p.width_um / p.scale_um_per_px;
      const double s = (kBandStartUm + 0.5 * kBandLengthUm) / p.scale_um_per_px + uni(-30, 30);
      const double u = (u01(rng) < 0.5 ? -1 : 1) * (0.5 * w_px + uni(-5, 25));
      const double th = p.tilt_deg * kDegToRad;
      p.spot_x_px = p.tip_x_px + s * std::sin(th) + u * std::cos(th);
      p.spot_y_px = p.tip_y_px + s * std::cos(th) - u * std::sin(th);
      p.spot_sigma_px = uni(4, 40);
      p.spot_level = uni(20, 150) * (u01(rng) < 0.7 ? 1 : -0.5);
      break;
    }
    case TroubleClass::kBlurGradient:
      p.blur_sigma_bottom_px = p.blur_sigma_px + uni(1.5, 4);
      break;
    case TroubleClass::kMotionBlur:
      p.motion_blur_px = uni(3, 20);
      break;
  }
  p.nozzle_tip_um = widest_um * uni(1.3, 2.5);
  p.nozzle_half_angle_deg = uni(20, 50);
  // A shaded strand is lit from the camera's side (a ring light) in half the scenes, else by a
  // lamp up to 45° off to one side, its far rim dark out to the terminator. From a stream of its
  // own, so that every other draw of a seed's scene stays as it was before the lamp was added.
  if (p.strand && !p.lens && p.shading_ambient < 1) {
    std::mt19937_64 lamp(seed * 0x51ed27ull + static_cast<uint64_t>(trouble) * 31 + 7);
    std::uniform_real_distribution<double> lamp01(0, 1);
    if (lamp01(lamp) < 0.5) p.light_deg = -45 + 90 * lamp01(lamp);
  }
  return p;
}

std::vector<cv::Mat> RenderAdversarial(const AdversarialScene& p, int frames,
                                       const std::string& temp_dir, AdversarialTruth* truth,
                                       ClipFacts* clip) {
  if (frames < 1) throw std::invalid_argument("adversarial render: need at least one frame");
  if (clip) *clip = ClipFacts{};
  cv::Mat tau_hi, emit_hi;
  RenderLayers(p, &tau_hi, &emit_hi);
  const cv::Mat tau = Optics(p, tau_hi), emit = Optics(p, emit_hi);
  tau_hi.release();
  emit_hi.release();
  const cv::Mat bg = Background(p);
  std::vector<cv::Mat> planes;
  const int nc = p.colour ? 3 : 1;
  for (int c = 0; c < nc; ++c) {
    const double tb = p.colour ? kBackgroundTint[c] : 1.0, ts = p.colour ? kStrandTint[c] : 1.0;
    planes.push_back(bg.mul(tau) * tb + emit * ts);
  }
  cv::Mat radiance;
  cv::merge(planes, radiance);

  cv::RNG rng(p.seed * 7919 + 1);
  std::vector<cv::Mat> out;
  for (int i = 0; i < frames; ++i) {
    cv::Mat img = Quantise(radiance, p.noise_sigma, rng);
    if (p.colour) img = BayerRoundTrip(img);
    if (p.codec == Codec::kJpeg) {
      std::string why;
      img = vision::DecodeImage(vision::EncodeImage(".jpg", img, p.jpeg_quality), &why);
      if (img.empty()) throw std::runtime_error("JPEG round trip: " + why);
    }
    out.push_back(img);
  }
  if (p.codec == Codec::kH264) {
    namespace fs = std::filesystem;
    const fs::path dir =
        fs::path(temp_dir) / fmt::format("adversarial_{}_{}", p.seed, static_cast<int>(p.trouble));
    const std::string path = EncodeX264Clip(out, dir, "round_trip.mp4", 25);
    if (clip) clip->encoder = vision::ReadX264Settings(path);
    // Read back as `measure` reads a video: the decoder's luma plane, as stored.
    vision::VideoDecoder decoder(path);
    for (cv::Mat& f : out) {
      vision::DecodedFrame decoded;
      if (!decoder.Read(&decoded) || decoded.grey.empty())
        throw std::runtime_error(path + ": H.264 round trip lost a frame");
      f = std::move(decoded.grey);
      if (clip) clip->luma_range = decoded.luma_range;
    }
    std::error_code ec;
    fs::remove_all(dir, ec);
  }

  if (truth) {
    *truth = AdversarialTruth{};
    truth->strand = p.strand;
    truth->tip_x_px = p.tip_x_px;
    truth->tip_y_px = p.tip_y_px;
    const StrandShape shape{0.5 * p.width_um / p.scale_um_per_px, p.swell_ratio,
                            p.swell_length_um / p.scale_um_per_px, 0, 0};
    const double s0 = kBandStartUm / p.scale_um_per_px, len = kBandLengthUm / p.scale_um_per_px;
    double sum = 0;
    const int n = 400;
    for (int i = 0; i < n; ++i) sum += 2 * shape.Half(s0 + len * (i + 0.5) / n);
    truth->width_px = p.strand ? sum / n : 0;
    truth->swell_ratio = p.strand ? 2 * shape.Half(0) / truth->width_px : 1;
  }
  return out;
}

std::string Describe(const AdversarialScene& p) {
  std::string extra;
  switch (p.trouble) {
    case TroubleClass::kSpecularStripe:
      extra = fmt::format(" stripe gain {:.0f} at {:+.2f} w, {:.2f} w wide", p.stripe_gain,
                          p.stripe_offset, p.stripe_width);
      break;
    case TroubleClass::kBacklitLens:
      extra = fmt::format(" n {:.2f}, acceptance {:.2f} rad, rim floor {:.2f}", p.lens_index,
                          p.lens_acceptance_rad, p.lens_rim_floor);
      break;
    case TroubleClass::kStringer:
      extra = fmt::format(" hair {:.0f} µm at {:+.0f} px, {:+.1f}°, {}, nozzle {:.0f}", p.hair_um,
                          p.hair_offset_px, p.hair_slant_deg,
                          p.hair_attached ? "attached" : "from above", p.nozzle_level);
      break;
    case TroubleClass::kDieSwell:
      extra = fmt::format(" swell {:.2f} over {:.0f} µm", p.swell_ratio, p.swell_length_um);
      break;
    case TroubleClass::kBend:
      extra = fmt::format(" bend from {:.0f} µm, k {:.4f}/px", p.bend_start_um,
                          p.bend_curvature_per_px);
      break;
    case TroubleClass::kBackgroundSpot:
      extra = fmt::format(" spot {:+.0f} σ {:.0f} px at ({:.0f},{:.0f})", p.spot_level,
                          p.spot_sigma_px, p.spot_x_px, p.spot_y_px);
      break;
    case TroubleClass::kBlurGradient:
      extra = fmt::format(" blur to {:.1f} px", p.blur_sigma_bottom_px);
      break;
    case TroubleClass::kMotionBlur:
      extra = fmt::format(" motion {:.1f} px", p.motion_blur_px);
      break;
    default:
      break;
  }
  if (p.light_deg != 0) extra += fmt::format(" light {:+.0f}°", p.light_deg);
  return fmt::format(
      "{} seed {}: {}x{} {} {:.2f} µm/px, {:.0f} µm ({:.1f} px), tilt {:+.1f}°, blur {:.1f}, noise "
      "{:.1f}, bg {:.0f} (slope {:+.2f}, texture {:.1f}) strand {:.0f} ambient {:.2f} nozzle "
      "{:.0f}{}",
      TroubleClassName(p.trouble), p.seed, p.width_px, p.height_px,
      p.codec == Codec::kJpeg ? fmt::format("jpeg q{}", p.jpeg_quality) : CodecName(p.codec),
      p.scale_um_per_px, p.width_um, p.width_um / p.scale_um_per_px, p.tilt_deg, p.blur_sigma_px,
      p.noise_sigma, p.background_level, p.background_slope, p.background_texture, p.strand_level,
      p.shading_ambient, p.nozzle_level, extra);
}

}  // namespace clogscope::synthetic
