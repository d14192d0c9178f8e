#include "apps/measure_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>
#include <tuple>

#include "apps/cli_util.h"
#include "apps/measure_options.h"
#include "apps/measure_overlays.h"
#include "apps/measure_rows.h"
#include "apps/run_command.h"
#include "calib/calibration_file.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/provenance.h"
#include "pipeline/band.h"
#include "pipeline/statistics.h"
#include "vision/io/video_io.h"
#include "vision/scene/batch.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

constexpr int kVideoOverlayEvery = 25;  // --overlay-every's default for a video

bool WritesToStdout(const MeasureCommandOptions& o) {
  return o.out_frames.empty() || o.out_frames == "-";
}

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

const std::vector<std::string>& FrameCsvColumns() { return pipeline::FrameColumns(); }

const std::vector<std::string>& GearCsvColumns() {
  static const std::vector<std::string> kColumns = {"gear_speed_mm_s", "gear_speed_sigma_mm_s",
                                                    "gear_reason", "slip_pct", "slip_sigma_pct"};
  return kColumns;
}

const std::vector<std::string>& FeedSpeedCsvColumns() {
  static const std::vector<std::string> kColumns = {
      "filament_speed_mm_s", "filament_speed_sigma_mm_s",
      "speed_reason",        "speed_baseline_frames",
      "speed_used",          "speed_left_out"};
  return kColumns;
}

bool MeasureCommandOptions::Validate(std::string* why) const {
  if (inputs.empty())
    *why = "no input given";
  else if (scale_um_per_px && !(*scale_um_per_px > 0 && std::isfinite(*scale_um_per_px)))
    *why = fmt::format("--scale-um-per-px {}: must be a positive number", *scale_um_per_px);
  else if (overlay_every < 0)
    *why = "--overlay-every must not be negative";
  else if (feed_speed && strand.target != vision::MeasureTarget::kFilament)
    *why = "--speed measures a moving filament: add --target filament";
  else if (feed_speed && !scale_um_per_px && !calibration)
    *why = "--speed needs a pixel scale to give mm/s: --scale-um-per-px or --calib";
  else if (feed_speed && !feed.Validate(why))
    return false;
  else if (gear_roi && !feed_speed)
    *why = "--gear-roi goes with --speed (the slip compares the two speeds)";
  else if (gear_roi && !gear_radius_mm)
    *why = "--gear-roi needs --gear-radius-mm (the gear's radius where it grips the filament)";
  else if (gear_radius_mm && !gear_roi)
    *why = "--gear-radius-mm needs --gear-roi (where the gear is in the frame)";
  else if (gear_radius_mm && !(*gear_radius_mm > 0 && *gear_radius_mm < 1000))
    *why = fmt::format("--gear-radius-mm {:g}: must be in (0, 1000) mm", *gear_radius_mm);
  else if (!strand.Validate(why))
    return false;
  else
    return true;
  return false;
}

void MeasureCommandOptions::ResolveBand() {
  if (scale_um_per_px && !(*scale_um_per_px > 0 && std::isfinite(*scale_um_per_px))) {
    throw std::invalid_argument(
        fmt::format("--scale-um-per-px {}: must be a positive number", *scale_um_per_px));
  }
  if (scale_um_per_px && calibration) {
    throw std::invalid_argument("give either --scale-um-per-px or --calib, not both");
  }
  pipeline::ApplyBandPx(band, Conversion(), &strand);
}

std::optional<calib::ScaleCalibration> MeasureCommandOptions::Conversion() const {
  if (calibration) return calibration;
  if (scale_um_per_px) return pipeline::PlainScale(*scale_um_per_px);
  return std::nullopt;
}

