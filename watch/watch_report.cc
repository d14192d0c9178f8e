#include "watch/watch_report.h"

#include <fmt/format.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <vector>

#include "common/version.h"
#include "model/predictor.h"
#include "watch/json_number.h"

namespace clogscope::watch {
double RoundDecimals(double v, int digits) {
  const double f = std::pow(10.0, digits);
  return std::isfinite(v) ? std::round(v * f) / f : v;
}

std::optional<ClogIndex> ComputeClogIndex(const model::ExtruderParams& params, double temperature_c,
                                          const WatchStatus& s, std::string* why) {
  if (!s.has_scale || !s.baseline_ready || !s.has_diameter) {
    *why = !s.has_scale ? "needs a pixel scale" : "no baseline and diameter yet";
    return std::nullopt;
  }
  std::vector<model::StepInput> steps(2);
  steps[0].step = 0;
  steps[1].step = 1;
  steps[0].temperature_c = steps[1].temperature_c = temperature_c;
  steps[0].diameter_m = s.baseline_um * 1e-6;
  // The alert window's diameter: the state the alert levels judge.
  steps[1].diameter_m = (s.has_recent ? s.recent_diameter_um : s.diameter_um) * 1e-6;
  try {
    const model::Prediction p = model::Predict(params, steps, /*spectrum_points=*/3);
    ClogIndex c;
    c.temperature_c = temperature_c;
    c.back_pressure_ratio = p.steps[1].f_bp_n / p.steps[0].f_bp_n;
    c.vibration_increase_pct =
        100 * (p.steps[1].relative_amplitude / p.steps[0].relative_amplitude - 1);
    c.current_ma = p.steps[1].current_ma;
    return c;
  } catch (const std::invalid_argument& e) {
    *why = e.what();
    return std::nullopt;
  }
}

std::string StatusJson(const WatchStatus& s, const std::optional<ClogIndex>& clog,
                       const WatchCounters& c, const std::string& event) {
  nlohmann::json j;
  j["event"] = event;
  j["time_s"] = RoundDecimals(s.time_s, 3);
  j["level"] = WatchLevelName(s.level);
  j["previous_level"] = WatchLevelName(s.previous_level);
  j["level_since_s"] = RoundDecimals(s.level_since_s, 3);
  j["reason"] = s.reason;
  if (!c.printer.empty()) j["printer"] = c.printer;
  j["source"] = c.source;
  j["source_kind"] = c.source_kind;
  j["source_up"] = s.source_up;
  if (!c.http_url.empty()) j["http"] = c.http_url;
  j["window"] = {{"frames", s.frames},
                 {"valid_frames", s.valid_frames},
                 {"nozzle_only_frames", s.nozzle_only_frames},
                 {"valid_fraction", RoundDecimals(s.valid_fraction, 4)},
                 {"frame_rate_hz", RoundDecimals(s.frame_rate_hz, 3)}};
  nlohmann::json d;
  if (s.has_diameter) {
    d["px"] = RoundDecimals(s.diameter_px, 4);
    d["um"] = JsonNumber(s.diameter_um, 3);
    d["ci95_um"] = JsonNumber(s.diameter_ci95_um, 3);
    d["std_um"] = JsonNumber(s.diameter_std_um, 3);
    d["n_used"] = s.n_used;
    d["n_rejected"] = s.n_rejected;
    d["n_effective"] = RoundDecimals(s.n_effective, 1);
  }
  j["diameter"] = d;
  nlohmann::json b;
  if (s.baseline_ready) {
    b["source"] = s.baseline_source;
    b["px"] = RoundDecimals(s.baseline_px, 4);
    b["um"] = JsonNumber(s.baseline_um, 3);
    b["ci95_um"] = JsonNumber(s.baseline_ci95_um, 3);
  }
  j["baseline"] = b;
  nlohmann::json dr;
  if (s.baseline_ready && s.has_diameter) {
    dr["um"] = JsonNumber(s.drift_um, 3);
    dr["pct"] = RoundDecimals(s.drift_pct, 4);
    dr["ci95_pct"] = RoundDecimals(s.drift_ci95_pct, 4);
  }
  if (s.has_recent) {
    dr["recent_pct"] = RoundDecimals(s.recent_drift_pct, 4);
    dr["recent_ci95_pct"] = RoundDecimals(s.recent_drift_ci95_pct, 4);
    dr["recent_um"] = JsonNumber(s.recent_diameter_um, 3);
  }
  j["drift"] = dr;
  nlohmann::json ci;
  if (clog) {
    ci["temperature_c"] = clog->temperature_c;
    ci["back_pressure_ratio"] = RoundDecimals(clog->back_pressure_ratio, 5);
    ci["vibration_increase_pct"] = RoundDecimals(clog->vibration_increase_pct, 4);
    if (clog->current_ma) ci["motor_current_ma"] = RoundDecimals(*clog->current_ma, 3);
  }
  j["clog_index"] = ci;
  j["counters"] = {{"frames_total", c.frames_total},
                   {"frames_valid_total", c.frames_valid_total},
                   {"frames_refused_total", c.frames_refused_total},
                   {"frames_skipped_total", c.frames_skipped_total},
                   {"reconnects_total", c.reconnects_total},
                   {"level_changes", s.level_changes},  // every change: what --on-alert runs on
                   {"latency_median_ms", RoundDecimals(c.latency_median_ms, 3)},
                   {"latency_max_ms", RoundDecimals(c.latency_max_ms, 3)},
                   {"uptime_s", RoundDecimals(c.uptime_s, 3)}};
  // Text from outside (a source's name, a decoder's words) may not be UTF-8: replaced, never a
  // throw.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void LatencyHistogram::Add(double seconds) {
  for (size_t i = 0; i < bucket_counts.size(); ++i) {
    if (seconds <= kLatencyBucketsS[i]) {
      ++bucket_counts[i];
      break;
    }
  }
  ++count;
  sum_s += seconds;
}

namespace {

// Prometheus text grouped by metric family: each family's HELP and TYPE once, then its samples of
// every camera (promtool refuses a family split in two). Families come in the order first seen.
class Families {
 public:
  void Head(const std::string& name, const char* type, const char* help) {
    if (index_.emplace(name, families_.size()).second)
      families_.push_back(
          fmt::format("# HELP clogscope_{0} {1}\n# TYPE clogscope_{0} {2}\n", name, help, type));
  }
  // A sample of `family` (its head written first): clogscope_SERIES{LABELS} VALUE, the camera's
  // label first.
  void Sample(const std::string& family, const std::string& series, const std::string& labels,
              const std::string& value) {
    const std::string all = printer_.empty() ? labels
                            : labels.empty() ? printer_
                                             : printer_ + "," + labels;
    families_[index_.at(family)] +=
        fmt::format("clogscope_{}{} {}\n", series, all.empty() ? "" : "{" + all + "}", value);
  }
  void SetPrinter(const std::string& name) {
    printer_ = name.empty() ? "" : fmt::format("printer=\"{}\"", name);
  }
  std::string Text() const {
    std::string out;
    for (const std::string& f : families_) out += f;
    return out;
  }

