#include "pipeline/measure_inputs.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/provenance.h"
#include "pipeline/band.h"
#include "pipeline/experiment.h"
#include "pipeline/frame_overlays.h"
#include "pipeline/frame_rows.h"
#include "pipeline/speed_summary.h"
#include "vision/io/encoder_note.h"
#include "vision/io/video_io.h"
#include "vision/scene/batch.h"

namespace clogscope::pipeline {
namespace {

namespace fs = std::filesystem;

constexpr int kVideoOverlayEvery = 25;  // --overlay-every's default for a video

}  // namespace

const std::vector<std::string>& FrameCsvColumns() { return FrameColumns(); }

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

bool MeasureInputsOptions::Validate(std::string* why) const {
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

void MeasureInputsOptions::ResolveBand() {
  if (scale_um_per_px && !(*scale_um_per_px > 0 && std::isfinite(*scale_um_per_px))) {
    throw std::invalid_argument(
        fmt::format("--scale-um-per-px {}: must be a positive number", *scale_um_per_px));
  }
  if (scale_um_per_px && calibration) {
    throw std::invalid_argument("give either --scale-um-per-px or --calib, not both");
  }
  ApplyBandPx(band, Conversion(), &strand);
}

std::optional<calib::ScaleCalibration> MeasureInputsOptions::Conversion() const {
  if (calibration) return calibration;
  if (scale_um_per_px) return PlainScale(*scale_um_per_px);
  return std::nullopt;
}

bool MeasureInputsOptions::WritesToStdout() const {
  return out_frames.empty() || out_frames == "-";
}

MeasureSummary MeasureInputs(MeasureInputsOptions o, std::ostream* table_out) {
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
  if (!table_out && !o.WritesToStdout()) file.emplace(o.out_frames, /*keep_partial=*/true);
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
    std::vector<FrameRow> rows;
    std::optional<OverlayWriter> overlays;
    if (!o.overlay_dir.empty())
      overlays.emplace(o.overlay_dir, from_video, o.flag_outliers, conv, &overlay_names);
    if (const std::string advice = vision::X264EdgeAdvice(source->encoder()); !advice.empty())
      spdlog::warn("{}: {}", input, advice);
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
    const FeedSpeedSummary speeds = o.feed_speed ? SummariseSpeeds(rows) : FeedSpeedSummary{};
    int valid = 0;
    for (size_t i = 0; i < rows.size(); ++i) {
      const FrameRow& r = rows[i];
      valid += r.m.valid();
      std::vector<std::string> fields = FrameFields(r.source, r.frame, r.time_s, r.m, conv);
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
                 WidthSummary(rows, conv) + (o.feed_speed ? SpeedSummary(speeds, *conv) : "") +
                     (o.gear_roi ? GearSummary(rows, speeds, *conv, *o.gear_radius_mm) : ""));
    if (const std::string part = StraightPartSummary(rows); !part.empty())
      spdlog::info("{}: {}", input, part);
    if (o.feed_speed) {
      WarnOncePerReason(input, "without a feed speed", rows, [&](const FrameRow& r) {
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
      WarnOncePerReason(input, "without a gear speed", rows, [](const FrameRow& r) {
        if (r.gear.valid || r.gear.reason == vision::SpeedReason::kFirstFrame) return Skipped();
        return std::make_pair(std::string(vision::SpeedReasonName(r.gear.reason)), r.gear.detail);
      });
    }
    if (valid < static_cast<int>(rows.size())) {
      // Say why, once per reason, so a user sees the cause without opening the CSV.
      std::map<std::string, std::pair<int, std::string>> reasons;  // count, first detail
      for (const FrameRow& r : rows) {
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

}  // namespace clogscope::pipeline
