#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vision/edges/polarity.h"

namespace clogscope::synthetic {

// What the scene shows: the strand below a nozzle, a calibration pin gauge (a cylinder across the
// whole frame, no nozzle), or a stage micrometer (parallel lines at a known pitch). (What the
// measurement looks for in a frame, strand or filament, is vision::MeasureTarget.)
enum class RenderTarget { kStrand, kPin, kMicrometer };
const char* RenderTargetName(RenderTarget t);
// Parses "strand", "pin" or "micrometer"; throws std::invalid_argument otherwise.
RenderTarget ParseRenderTarget(const std::string& name);

// A side view of a nozzle tip and the strand below it, with exactly known geometry.
//
// Image frame: x to the right, y down, pixel centres at integer coordinates. The scene is tilted by
// tilt_deg about the nozzle tip; the strand axis leans by tilt_deg (+ per-frame sway), positive
// when the strand moves to +x going down.
struct SceneParams {
  RenderTarget target = RenderTarget::kStrand;
  int width_px = 1280;
  int height_px = 720;
  double scale_um_per_px = 3.0;
  double strand_width_um = 400.0;
  double tip_x_px = 640.0;
  double tip_y_px = 240.0;
  double tilt_deg = 0.0;
  double blur_sigma_px = 1.5;      // Gaussian PSF
  double noise_sigma = 3.0;        // sensor noise, grey levels (8-bit scale)
  double background_level = 40.0;  // grey levels (8-bit scale)
  double strand_level = 200.0;
  double nozzle_level = 150.0;
  double bed_level = 120.0;
  // Illumination falls off linearly along gradient_angle_deg: the relative change across the frame
  // diagonal (0.3 = 30 % darker at one corner than at the other).
  double gradient_fraction = 0.0;
  double gradient_angle_deg = 0.0;
  // Glossy-melt highlight: a bright stripe inside the strand, parallel to its axis.
  bool highlight = false;
  double highlight_offset_fraction = -0.2;  // stripe centre from the axis, in strand widths
  double highlight_width_fraction = 0.12;   // stripe width, in strand widths
  double highlight_gain = 45.0;             // grey levels added at the stripe
  // Print bed (perpendicular to the scene axis) bed_gap_um below the tip; hides the strand below
  // it.
  bool bed = false;
  double bed_gap_um = 200.0;
  // Nozzle: a flat tip face nozzle_tip_width_um wide, flanks opening upward at the cone angle.
  double nozzle_tip_width_um = 1000.0;
  double nozzle_cone_half_angle_deg = 40.0;
  // Per-frame variation (standard deviations): strand axis angle and strand width.
  double sway_deg = 0.0;
  double width_jitter_um = 0.0;
  // A width schedule: when not empty, frame i's strand width is frame_width_um[i] (the last entry
  // for later frames) instead of strand_width_um, e.g. a strand following the flow's lag.
  std::vector<double> frame_width_um;
  // A moving filament: a surface texture along the strand (± grey levels, wavelengths 6–80 px)
  // that travels down the axis at feed_speed_mm_s; frame i is at time i / frame_rate_hz
  // (RenderSequence sets it from its fps).
  double surface_texture_amplitude = 0.0;
  double feed_speed_mm_s = 0.0;
  double frame_rate_hz = 25.0;
  // A drive gear turning beside the strand: centre, tip radius and teeth in px, its grey level, and
  // the surface speed at its tip radius (mm/s; + clockwise in the image, y down). Marks on its
  // face turn with it.
  bool drive_gear = false;
  double gear_centre_x_px = 0, gear_centre_y_px = 0;
  double gear_radius_px = 100;
  int gear_teeth = 20;
  double gear_tooth_depth_px = 6;
  double gear_level = 150;
  double gear_surface_speed_mm_s = 0;
  // A drive gear's knurl marks on the strand's left edge from knurl_start_px along the axis (below
  // the tip point) on: a saw tooth knurl_depth_px deep (a third pressed in, two thirds pushed
  // out), knurl_pitch_px long, moving with the feed. Rendered as a locally straight edge (exact
  // on the long flank, approximate at the steep one). Truth stays the unmarked width.
  double knurl_depth_px = 0;
  double knurl_pitch_px = 40;
  double knurl_start_px = 0;
  // The optics' edge bias: every object appears this many px wider than width/scale (blur,
  // diffraction, edge convention). Calibration fits it; 0 renders the geometric edge.
  double edge_bias_px = 0.0;
  // Stage micrometer (target kMicrometer): lines across the axis direction, centred on the tip
  // point. The pin (kPin) is strand_width_um wide along the axis through the tip point.
  double pitch_um = 100.0;
  double line_width_um = 8.0;
  // A real micrometer's marks (see render::MicrometerMarks): with tick_length_um > 0 the lines are
  // ticks ending on a common line tick_length_um below the tip point, short ones tick_length_um
  // long, every 5th 1.5× and every 10th 2× as long; numerals above the long ticks; dust specks and
  // fibres anywhere. Truth stays the ticks' lattice.
  double tick_length_um = 0;  // 0: lines across the whole frame
  bool numerals = false;      // needs tick_length_um
  int dust_specks = 0;
  int dust_fibres = 0;
  // Realism beyond the reference scene (truth stays the geometric width and tip):
  bool nozzle = true;              // false: no nozzle in view (a filament, a needle)
  bool strand = true;              // false: nothing below the nozzle (no-strand tests)
  double texture_amplitude = 0.0;  // low-frequency background texture, ± grey levels
  double texture_wavelength_px = 120.0;
  int clutter_discs = 0;  // opaque discs beside (and partly behind) the strand
  int clutter_gears = 0;  // gear-like discs with teeth
  // Lambertian shading of a front-lit strand: inside, strand_level·(a + (1 − a)·√(1 − (2u/w)²))
  // with a the ambient fraction; 1 = flat.
  double shading_ambient = 1.0;
  // A clear strand: two bright internal lines (refraction) at ±0.3 of the width from the axis.
  bool clear_strand = false;
  double clear_line_gain = 60.0;
  double vignetting = 0.0;  // relative darkening at the frame corners (radial, quadratic)
  bool colour = false;      // BGR output: orange strand (strand_tint) on background_tint
  double strand_tint[3] = {0.45, 0.75, 1.0};  // B, G, R gains (colour only)
  double background_tint[3] = {0.45, 0.75, 1.0};
  double nozzle_tint[3] = {0.45, 0.75, 1.0};
  int bit_depth = 8;  // 8 or 16
  // 16 bit only: the data's significant bits, as a 12-bit camera writes values 0..4095 into a
  // 16-bit file (grey levels then scale to 2^data_bits − 1); 0: all 16.
  int data_bits = 0;
  uint64_t seed = 1;
  // Live-watch events, by frame time (frame_index / frame_rate_hz): a purge blob of molten
  // plastic hanging from the tip (a disc at strand_level, purge_radius_px, its top at the tip) from
  // purge_start_s for purge_duration_s; occluders (a dark disc of three strand widths' radius over
  // the strand below the tip, as a tool or a hand passing) from each occlusion_start_s for
  // occlusion_duration_s. Negative start / empty list: none. Truth stays the strand's.
  double purge_start_s = -1, purge_duration_s = 2, purge_radius_px = 0;  // radius 0: 1.5 widths
  std::vector<double> occlusion_start_s;
  double occlusion_duration_s = 0.5;

