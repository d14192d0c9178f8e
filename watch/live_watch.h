#pragma once

#include <atomic>
#include <functional>
#include <limits>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "model/parameters.h"
#include "vision/io/live_source.h"
#include "vision/scene/strand_measure.h"
#include "watch/watch_history.h"
#include "watch/watch_report.h"
#include "watch/watch_state.h"

namespace clogscope::watch {

struct LiveWatchOptions {
  std::string source;  // device, stream URL, video file or folder (OpenLiveSource)
  vision::LiveSourceOptions source_options;
  vision::StrandMeasureOptions strand;                // band already in px
  std::optional<calib::ScaleCalibration> conversion;  // px → µm; nullopt: px only
  WatchOptions watch;
  std::optional<model::ExtruderParams> extruder;  // the clog index, when given
  double temperature_c = 0;                       // the nozzle's, for the clog index
  double report_every_s = 0;                      // periodic status line; 0: every window_s
  double duration_s = 0;                          // stop after this long; 0: until stopped/ended
  double reconnect_initial_s = 0.5;               // back-off after a drop: doubles up to max
  double reconnect_max_s = 10;
  std::string printer;   // the camera's name in a farm (`watch --config`): in every line; or empty
  std::string http_url;  // where /status is served ("http://127.0.0.1:8090"), told in every line
  bool Validate(std::string* why) const;
};

// The latest state, shared with readers on other threads (the HTTP server).
struct WatchSnapshot {
  WatchStatus status;
  std::optional<ClogIndex> clog;
  WatchCounters counters;
  cv::Mat frame;                          // the latest frame, as read
  vision::StrandMeasurement measurement;  // and what was measured in it
  long long sequence = 0;                 // frames published so far
};

// The latest state and its history (every state published feeds it), shared with readers on
// other threads.
class WatchBoard {
 public:
  // Throws std::invalid_argument when the history's options do not validate.
  explicit WatchBoard(const WatchHistoryOptions& history = {}) : history_(history) {}
  void Publish(WatchSnapshot snapshot);
  // The state without a new frame (time passing while none arrive): the latest frame stays.
  void PublishState(const WatchStatus& status, const std::optional<ClogIndex>& clog,
                    const WatchCounters& counters);
  WatchSnapshot Read() const;  // a copy (the frame is shared, never written again)
  // The history's points at or after since_s (all by default), oldest first.
  std::vector<HistoryPoint> History(
      double since_s = -std::numeric_limits<double>::infinity()) const;
  const WatchHistoryOptions& history_options() const { return history_.options(); }

 private:
  mutable std::mutex mutex_;
  WatchSnapshot latest_;
  WatchHistory history_;
};

// What the watch tells its caller, on the measuring thread.
struct LiveWatchEvents {
  // One JSON line (StatusJson): every report_every_s, on every level change and at the stop.
  std::function<void(const std::string& line)> on_line;
  // With each of those lines, the state it tells: `event` is "status", "level" or "stop".
  std::function<void(const std::string& event, const WatchStatus&, const std::optional<ClogIndex>&)>
      on_report;
  // On every level change, after its line and once the board shows the new state (what /status,
  // /metrics and /frame.jpg serve); the watch waits for it, so the board holds that state
  // meanwhile.
  std::function<void(const WatchStatus&, const std::optional<ClogIndex>&)> on_level_change;
  // The state after every update (each frame, and time passing without one): for what must follow
  // the watch's clock closely (the printer link's pause, its hold-off and retries). Must be cheap.
  std::function<void(const WatchStatus&)> on_state;
  // Warnings worth a log line (the source dropped, reconnecting, a frame that could not be
  // measured).
  std::function<void(const std::string& message)> on_warning;
};

struct LiveWatchSummary {
  long long frames = 0, valid_frames = 0, skipped_frames = 0, reconnects = 0;
  int level_changes = 0;
  WatchLevel final_level = WatchLevel::kStarting;
  std::string ended_because;  // "the file ended", "stopped", "--duration-s reached"
  std::string error;          // the one line of a source that failed mid-way, or empty
  double latency_median_ms = 0, latency_p95_ms = 0, latency_max_ms = 0;
  double seconds = 0;
};

// Watches SOURCE until *stop turns true, a file ends, or duration_s passes: a reader thread takes
// frames from the source (reopening a live source that drops, with back-off, while the state says
// no_view), and this thread measures each one (tracking the strand), feeds the rolling state and
// publishes it to `board`. A live source's newest frame wins when measuring falls behind (the
// skipped frames are counted); a file's frames are all measured. Throws std::invalid_argument
// when the options do not validate or the source cannot be opened at the start. Sets *stop on
// return (the reader thread ends with it).
LiveWatchSummary RunLiveWatch(const LiveWatchOptions& options, const LiveWatchEvents& events,
                              WatchBoard* board, std::atomic<bool>* stop);
// The same on a source already open (benchmarks and tests feed their own); a drop reopens
// options.source.
LiveWatchSummary RunLiveWatch(const LiveWatchOptions& options, const LiveWatchEvents& events,
                              WatchBoard* board, std::atomic<bool>* stop,
                              std::unique_ptr<vision::FrameSource> source);

}  // namespace clogscope::watch