MeasureSummary MeasureInputs(MeasureCommandOptions o, std::ostream* table_out) {
  o.ResolveBand();
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  if (!o.overlay_dir.empty()) {
    std::error_code ec;
    fs::create_directories(o.overlay_dir, ec);
    if (ec || !fs::is_directory(o.overlay_dir))
      throw std::invalid_argument(o.overlay_dir + ": cannot create overlay directory");
  }
  MeasureSummary summary;
  std::set<std::string> overlay_names;
  const auto t0 = std::chrono::steady_clock::now();
  // Rows go to "<out>.partial" as each input completes, so an interrupted run keeps what it did;
  // without a file, to standard output (the log goes to standard error).
  std::optional<AtomicTextFile> file;
  if (!table_out && !WritesToStdout(o)) file.emplace(o.out_frames, /*keep_partial=*/true);
  std::ostream& table = table_out ? *table_out : file ? file->stream() : std::cout;
  const std::optional<calib::ScaleCalibration> conv = o.Conversion();
  table << ProvenanceCsvComment(CurrentProvenance());
  if (o.calibration) {
    table << fmt::format(
        "# calibration {}: scale {:.6f} ± {:.6f} µm/px, edge bias {:+.4f} ± {:.4f} px\n",
        o.calibration->method, o.calibration->scale_um_per_px, o.calibration->scale_sigma_um_per_px,
        o.calibration->edge_bias_px, o.calibration->edge_bias_sigma_px);
  }
  std::vector<std::string> columns = FrameCsvColumns();
  if (o.feed_speed)
    columns.insert(columns.end(), FeedSpeedCsvColumns().begin(), FeedSpeedCsvColumns().end());
  if (o.gear_roi) columns.insert(columns.end(), GearCsvColumns().begin(), GearCsvColumns().end());
  vision::GearSpeedOptions gear_options;
  if (o.gear_roi) {
    gear_options.roi = *o.gear_roi;
    gear_options.centre_px = o.gear_centre_px;
    gear_options.outer_radius_px = *o.gear_radius_mm * 1e3 / conv->scale_um_per_px;
    std::string why;
    if (!gear_options.Validate(&why)) throw std::invalid_argument("--gear-roi: " + why);
  }
  table << CsvLine(columns) << "\n";

  for (const std::string& input : o.inputs) {
    std::unique_ptr<vision::FrameSource> source;
    try {
      source = vision::FrameSource::Open(input);
    } catch (const std::invalid_argument& e) {
      spdlog::error("{}", e.what());
      summary.errors.push_back(e.what());
      ++summary.inputs_failed;
      continue;
    }
    std::error_code ec;
    const bool from_video = vision::IsVideoPath(input) && !fs::is_directory(input, ec);
    const int every = o.overlay_every > 0 ? o.overlay_every : (from_video ? kVideoOverlayEvery : 1);
    std::vector<Row> rows;
    std::optional<OverlayWriter> overlays;
    if (!o.overlay_dir.empty())
      overlays.emplace(o.overlay_dir, from_video, o.flag_outliers, conv, &overlay_names);
    const auto ts = std::chrono::steady_clock::now();
    vision::FeedSpeedTracker speed(o.feed);  // starts afresh with every input
    std::optional<vision::GearSpeedTracker> gear;
    if (o.gear_roi) gear.emplace(gear_options);
    try {
      vision::MeasureFrames(
          *source, o.strand, [&](vision::InputFrame& f, vision::StrandMeasurement& m) {
            vision::FeedSpeedSample v;
            if (o.feed_speed) v = speed.Next(f.image, f.time_s, m);
            vision::GearSpeedSample g;
            if (gear) g = gear->Next(f.image, f.time_s);
            rows.push_back({f.source, f.index, f.time_s, std::move(m), std::move(v), std::move(g)});
            if (!overlays) return;
            if (!f.image.empty() && f.index % every == 0) overlays->Add(rows.size() - 1, f.image);
            overlays->WriteReady(rows, /*all=*/false);
          });
    } catch (const std::exception& e) {
      // One input that cannot be measured (its frames smaller than the ROI, a library error) is
      // reported and skipped; the others and the table go on.
      const std::string why = fmt::format("{}: {}", input, e.what());
      spdlog::error("{}", why);
      summary.errors.push_back(why);
      ++summary.inputs_failed;
      continue;
    }
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - ts).count();
    if (o.flag_outliers) {
      std::vector<vision::StrandMeasurement> ms;
      ms.reserve(rows.size());
      for (auto& r : rows) ms.push_back(std::move(r.m));
      vision::FlagWidthOutliers(ms, vision::kWidthOutlierHalfWindow);
      for (size_t i = 0; i < rows.size(); ++i) rows[i].m = std::move(ms[i]);
    }
    // The rows' speeds are summarised before they are written, so each row can say whether the
    // logged mean used it.
    const pipeline::FeedSpeedSummary speeds =
        o.feed_speed ? SummariseSpeeds(rows) : pipeline::FeedSpeedSummary{};
    std::vector<double> widths_px;
    for (size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      if (r.m.valid()) widths_px.push_back(r.m.width_px);
      std::vector<std::string> fields =
          pipeline::FrameFields(r.source, r.frame, r.time_s, r.m, conv);
      if (o.feed_speed) {
        const auto sf = SpeedFields(r.speed, speeds, i, *conv);
        fields.insert(fields.end(), sf.begin(), sf.end());
      }
      if (o.gear_roi) {
        const GearAndSlip g = GearAndSlipOf(r, *conv, *o.gear_radius_mm);
        fields.insert(fields.end(), {CsvNumber(g.gear_mm_s, 5), CsvNumber(g.gear_sigma_mm_s, 5),
                                     r.gear.valid ? "" : vision::SpeedReasonName(r.gear.reason),
                                     CsvNumber(g.slip_pct, 3), CsvNumber(g.slip_sigma_pct, 3)});
      }
      table << CsvLine(fields) << "\n";
    }
    const int valid = static_cast<int>(widths_px.size());
    table.flush();
    if (overlays) {
      overlays->WriteReady(rows, /*all=*/true);
      summary.overlays_written += overlays->written();
      summary.overlay_frames_held_peak =
          std::max(summary.overlay_frames_held_peak, overlays->held_peak());
      if (!overlays->error().empty()) {
        spdlog::warn("overlays stopped: {}", overlays->error());
        summary.errors.push_back(overlays->error());
      }
    }
    ++summary.inputs_ok;
    summary.frames += static_cast<int>(rows.size());
    summary.valid_frames += valid;
    spdlog::info("{}: {} of {} frames valid ({:.0f} frames/s){}", input, valid, rows.size(),
                 rows.size() / std::max(secs, 1e-9),
                 WidthSummary(widths_px, conv) + (o.feed_speed ? SpeedSummary(speeds, *conv) : "") +
                     (o.gear_roi ? GearSummary(rows, speeds, *conv, *o.gear_radius_mm) : ""));
    if (const std::string part = StraightPartSummary(rows); !part.empty())
      spdlog::info("{}: {}", input, part);
    if (o.feed_speed) {
      WarnOncePerReason(input, "without a feed speed", rows, [&](const Row& r) {
        if (r.speed.valid || r.speed.reason == vision::SpeedReason::kFirstFrame) return Skipped();
        std::string detail = r.speed.detail;
        if (r.speed.reason == vision::SpeedReason::kTooFast) {
          detail +=
              fmt::format(" (faster than {:.2f} mm/s)",
                          r.speed.search_limit_px * conv->scale_um_per_px * 1e-3 / r.speed.dt_s);
        }
        return std::make_pair(std::string(vision::SpeedReasonName(r.speed.reason)), detail);
      });
    }
    if (o.gear_roi) {
      WarnOncePerReason(input, "without a gear speed", rows, [](const Row& r) {
        if (r.gear.valid || r.gear.reason == vision::SpeedReason::kFirstFrame) return Skipped();
        return std::make_pair(std::string(vision::SpeedReasonName(r.gear.reason)), r.gear.detail);
      });
    }
    if (valid < static_cast<int>(rows.size())) {
      // Say why, once per reason, so a user sees the cause without opening the CSV.
      std::map<std::string, std::pair<int, std::string>> reasons;  // count, first detail
      for (const Row& r : rows) {
        if (r.m.valid()) continue;
        auto& [count, detail] = reasons[vision::FrameStatusName(r.m.status)];
        if (count++ == 0) detail = r.m.detail;
      }
      for (const auto& [reason, info] : reasons) {
        spdlog::warn("{}: {} frame(s) {} (first: {})", input, info.first, reason, info.second);
      }
    }
  }
  if (file) file->Commit();
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return summary;
}

int RunMeasure(int argc, char** argv) {
  CLI::App app{"Measure the strand width in every frame of images, image directories or videos.",
               "clogscope measure"};
  MeasureCommandOptions o;
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
  const MeasureSummary s = MeasureInputs(o);
  // No input read: its error said it all; a line about an empty table would only add noise.
  if (s.inputs_ok > 0) {
    spdlog::info("{} of {} frames valid from {} input(s) in {:.2f} s; wrote {}", s.valid_frames,
                 s.frames, s.inputs_ok, s.seconds,
                 WritesToStdout(o) ? "the table to standard output" : o.out_frames);
  }
  if (s.valid_frames == 0) {
    spdlog::error("nothing could be measured{}", s.frames ? " (see the reason column)" : "");
    return 1;
  }
  return s.inputs_failed > 0 ? 2 : 0;
}

}  // namespace clogscope::apps
