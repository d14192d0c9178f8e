#pragma once

#include <array>
#include <iterator>
#include <optional>
#include <string>
#include <vector>

#include "model/parameters.h"
#include "watch/watch_state.h"

namespace clogscope::watch {

// What the drift means physically (predictor.md): the predictor run at the baseline and at the
// current diameter, both at temperature_c.
struct ClogIndex {
  double temperature_c = 0;
  double back_pressure_ratio = 1;     // F_bp / F_bp,0
  double vibration_increase_pct = 0;  // (A / A_0 − 1) · 100 at the mount's natural frequency
  std::optional<double> current_ma;   // feeding motor current at the current diameter
};

// nullopt with the reason in *why when the predictor refuses the diameters (e.g. wider than the
// entry bore) or the status has no drift yet.
std::optional<ClogIndex> ComputeClogIndex(const model::ExtruderParams& params, double temperature_c,
                                          const WatchStatus& status, std::string* why);

// Upper bounds of the frame latency histogram's buckets, s: 0.5 ms to 2 s in 1-2-5 steps (a PC
// takes under a millisecond a frame, a Pi 10-60 ms; frames come every 40 ms at 25 frames/s).
// +Inf is implied.
inline constexpr double kLatencyBucketsS[] = {0.0005, 0.001, 0.002, 0.005, 0.01, 0.02,
                                              0.05,   0.1,   0.2,   0.5,   1,    2};

// Frame latencies (arrival to state published) since the start, as Prometheus histograms count
// them: per bucket (not cumulative here), their number and sum.
struct LatencyHistogram {
  std::array<long long, std::size(kLatencyBucketsS)> bucket_counts{};  // le kLatencyBucketsS[i]
  long long count = 0;                                                 // all, +Inf included
  double sum_s = 0;
  void Add(double seconds);
};

// Counters of the watch run that go with the state.
struct WatchCounters {
  std::string printer;  // the camera's name in a farm (`watch --config`), or empty
  std::string source;   // as shown: a URL's password hidden (vision::RedactCredentials)
  std::string source_kind;
  std::string http_url;              // where /status is served, or empty
  long long frames_total = 0;        // frames received
  long long frames_valid_total = 0;  // with a width
  // Not measured: undecodable, damaged, too large, or not the first frame's size.
  long long frames_refused_total = 0;
  long long frames_skipped_total = 0;  // dropped because measurement fell behind a live source
  long long reconnects_total = 0;
  double latency_median_ms = 0;  // frame arrival to state update, over the recent frames
  double latency_max_ms = 0;
  LatencyHistogram latency;  // the same since the start
  double uptime_s = 0;
};

// v rounded to `digits` decimals (the JSON outputs' precision); a value that is not finite is kept.
double RoundDecimals(double v, int digits);

// The rolling state as one line of JSON (no newline): the /status document and the log's lines.
// `event` is "status" for the periodic line, "level" for a level change, "stop" for the last.
std::string StatusJson(const WatchStatus& status, const std::optional<ClogIndex>& clog,
                       const WatchCounters& counters, const std::string& event);

// The same as Prometheus text exposition format (version 0.0.4), metrics prefixed clogscope_, in
// base units (metres, seconds, ratios); what is not known yet is absent (docs/watch.md lists them).
std::string PrometheusText(const WatchStatus& status, const std::optional<ClogIndex>& clog,
                           const WatchCounters& counters);

// One camera of a farm (`watch --config`), for the Prometheus text of them all.
struct PrometheusCamera {
  std::string printer;  // its name, the `printer` label of each of its series
  WatchStatus status;
  std::optional<ClogIndex> clog;
  WatchCounters counters;
};
// Every camera's series in one exposition, labelled printer="NAME" (each family's HELP and TYPE
// once); clogscope_build_info once, unlabelled.
std::string PrometheusText(const std::vector<PrometheusCamera>& cameras);

}  // namespace clogscope::watch
