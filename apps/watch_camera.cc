#include "apps/watch_camera.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <stdexcept>

#include "model/prediction_run.h"
#include "vision/io/live_source.h"

namespace clogscope::apps {

CameraWatch::CameraWatch(const WatchCommandOptions& options, std::string printer,
                         std::function<void(const watch::PrinterEvent&)> on_printer)
    : printer_(std::move(printer)), tag_(printer_.empty() ? "" : printer_ + ": ") {
  pipeline::MeasureInputsOptions m = options.measure;
  m.ResolveBand();
  live_ = options.live;
  live_.printer = printer_;
  std::string why;
  // The printer first: its options checked, then (with no source) its webcam is the source.
  if (!options.printer.Validate(&why)) throw std::invalid_argument(why);
  if (live_.source.empty() && options.printer.moonraker_url.empty())
    throw std::invalid_argument(
        "no source: a device, stream URL, video file or folder (or --moonraker to watch its "
        "webcam)");
  live_.strand = m.strand;
  live_.conversion = m.Conversion();
  if (!options.extruder.empty()) {
    live_.extruder = model::LoadExtruderWithOverrides(options.extruder, options.set);
    live_.temperature_c =
        options.temperature_c.value_or(live_.extruder->Get(model::Param::kReferenceTemperatureC));
  } else if (options.temperature_c || !options.set.empty()) {
    throw std::invalid_argument("--temperature-c and --set go with --extruder");
  }
  if (options.printer.enabled()) {
    // Its lines come from its own thread: the tag is copied, nothing of this object captured.
    const std::string tag = tag_;
    watch::PrinterLink::Log log{[tag](const std::string& s) { spdlog::info("{}{}", tag, s); },
                                [tag](const std::string& s) { spdlog::warn("{}{}", tag, s); }};
    link_.emplace(options.printer, log, std::move(on_printer));
    // A farm's printer may be off when the farm starts: its webcam is asked for as the camera
    // starts (and again while it cannot be), not here, where it would stop every camera.
    webcam_from_printer_ = live_.source.empty() && !printer_.empty();
    if (live_.source.empty() && !webcam_from_printer_) live_.source = link_->WebcamSource();
  }
  if (webcam_from_printer_) {
    watch::LiveWatchOptions checked = live_;
    checked.source = "the printer's webcam";  // the rest of the options checked now
    if (!checked.Validate(&why)) throw std::invalid_argument(why);
  } else if (!live_.Validate(&why)) {
    throw std::invalid_argument(why);
  }
  frames_ = std::make_shared<watch::OverlayJpegCache>(&board_, live_.conversion);
  log_ = std::make_unique<LineLog>(options.log_path);
  if (!options.on_alert.empty()) alert_.emplace(options.on_alert, printer_);
}

CameraWatch::~CameraWatch() = default;

watch::WatchSnapshot CameraWatch::PublishEnded() {
  watch::WatchSnapshot s = board_.Read();
  s.status.source_up = false;
  board_.PublishState(s.status, s.clog, s.counters);
  return s;
}

bool CameraWatch::StartMayBeRetried() const {
  if (webcam_from_printer_) return true;
  const vision::SourceKind kind = vision::LiveSourceKindOf(live_.source);
  return kind == vision::SourceKind::kStream || kind == vision::SourceKind::kDevice;
}

WatchReport CameraWatch::Run(
    std::atomic<bool>* stop,
    std::function<void(const watch::WatchStatus&, const std::optional<watch::ClogIndex>&)>
        on_report,
    std::function<void(const watch::WatchStatus&)> on_level_change) {
  if (webcam_from_printer_) live_.source = link_->WebcamSource();
  WatchReport report;
  watch::LiveWatchEvents events;
  std::string last_line;
  events.on_line = [&](const std::string& line) {
    log_->Write(line);
    last_line = line;
  };
  events.on_report = [&](const std::string&, const watch::WatchStatus& s,
                         const std::optional<watch::ClogIndex>& clog) {
    if (on_report) on_report(s, clog);
  };
  // The printer link follows every state: a pause, a retry or the end of a hold-off is decided on
  // the watch's clock as it goes, not at the next status report.
  events.on_state = [&](const watch::WatchStatus& s) {
    if (link_) link_->Update(s);
  };
  events.on_level_change = [&](const watch::WatchStatus& s,
                               const std::optional<watch::ClogIndex>& clog) {
    spdlog::log(s.level == watch::WatchLevel::kOk ? spdlog::level::info : spdlog::level::warn,
                "{}{:.1f} s: {} → {}: {}", tag_, s.time_s, watch::WatchLevelName(s.previous_level),
                watch::WatchLevelName(s.level), s.reason);
    if (alert_) {
      std::string no_start;
      if (!alert_->Run(s, clog, live_.source, last_line, &no_start)) {
        spdlog::error("{}{}", tag_, no_start);
        report.alert_failures.push_back(no_start);
      }
      for (const std::string& f : alert_->Reap()) {
        spdlog::warn("{}{}", tag_, f);
        report.alert_failures.push_back(f);
      }
    }
    if (on_level_change) on_level_change(s);
  };
  events.on_warning = [&](const std::string& message) { spdlog::warn("{}{}", tag_, message); };
  report.summary = watch::RunLiveWatch(live_, events, &board_, stop);
  if (alert_) {
    for (const std::string& f : alert_->Reap(/*wait=*/true)) {
      spdlog::warn("{}{}", tag_, f);
      report.alert_failures.push_back(f);
    }
  }
  return report;
}

}  // namespace clogscope::apps