 private:
  std::vector<std::string> families_;
  std::map<std::string, size_t> index_;
  std::string printer_;  // printer="NAME", or empty
};

void AddBuildInfo(Families* f) {
  f->Head("build_info", "gauge", "The watch's version, as labels; always 1.");
  f->Sample("build_info", "build_info", fmt::format("version=\"{}\"", kVersion), "1");
}

void AddSamples(const WatchStatus& s, const std::optional<ClogIndex>& clog, const WatchCounters& c,
                Families* f) {
  constexpr double kPerUm = 1e-6, kPerPct = 1e-2;  // µm → m, % → ratio
  const auto metric = [&](const char* name, const char* type, const char* help, double value) {
    if (!std::isfinite(value)) return;  // unknown: absent, as Prometheus expects
    f->Head(name, type, help);
    f->Sample(name, name, "", fmt::format("{}", value));
  };
  f->Head("level", "gauge", "1 for the current alert level, 0 for the others.");
  for (WatchLevel l : kWatchLevels) {
    f->Sample("level", "level", fmt::format("level=\"{}\"", WatchLevelName(l)),
              l == s.level ? "1" : "0");
  }
  metric("source_up", "gauge", "1 when the source delivers frames.", s.source_up ? 1 : 0);
  metric("window_frames", "gauge", "Frames in the rolling window.", s.frames);
  metric("window_valid_ratio", "gauge",
         "Frames with a width over the frames expected in the rolling window.", s.valid_fraction);
  if (s.frame_rate_hz > 0) {
    metric("frame_interval_seconds", "gauge", "Median interval between arriving frames.",
           1 / s.frame_rate_hz);
  }
  if (s.has_diameter) {
    metric("strand_diameter_pixels", "gauge",
           "Mean effective strand diameter over the rolling window, in image pixels.",
           s.diameter_px);
    metric("strand_diameter_meters", "gauge",
           "Mean effective strand diameter over the rolling window (needs a pixel scale).",
           s.diameter_um * kPerUm);
    metric("strand_diameter_ci95_meters", "gauge",
           "Half-width of the 95 % confidence interval of the mean strand diameter.",
           s.diameter_ci95_um * kPerUm);
  }
  if (s.baseline_ready) {
    metric("strand_baseline_diameter_meters", "gauge",
           "Baseline effective strand diameter the drift is measured from.",
           s.baseline_um * kPerUm);
    if (s.has_diameter) {
      metric("strand_drift_ratio", "gauge",
             "Rolling window's mean diameter over the baseline, minus 1 (-0.05: 5 % narrower).",
             s.drift_pct * kPerPct);
      metric("strand_drift_ci95_ratio", "gauge",
             "Half-width of the 95 % confidence interval of the drift.",
             s.drift_ci95_pct * kPerPct);
    }
  }
  if (s.has_recent) {
    metric("strand_recent_drift_ratio", "gauge",
           "Drift over the alert window (what the warn and clog levels test), as a ratio.",
           s.recent_drift_pct * kPerPct);
  }
  if (clog) {
    metric("back_pressure_ratio", "gauge",
           "Predicted back pressure F_bp / F_bp,0 at the current diameter.",
           clog->back_pressure_ratio);
    metric("vibration_increase_ratio", "gauge",
           "Predicted bar-mount vibration amplitude increase at the current diameter, as a ratio.",
           clog->vibration_increase_pct * kPerPct);
  }
  metric("frames_total", "counter", "Frames received.", c.frames_total);
  metric("frames_valid_total", "counter", "Frames with a width.", c.frames_valid_total);
  metric("frames_refused_total", "counter",
         "Frames not measured: undecodable, damaged, too large, or not the first frame's size.",
         c.frames_refused_total);
  metric("frames_skipped_total", "counter", "Frames skipped because measuring fell behind.",
         c.frames_skipped_total);
  metric("reconnects_total", "counter", "Times the source was reopened.", c.reconnects_total);
  metric("level_changes_total", "counter",
         "Level changes, returns to ok included (each runs --on-alert).", s.level_changes);
  f->Head("alerts_total", "counter",
          "Level changes into an alert level (warn, clog, not_extruding, no_view), by that level.");
  for (WatchLevel l : kWatchLevels) {
    if (!IsAlertLevel(l)) continue;
    f->Sample("alerts_total", "alerts_total", fmt::format("level=\"{}\"", WatchLevelName(l)),
              std::to_string(s.changes_into[static_cast<size_t>(l)]));
  }
  const std::string h = "frame_latency_seconds";
  f->Head(h, "histogram", "Time from a frame's arrival to the state it updated being published.");
  long long cumulative = 0;
  for (size_t i = 0; i < c.latency.bucket_counts.size(); ++i) {
    cumulative += c.latency.bucket_counts[i];
    f->Sample(h, h + "_bucket", fmt::format("le=\"{}\"", kLatencyBucketsS[i]),
              std::to_string(cumulative));
  }
  f->Sample(h, h + "_bucket", "le=\"+Inf\"", std::to_string(c.latency.count));
  f->Sample(h, h + "_sum", "", fmt::format("{}", c.latency.sum_s));
  f->Sample(h, h + "_count", "", std::to_string(c.latency.count));
  metric("uptime_seconds", "gauge", "Seconds since the watch started.", c.uptime_s);
}

}  // namespace

std::string PrometheusText(const WatchStatus& s, const std::optional<ClogIndex>& clog,
                           const WatchCounters& c) {
  Families f;
  AddBuildInfo(&f);
  AddSamples(s, clog, c, &f);
  return f.Text();
}

std::string PrometheusText(const std::vector<PrometheusCamera>& cameras) {
  Families f;
  AddBuildInfo(&f);  // the process's, once: no printer label
  for (const PrometheusCamera& camera : cameras) {
    f.SetPrinter(camera.printer);
    AddSamples(camera.status, camera.clog, camera.counters, &f);
  }
  return f.Text();
}

}  // namespace clogscope::watch
