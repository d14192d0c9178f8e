#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "vision/io/data_range.h"
#include "vision/io/encoder_note.h"

namespace clogscope::synthetic {

// An adversarial renderer, written apart from synthetic/synthetic.cc (the world the measurement was
// tuned in) to judge the measurement on scenes it was not designed around. Every object is drawn
// as a shape at 3× resolution (anti-aliased by signed distance), blurred there, averaged down to
// pixels, lit, made noisy and passed through a camera's codec. Nothing here is used by the
// production measurement.

// The kinds of trouble a scene is built around (one per scene; every scene also draws a random
// camera: size, scale, tilt, blur, noise, codec).
enum class TroubleClass {
  kPlain,           // an opaque strand, lit (shaded or flat) or a silhouette
  kSpecularStripe,  // a brighter stripe anywhere inside a darker or lit strand
  kBacklitLens,     // a transparent strand on a backlight: dark rim, bright core (refraction)
  kStringer,        // a thin hair (10–50 µm) beside the strand; the nozzle often barely visible
  kDieSwell,        // the strand 10–50 % wider just below the tip, relaxing over ~30–150 µm
  kSaturated,       // the strand clipped at full scale before compression
  kBayer,           // a colour camera: Bayer mosaic and demosaicing
  kBend,            // the strand bends below the band
  kBackgroundSpot,  // a lamp's reflection in the background behind an edge
  kBlurGradient,    // depth of field: blur growing along the strand
  kMotionBlur,      // motion blur along the strand's axis
  kNoStrand,        // the nozzle alone: must never give a width
};
inline constexpr int kTroubleClassCount = 12;
const char* TroubleClassName(TroubleClass c);

enum class Codec { kPng, kJpeg, kH264 };
const char* CodecName(Codec c);

struct AdversarialScene {
  TroubleClass trouble = TroubleClass::kPlain;
  int width_px = 1280, height_px = 720;
  double scale_um_per_px = 3.0;
  double width_um = 400.0;  // strand far below the tip
  double tip_x_px = 640, tip_y_px = 200;
  double tilt_deg = 0;  // strand axis from image vertical, + toward +x going down
  double blur_sigma_px = 1.5;
  double blur_sigma_bottom_px = -1;  // > 0: blur grows linearly to this at the frame's bottom
  double motion_blur_px = 0;         // box length along the axis
  double noise_sigma = 3;            // grey levels, 8-bit scale
  double background_level = 40, background_slope = 0, background_texture = 0;
  double spot_level = 0, spot_sigma_px = 20, spot_x_px = 0, spot_y_px = 0;  // a lamp's reflection
  // Strand: opaque (level, shading ambient 1 = flat) or a transparent lens on the backlight.
  double strand_level = 200, shading_ambient = 1;
  // The lamp's direction across a shaded strand, from the camera's axis (+ toward +u): 0 lights
  // both rims alike; otherwise one rim is brighter and the other is at the ambient level out to
  // the terminator.
  double light_deg = 0;
  bool lens = false;
  double lens_index = 1.5, lens_acceptance_rad = 0.22, lens_rim_floor = 0.1;
  double stripe_gain = 0, stripe_offset = 0, stripe_width = 0.1;  // fractions of the width
  double swell_ratio = 1, swell_length_um = 80;           // w(s) = w (1 + (B − 1) e^(−s/λ))
  double bend_start_um = 1e9, bend_curvature_per_px = 0;  // axis offset k (s − s_b)² below s_b
  // Nozzle: a flat face nozzle_tip_um wide at the tip, flanks opening upward.
  double nozzle_level = 150, nozzle_tip_um = 800, nozzle_half_angle_deg = 35;
  bool strand = true;
  // A stringer: a hair beside the strand, from the nozzle's face (attached) or from above the
  // frame.
  double hair_um = 0, hair_offset_px = 0, hair_slant_deg = 0, hair_level = 0;
  bool hair_attached = true;
  double full_scale_level = 255;  // the camera clips radiance here (8-bit scale)
  bool colour = false;            // Bayer mosaic and demosaic
  Codec codec = Codec::kPng;
  int jpeg_quality = 90;
  uint64_t seed = 1;
};

// The reference band: 50 µm below the tip, 150 µm long.
inline constexpr double kBandStartUm = 50.0, kBandLengthUm = 150.0;

struct AdversarialTruth {
  bool strand = false;
  double width_px = 0;  // geometric width averaged over the band's rows
  double tip_x_px = 0, tip_y_px = 0;
  double swell_ratio = 1;  // widest width just below the tip over the band's mean width
};

// A random scene of the given class; the seed picks everything.
AdversarialScene RandomAdversarialScene(TroubleClass trouble, uint64_t seed);

// Renders `frames` frames of the scene (the same scene, independent noise), passed through its
// codec (an H.264 clip goes through a temporary file in `temp_dir`). 8-bit grey, or BGR.
// An H.264 clip is read back as `measure` reads a video: the decoder's luma plane as stored
// (16-235), so colour scenes come back grey. clip (optional): what `measure` knows of the frames
// besides their pixels.
struct ClipFacts {
  vision::X264Settings encoder;  // the settings x264 wrote into an H.264 clip (else not found)
  vision::LumaRange luma_range = vision::LumaRange::kFull;  // as the decoder says of the frames
};
std::vector<cv::Mat> RenderAdversarial(const AdversarialScene& scene, int frames,
                                       const std::string& temp_dir, AdversarialTruth* truth,
                                       ClipFacts* clip = nullptr);

// A one-line account of the scene, for tables and failures.
std::string Describe(const AdversarialScene& scene);

}  // namespace clogscope::synthetic
