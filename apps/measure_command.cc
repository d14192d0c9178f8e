#include "apps/measure_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <map>
#include <stdexcept>
#include <string>

#include "apps/cli_util.h"
#include "apps/measure_options.h"
#include "apps/run_command.h"
#include "pipeline/band.h"
#include "pipeline/measure_inputs.h"

namespace clogscope::apps {
namespace {

// The options of the two modes that do not go with the other, and why; an option in neither list
// goes with both.
const std::map<std::string, std::string>& ManifestOnlyOptions() {
  static const std::map<std::string, std::string> kOptions = {
      {"--out", "the folder for a manifest's tables (use --out-frames for inputs)"},
      {"--samples", "frames per step of a manifest"},
      {"--jobs", "steps of a manifest measured at once"},
      {"--resume", "keeps the steps of a manifest measured before"}};
  return kOptions;
}
const std::map<std::string, std::string>& InputsOnlyOptions() {
  static const std::string kSpeed = "speeds of a manifest's steps come from its feedstock: block";
  static const std::map<std::string, std::string> kOptions = {
      {"--out-frames", "a manifest's tables go to --out"},
      {"--overlay-every", "a manifest's overlays are three sampled frames per step"},
      {"--no-outlier-flags", "a manifest's steps leave outliers out by their MAD"},
      {"--speed", kSpeed},
      {"--gear-roi", kSpeed},
      {"--gear-centre", kSpeed},
      {"--gear-radius-mm", kSpeed},
      {"--speed-max-shift-px", kSpeed},
      {"--speed-smooth-px", kSpeed}};
  return kOptions;
}

// Refuses, naming it, the first option given that does not go with the mode chosen.
void RefuseOtherModesOptions(const CLI::App& app, bool manifest) {
  const auto& other = manifest ? InputsOnlyOptions() : ManifestOnlyOptions();
  for (const CLI::Option* option : app.get_options()) {
    const auto it = other.find(option->get_name());
    if (option->count() == 0 || it == other.end()) continue;
    throw std::invalid_argument(fmt::format("{}: {} --manifest: {}", it->first,
                                            manifest ? "not with" : "only with", it->second));
  }
}

}  // namespace

int RunMeasure(int argc, char** argv) {
  CLI::App app{"Measure the strand width in every frame of images, image directories or videos.",
               "clogscope measure"};
  pipeline::MeasureInputsOptions o;
  bool no_outliers = false;
  pipeline::ManifestRunOptions exp;
  int samples = 0;
  app.add_option("inputs", o.inputs, "Images, directories of images, or video files");
  app.add_option("--manifest", exp.manifest,
                 "Step manifest (YAML or CSV): measure an experiment into --out");
  app.add_option("--out", exp.out_dir, "With --manifest: output folder for the tables");
  app.add_option("--samples", samples, "With --manifest: valid frames per step (default 50)");
  app.add_option("--jobs", exp.jobs,
                 "With --manifest: steps measured at once (default: all cores)");
  app.add_flag("--resume", exp.resume, "With --manifest: keep steps already measured in --out");
  MeasureCliText text;
  AddMeasurementOptions(app, &o, &text);
  app.add_option("--out-frames", o.out_frames,
                 "Per-frame CSV to write (inputs mode; default or '-': standard output)");
  app.add_option("--overlay", o.overlay_dir, "Directory for annotated PNGs");
  app.add_option("--overlay-every", o.overlay_every,
                 "Overlay every Nth frame (default: every image, every 25th video frame)");
  app.add_flag("--no-outlier-flags", no_outliers, "Do not mark width outliers between frames");
  app.add_flag("--speed", o.feed_speed,
               "With --target filament: feed speed from the surface texture between video "
               "frames (columns filament_speed_mm_s, filament_speed_sigma_mm_s, speed_reason, "
               "speed_baseline_frames, speed_used, speed_left_out; needs a scale)");
  std::string gear_roi, gear_centre;
  app.add_option("--gear-roi", gear_roi,
                 "With --speed: x,y,w,h around the drive gear: its surface speed and the slip");
  app.add_option("--gear-centre", gear_centre,
                 "x,y of the gear's axis (default: the ROI's centre)");
  app.add_option("--gear-radius-mm", o.gear_radius_mm,
                 "The gear's radius where it grips the filament (surface speed = ω·R)");
  app.add_option("--speed-max-shift-px", o.feed.max_shift_px,
                 "Largest movement per frame searched for --speed")
      ->capture_default_str();
  app.add_option("--speed-smooth-px", o.feed.smooth_sigma_px,
                 "Gaussian σ the texture profiles are smoothed with for --speed (more for blocky "
                 "MJPEG, less for a fine texture)")
      ->capture_default_str();
  app.footer(
      "Examples:\n"
      "  clogscope measure step1.mp4 --scale-um-per-px 3.0 --out-frames frames.csv\n"
      "  clogscope measure frames/ --out-frames frames.csv --overlay overlays/\n"
      "  clogscope measure step1.mp4 --calib calib.yaml --out-frames frames.csv\n"
      "  clogscope measure --manifest steps.yaml --calib calib.yaml --out results/\n"
      "  clogscope measure a.png b.png --roi 400,150,480,400 --polarity dark --out-frames f.csv\n"
      "  clogscope measure feed.avi --target filament --out-frames filament.csv\n"
      "  clogscope measure feed.avi --target filament > filament.csv\n"
      "  clogscope measure feed.avi --target filament --speed --scale-um-per-px 20.6 > feed.csv\n"
      "  clogscope measure feed.avi --target filament --speed --scale-um-per-px 20 --gear-roi "
      "70,134,213,213 --gear-radius-mm 2\n"
      "Exit status: 0 all inputs read, 2 some inputs unreadable, 1 nothing measured.");
  if (!ParseCommandLine(app, argc, argv)) return 0;  // --help printed
  const bool manifest = !exp.manifest.empty();
  RefuseOtherModesOptions(app, manifest);
  if (manifest && !o.inputs.empty())
    throw std::invalid_argument("give either inputs or --manifest, not both");
  if (!manifest && o.inputs.empty())
    throw std::invalid_argument("give inputs (images, directories, videos) or --manifest");
  // The gear's options are refused with --manifest above: these two read the inputs mode's.
  if (!gear_roi.empty()) {
    try {
      o.gear_roi = pipeline::ParseRoi(gear_roi);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument("--gear-roi '" + gear_roi + "': expected x,y,w,h");
    }
  }
  if (!gear_centre.empty())
    o.gear_centre_px = cv::Point2d(pipeline::ParsePoint(gear_centre, "--gear-centre"));
  // The measurement options, read once for both modes.
  ApplyMeasurementOptions(app, text, &o);
  if (manifest) {
    exp.scale_um_per_px = o.scale_um_per_px;
    exp.calib_path = text.calib_path;
    exp.strand = o.strand;
    exp.roi_given = !text.roi.empty();
    exp.polarity_given = app.count("--polarity") > 0;
    exp.target_given = app.count("--target") > 0;
    exp.band = o.band;
    exp.overlay_dir = o.overlay_dir;
    if (samples) exp.samples = samples;
    return RunExperimentCli(exp);
  }
  o.flag_outliers = !no_outliers;
  const pipeline::MeasureSummary s = pipeline::MeasureInputs(o);
  // No input read: its error said it all; a line about an empty table would only add noise.
  if (s.inputs_ok > 0) {
    spdlog::info("{} of {} frames valid from {} input(s) in {:.2f} s; wrote {}", s.valid_frames,
                 s.frames, s.inputs_ok, s.seconds,
                 o.WritesToStdout() ? "the table to standard output" : o.out_frames);
  }
  if (s.valid_frames == 0) {
    spdlog::error("nothing could be measured{}", s.frames ? " (see the reason column)" : "");
    return 1;
  }
  return s.inputs_failed > 0 ? 2 : 0;
}

}  // namespace clogscope::apps
