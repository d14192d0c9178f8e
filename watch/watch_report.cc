#include "watch/watch_report.h"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "model/predictor.h"

namespace clogscope::watch {
namespace {

// JSON has no NaN: a quantity not known yet is null.
nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

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
    d["um"] = Number(RoundDecimals(s.diameter_um, 3));
    d["ci95_um"] = Number(RoundDecimals(s.diameter_ci95_um, 3));
    d["std_um"] = Number(RoundDecimals(s.diameter_std_um, 3));
    d["n_used"] = s.n_used;
    d["n_rejected"] = s.n_rejected;
    d["n_effective"] = RoundDecimals(s.n_effective, 1);
  }
  j["diameter"] = d;
  nlohmann::json b;
  if (s.baseline_ready) {
    b["source"] = s.baseline_source;
    b["px"] = RoundDecimals(s.baseline_px, 4);
    b["um"] = Number(RoundDecimals(s.baseline_um, 3));
    b["ci95_um"] = Number(RoundDecimals(s.baseline_ci95_um, 3));
  }
  j["baseline"] = b;
  nlohmann::json dr;
  if (s.baseline_ready && s.has_diameter) {
    dr["um"] = Number(RoundDecimals(s.drift_um, 3));
    dr["pct"] = RoundDecimals(s.drift_pct, 4);
    dr["ci95_pct"] = RoundDecimals(s.drift_ci95_pct, 4);
  }
  if (s.has_recent) {
    dr["recent_pct"] = RoundDecimals(s.recent_drift_pct, 4);
    dr["recent_ci95_pct"] = RoundDecimals(s.recent_drift_ci95_pct, 4);
    dr["recent_um"] = Number(RoundDecimals(s.recent_diameter_um, 3));
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
                   {"alerts_total", c.alerts_total},
                   {"latency_median_ms", RoundDecimals(c.latency_median_ms, 3)},
                   {"latency_max_ms", RoundDecimals(c.latency_max_ms, 3)},
                   {"uptime_s", RoundDecimals(c.uptime_s, 3)}};
  // Text from outside (a source's name, a decoder's words) may not be UTF-8: replaced, never a
  // throw.
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string PrometheusText(const WatchStatus& s, const std::optional<ClogIndex>& clog,
                           const WatchCounters& c) {
  std::string out;
  const auto metric = [&](const char* name, const char* type, const char* help, double value) {
    if (!std::isfinite(value)) return;  // unknown: absent, as Prometheus expects
    out += fmt::format("# HELP clogscope_{0} {1}\n# TYPE clogscope_{0} {2}\nclogscope_{0} {3}\n",
                       name, help, type, value);
  };
  out +=
      "# HELP clogscope_level Current alert level (1 for the current one).\n"
      "# TYPE clogscope_level gauge\n";
  for (WatchLevel l : kWatchLevels) {
    out += fmt::format("clogscope_level{{level=\"{}\"}} {}\n", WatchLevelName(l),
                       l == s.level ? 1 : 0);
  }
  metric("source_up", "gauge", "1 when the source delivers frames.", s.source_up ? 1 : 0);
  metric("window_frames", "gauge", "Frames in the rolling window.", s.frames);
  metric("window_valid_fraction", "gauge", "Valid frames over frames expected in the window.",
         s.valid_fraction);
  metric("frame_rate_hz", "gauge", "Frames arriving per second.", s.frame_rate_hz);
  if (s.has_diameter) {
    metric("diameter_px", "gauge", "Mean effective diameter over the window, px.", s.diameter_px);
    metric("diameter_um", "gauge", "Mean effective diameter over the window, um.", s.diameter_um);
    metric("diameter_ci95_um", "gauge", "95 % CI half-width of the mean diameter, um.",
           s.diameter_ci95_um);
  }
  if (s.baseline_ready) {
    metric("baseline_um", "gauge", "Baseline effective diameter, um.", s.baseline_um);
    if (s.has_diameter) {
      metric("drift_pct", "gauge", "Drift of the window mean from the baseline, %.", s.drift_pct);
      metric("drift_ci95_pct", "gauge", "95 % CI half-width of the drift, %.", s.drift_ci95_pct);
    }
  }
  if (s.has_recent) {
    metric("recent_drift_pct", "gauge", "Drift over the alert window, %.", s.recent_drift_pct);
  }
  if (clog) {
    metric("back_pressure_ratio", "gauge", "Predicted F_bp / F_bp,0 at the current diameter.",
           clog->back_pressure_ratio);
    metric("vibration_increase_pct", "gauge", "Predicted bar-mount vibration increase, %.",
           clog->vibration_increase_pct);
  }
  metric("frames_total", "counter", "Frames received.", c.frames_total);
  metric("frames_valid_total", "counter", "Frames with a width.", c.frames_valid_total);
  metric("frames_refused_total", "counter",
         "Frames not measured: undecodable, damaged, too large, or not the first frame's size.",
         c.frames_refused_total);
  metric("frames_skipped_total", "counter", "Frames skipped because measuring fell behind.",
         c.frames_skipped_total);
  metric("reconnects_total", "counter", "Times the source was reopened.", c.reconnects_total);
  metric("alerts_total", "counter", "Alert level changes.", c.alerts_total);
  metric("latency_median_ms", "gauge", "Median frame-arrival-to-state latency, ms.",
         c.latency_median_ms);
  metric("uptime_seconds", "gauge", "Seconds since the watch started.", c.uptime_s);
  return out;
}

}  // namespace clogscope::watch