  // True when the parameters make a renderable scene; otherwise says why.
  bool Validate(std::string* why) const;
  // Makes this a silhouette on a backlight (dark strand, nozzle and bed on a bright background).
  void SetSilhouette();
};

// A randomised scene far from the defaults, for robustness tests and benchmarks: a lit strand or a
// silhouette, tilt within ±20°, blur 0.8–3 px, a nozzle of any grey level (or none, one in five),
// background texture, discs and gears beside the strand, Lambertian shading (ambient ≥ 0.4) on
// lit strands, clear strands on backlights, a coloured strand on a coloured background, an
// illumination gradient, vignetting, highlights and beds. `seed` picks everything.
SceneParams RandomRealisticScene(uint64_t seed);

// Feedstock seen from the side, as in Greeff & Schilling's video: a 1.75 mm filament at 20 µm/px
// (87.5 px) running down a 640×480 frame through its centre, no nozzle, 30 frames/s, ±8 grey
// levels of surface texture moving at feed_speed_mm_s; with gear_surface_speed_mm_s, a 20-tooth
// drive gear of 2 mm tip radius (100 px, centre 176,240) turning beside it, its rim at the
// filament's left edge.
SceneParams FeedstockScene(double feed_speed_mm_s,
                           std::optional<double> gear_surface_speed_mm_s = std::nullopt);

// The exact geometry of one rendered frame.
struct FrameTruth {
  int frame = 0;
  double width_um = 0;   // physical width (strand or pin; the micrometer's line width)
  double width_px = 0;   // apparent width in the image: width_um / scale + edge bias
  double angle_deg = 0;  // strand axis angle, image frame
  double tip_x_px = 0;
  double tip_y_px = 0;
  double time_s = 0;          // frame_index / frame_rate_hz
  double feed_offset_px = 0;  // how far the surface has moved down the axis since frame 0
  double gear_angle_rad = 0;  // how far the drive gear has turned since frame 0 (+ clockwise)
};

// Renders frame `frame_index` of a sequence. The same params, seed and index give the same image.
// Throws std::invalid_argument when params do not validate.
cv::Mat RenderFrame(const SceneParams& params, int frame_index, FrameTruth* truth);

// The truth of frame `frame_index` without rendering it.
FrameTruth FrameTruthFor(const SceneParams& params, int frame_index);

// Writes `frame_count` frames: to a directory of PNGs (frame_000000.png …) when `out_path` has no
// video extension, or to a video: .avi (MJPEG) or .mp4 (H.264) through VideoFileWriter. Writes the
// truth as JSON to `truth_path` (atomically). Throws std::invalid_argument on bad paths/params.
std::vector<FrameTruth> RenderSequence(const SceneParams& params, int frame_count, double fps,
                                       const std::string& out_path, const std::string& truth_path);

// Ground truth as JSON text: the scene parameters and one entry per frame.
std::string TruthToJson(const SceneParams& params, const std::vector<FrameTruth>& truth);

}  // namespace clogscope::synthetic
