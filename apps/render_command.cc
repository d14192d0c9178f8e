#include "apps/render_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "apps/cli_util.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/path_check.h"
#include "model/extrusion_lag.h"
#include "vision/io/video_io.h"

namespace clogscope::apps {

bool RenderCommandOptions::Validate(std::string* why) const {
  if (!scene.Validate(why)) return false;
  if (frames < 1)
    *why = "--frames must be at least 1";
  else if (!(fps > 0 && fps <= 1000))
    *why = "--fps must be in (0, 1000]";
  else if (out.empty())
    *why = "--out is required";
  else if (!lag_commanded.empty() && !(lag_k_s > 0))
    *why = "--lag-k-s must be positive";
  else if (!lag_commanded.empty() && !(lag_um_per_mm3_s > 0))
    *why = "--lag-um-per-mm3-s must be positive";
  else if (!(filament_diameter_mm > 0))
    *why = "--filament-diameter-mm must be positive";
  else if (!lag_commanded.empty() &&
           !CheckInputPath("--lag-commanded", lag_commanded, PathExpect::kFile, why))
    return false;
  else
    return true;
  return false;
}

std::string RenderToFiles(const RenderCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  namespace fs = std::filesystem;
  std::string truth = o.truth_path;
  if (truth.empty()) {
    if (vision::VideoKindForPath(o.out) != vision::VideoKind::kNone) {
      fs::path p(o.out);
      truth = (p.parent_path() / (p.stem().string() + ".truth.json")).string();
    } else {
      truth = (fs::path(o.out) / "truth.json").string();
    }
  }
  if (o.lag_commanded.empty()) {
    synthetic::SceneParams scene = o.scene;
    if (o.drop_pct != 0) {
      if (!o.scene.frame_width_um.empty() || !(o.drop_pct > -100 && o.drop_pct < 100))
        throw std::invalid_argument("--drop-pct: must be in (−100, 100) % (and without --lag-*)");
      for (int i = 0; i < o.frames; ++i) {
        scene.frame_width_um.push_back(scene.strand_width_um *
                                       (i / o.fps >= o.drop_at_s ? 1 + o.drop_pct / 100 : 1.0));
      }
    }
    synthetic::RenderSequence(scene, o.frames, o.fps, o.out, truth);
    return truth;
  }
  // The strand's width follows the lagged outlet flow at each frame's time (frame i at i / fps).
  const model::FlowProfile profile =
      model::ReadFlowProfile(o.lag_commanded, o.lag_profile_form, o.filament_diameter_mm);
  std::vector<double> times;
  for (int i = 0; i < o.frames; ++i) times.push_back(i / o.fps);
  const auto flow = model::OutletFlow(profile, o.lag_k_s, 0.0, times);
  synthetic::SceneParams scene = o.scene;
  scene.frame_width_um.clear();
  for (size_t i = 0; i < flow.size(); ++i) {
    scene.frame_width_um.push_back(o.lag_um_per_mm3_s * flow[i]);
    if (!(scene.frame_width_um.back() > 0)) {
      throw std::invalid_argument(
          fmt::format("{}: the outlet flow at {:g} s is {:g} mm³/s; the strand would vanish",
                      o.lag_commanded, times[i], flow[i]));
    }
  }
  synthetic::RenderSequence(scene, o.frames, o.fps, o.out, truth);
  // The lag's truth next to the frames' own.
  auto j = nlohmann::ordered_json::parse(ReadFile(truth));
  j["lag"] = {{"k_s", o.lag_k_s},
              {"um_per_mm3_s", o.lag_um_per_mm3_s},
              {"commanded", o.lag_commanded},
              {"profile_time_s", profile.time_s},
              {"profile_flow_mm3_s", profile.flow_mm3_s},
              {"outlet_flow_mm3_s", flow}};
  WriteFileAtomically(truth, j.dump(2) + "\n");
  return truth;
}

int RunRender(int argc, char** argv) {
  CLI::App app{
      "Render synthetic side-view frames of a nozzle tip and strand with exact ground truth.",
      "clogscope render"};
  RenderCommandOptions o;
  synthetic::SceneParams& s = o.scene;
  bool silhouette = false;
  std::string target = "strand";
  app.add_option("--out", o.out,
                 "Output: a directory (PNG frames) or a .avi (MJPEG) / .mp4 (H.264) file")
      ->required();
  app.add_option("--truth", o.truth_path,
                 "Ground-truth JSON (default: DIR/truth.json or NAME.truth.json)");
  app.add_option("--target", target,
                 "strand (below a nozzle), pin (gauge across the frame) or micrometer")
      ->capture_default_str();
  app.add_option("--frames", o.frames, "Number of frames")->capture_default_str();
  app.add_option("--fps", o.fps, "Video frame rate")->capture_default_str();
  app.add_option(
      "--size",
      [&s](const CLI::results_t& r) { return ParseSize(r[0], &s.width_px, &s.height_px); },
      "Frame size WxH in px (default 1280x720)");
  app.add_option("--scale-um-per-px", s.scale_um_per_px, "Pixel scale")->capture_default_str();
  app.add_option("--strand-width-um", s.strand_width_um, "Strand width")->capture_default_str();
  app.add_option("--tip-x-px", s.tip_x_px, "Nozzle tip x")->capture_default_str();
  app.add_option("--tip-y-px", s.tip_y_px, "Nozzle tip y")->capture_default_str();
  app.add_option("--tilt-deg", s.tilt_deg,
                 "Scene and strand axis tilt (+: strand leans to +x going down)")
      ->capture_default_str();
  app.add_option("--blur-px", s.blur_sigma_px, "Gaussian PSF sigma")->capture_default_str();
  app.add_option("--noise", s.noise_sigma, "Sensor noise sigma, grey levels")
      ->capture_default_str();
  app.add_option("--background", s.background_level, "Background grey level")
      ->capture_default_str();
  app.add_option("--strand-level", s.strand_level, "Strand grey level")->capture_default_str();
  app.add_flag("--silhouette", silhouette, "Dark strand on a backlight (sets the grey levels)");
  app.add_flag("--highlight", s.highlight, "Add a specular highlight stripe inside the strand");
  app.add_option("--gradient", s.gradient_fraction,
                 "Illumination change across the frame diagonal (0.3 = 30 %)")
      ->capture_default_str();
  app.add_option("--gradient-angle-deg", s.gradient_angle_deg,
                 "Direction of the illumination gradient")
      ->capture_default_str();
  app.add_flag("--bed", s.bed, "Add a print bed below the tip");
  app.add_option("--bed-gap-um", s.bed_gap_um, "Bed distance below the tip")->capture_default_str();
  app.add_option("--sway-deg", s.sway_deg, "Per-frame sigma of the strand axis angle")
      ->capture_default_str();
  app.add_option("--width-jitter-um", s.width_jitter_um, "Per-frame sigma of the strand width")
      ->capture_default_str();
  app.add_option("--edge-bias-px", s.edge_bias_px,
                 "Objects appear this much wider than width/scale (the optics' edge bias)")
      ->capture_default_str();
  app.add_option("--pitch-um", s.pitch_um, "Micrometer line pitch")->capture_default_str();
  app.add_option("--line-width-um", s.line_width_um, "Micrometer line width")
      ->capture_default_str();
  app.add_option("--tick-length-um", s.tick_length_um,
                 "Micrometer: finite ticks this long, every 5th 1.5x and every 10th 2x (0: lines "
                 "across the frame)")
      ->capture_default_str();
  app.add_flag("--numerals", s.numerals, "Micrometer: numerals above the long ticks");
  app.add_option("--dust", s.dust_specks, "Micrometer: dust specks")->capture_default_str();
  app.add_option("--fibres", s.dust_fibres, "Micrometer: dust fibres")->capture_default_str();
  app.add_flag("--colour,--color", s.colour, "BGR frames with an orange tint");
  app.add_option("--bit-depth", s.bit_depth, "8 or 16 (PNG only)")->capture_default_str();
  app.add_option("--data-bits", s.data_bits,
                 "16 bit: the data's significant bits (12: values 0..4095; 0: all 16)")
      ->capture_default_str();
  app.add_option("--seed", s.seed, "Random seed")->capture_default_str();
  bool no_nozzle = false, no_strand = false;
  std::string strand_tint, background_tint;
  app.add_option("--nozzle-level", s.nozzle_level, "Nozzle grey level (0 black … 255 white)")
      ->capture_default_str();
  app.add_flag("--no-nozzle", no_nozzle, "No nozzle in view (a filament or needle)");
  app.add_flag("--no-strand", no_strand, "Nothing below the nozzle");
  app.add_option("--texture", s.texture_amplitude,
                 "Low-frequency background texture, ± grey levels");
  app.add_option("--discs", s.clutter_discs, "Discs beside and behind the strand");
  app.add_option("--gears", s.clutter_gears, "Gears beside and behind the strand");
  app.add_option("--shading-ambient", s.shading_ambient,
                 "Lambertian shading of a lit strand: ambient fraction (1 = flat)")
      ->capture_default_str();
  app.add_flag("--clear", s.clear_strand, "A clear strand with two bright internal lines");
  app.add_option("--vignetting", s.vignetting, "Relative darkening at the corners");
  app.add_option(
         "--surface-texture", s.surface_texture_amplitude,
         "Texture on the strand's surface along its axis, ± grey levels (a filament's marks)")
      ->capture_default_str();
  app.add_option("--feed-speed-mm-s", s.feed_speed_mm_s,
                 "The surface texture travels down the axis at this speed (frame i at i / fps)")
      ->capture_default_str();
  std::string drive_gear;
  app.add_option("--drive-gear", drive_gear,
                 "CX,CY,RADIUS_PX: a toothed drive gear beside the strand (behind it)");
  app.add_option("--gear-teeth", s.gear_teeth, "Teeth of the drive gear")->capture_default_str();
  app.add_option("--gear-surface-speed-mm-s", s.gear_surface_speed_mm_s,
                 "Surface speed at the gear's tip radius (+ clockwise)")
      ->capture_default_str();
  std::string knurl;
  app.add_option("--knurl", knurl,
                 "DEPTH,PITCH,START (px): knurl marks on the strand's left edge below START");
  std::string lag_form = "moves";
  app.add_option("--drop-pct", o.drop_pct,
                 "Clog sequence: the strand narrows by this % (negative) at --drop-at-s");
  app.add_option("--drop-at-s", o.drop_at_s, "When the strand narrows (frame time)");
  app.add_option("--purge-at-s", s.purge_start_s, "A purge blob hangs from the tip from then");
  app.add_option("--purge-s", s.purge_duration_s, "…for this long")->capture_default_str();
  app.add_option("--occlude-at-s", s.occlusion_start_s,
                 "Something passes in front of the strand at these times");
  app.add_option("--occlude-s", s.occlusion_duration_s, "…for this long each")
      ->capture_default_str();
  app.add_option("--lag-commanded", o.lag_commanded,
                 "Flow profile CSV (time_s, flow_mm3_s): the width follows its first-order lag");
  app.add_option("--lag-k-s", o.lag_k_s, "Lag K of the outlet flow")->capture_default_str();
  app.add_option("--lag-um-per-mm3-s", o.lag_um_per_mm3_s, "Strand width per unit outlet flow")
      ->capture_default_str();
  app.add_option("--lag-profile-form", lag_form, "moves or linear (see clogscope lag)")
      ->capture_default_str();
  app.add_option("--strand-tint", strand_tint, "With --colour: B,G,R gains of the strand");
  app.add_option("--background-tint", background_tint,
                 "With --colour: B,G,R gains of the background");
  app.footer(
      "Examples:\n"
      "  clogscope render --out frames/ --frames 10\n"
      "  clogscope render --out step.mp4 --frames 250 --strand-width-um 390.1 --width-jitter-um 2\n"
      "  clogscope render --out tilted/ --tilt-deg 15 --silhouette --highlight --gradient 0.3\n"
      "  clogscope render --out feed.avi --no-nozzle --scale-um-per-px 20 --strand-width-um 1750 "
      "--tip-y-px 0 --surface-texture 8 --feed-speed-mm-s 3 --fps 30 --frames 60 --drive-gear "
      "176,240,100 --gear-surface-speed-mm-s 3.3\n"
      "  clogscope render --out lag.avi --frames 200 --lag-commanded profile.csv --lag-k-s 0.1\n"
      "  clogscope render --target pin --strand-width-um 300 --edge-bias-px 0.4 --out pin300/\n"
      "  clogscope render --target micrometer --pitch-um 100 --tilt-deg 2 --silhouette --out "
      "micro/\n"
      "  clogscope render --target micrometer --pitch-um 10 --scale-um-per-px 0.5 --line-width-um "
      "2 --tick-length-um 80 --numerals --dust 12 --fibres 2 --bit-depth 16 --data-bits 12 "
      "--silhouette --out stage/");
  if (!ParseCommandLine(app, argc, argv)) return 0;  // --help printed
  s.target = synthetic::ParseRenderTarget(target);
  o.lag_profile_form = model::ParseProfileForm(lag_form);
  s.nozzle = !no_nozzle;
  s.strand = !no_strand;
  // Three comma-separated numbers ("B,G,R" gains, a gear's "CX,CY,RADIUS_PX"), each through the
  // shared number parser.
  const auto three = [](const std::string& text, const char* option, const char* expected,
                        double* out) {
    std::stringstream ss(text);
    std::string item;
    int c = 0;
    while (std::getline(ss, item, ',')) {
      if (c == 3) break;
      out[c++] = ParseNumberField(item, option, "value");
    }
    if (c != 3 || std::getline(ss, item))
      throw std::invalid_argument(std::string(option) + " '" + text + "': expected " + expected);
  };
  const auto tint = [&](const std::string& text, const char* option, double* out) {
    three(text, option, "B,G,R gains", out);
  };
  if (!strand_tint.empty()) tint(strand_tint, "--strand-tint", s.strand_tint);
  if (!drive_gear.empty()) {
    double g[3];
    three(drive_gear, "--drive-gear", "CX,CY,RADIUS_PX", g);
    s.drive_gear = true;
    s.gear_centre_x_px = g[0];
    s.gear_centre_y_px = g[1];
    s.gear_radius_px = g[2];
  }
  if (!knurl.empty()) {
    double k[3];
    three(knurl, "--knurl", "DEPTH,PITCH,START", k);
    s.knurl_depth_px = k[0];
    s.knurl_pitch_px = k[1];
    s.knurl_start_px = k[2];
  }
  if (!background_tint.empty()) tint(background_tint, "--background-tint", s.background_tint);
  if (silhouette) {
    const double bg = s.background_level, st = s.strand_level;
    s.SetSilhouette();
    // Explicit levels win over the preset.
    if (app.count("--background")) s.background_level = bg;
    if (app.count("--strand-level")) s.strand_level = st;
  }
  const std::string truth = RenderToFiles(o);
  spdlog::info("rendered {} frame(s) to {}; truth in {}", o.frames, o.out, truth);
  return 0;
}

}  // namespace clogscope::apps
