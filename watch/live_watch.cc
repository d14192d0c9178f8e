#include "watch/live_watch.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <stdexcept>

#include "common/work_queue.h"
#include "vision/io/source_name.h"
#include "vision/scene/scene_memory.h"
#include "vision/scene/track.h"

namespace clogscope::watch {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// Frames between the reader thread and the measuring thread. A live source keeps only the newest
// frames (what a watch wants is now, not a backlog); a file's reader waits for room instead.
using FrameQueue = BoundedQueue<vision::InputFrame>;

// Raises the stop flag and cancels the queue when it goes out of scope.
struct StopOnExit {
  std::atomic<bool>* stop;
  FrameQueue* queue;
  ~StopOnExit() {
    stop->store(true);
    queue->Cancel();
  }
};

// Reads frames into the queue; reopens a live source that drops, with back-off.
struct Reader {
  const LiveWatchOptions& options;
  const LiveWatchEvents& events;
  std::unique_ptr<vision::FrameSource> source;
  FrameQueue* queue;
  std::atomic<bool>* stop;
  std::atomic<bool> up{true};
  std::atomic<long long> reconnects{0};
  std::string ended_because;  // written by the reader before Close()
  std::string error;          // why the source could not go on, or empty

  void Warn(const std::string& message) const {
    if (events.on_warning) events.on_warning(message);
  }
  std::string Shown() const { return vision::RedactCredentials(options.source); }

  bool Wait(double seconds) const {
    return vision::SleepUnlessStopped(Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                                         std::chrono::duration<double>(seconds)),
                                      stop);
  }

  // Ends with the queue closed, however it ends. Nothing thrown leaves this thread: a source that
  // cannot go on (its frames would take too much memory) or anything else that throws here ends
  // the watch with the reason, which the measuring thread reports after its stop line.
  void Run() {
    CloseOnExit<vision::InputFrame> close(queue);
    try {
      Loop();
    } catch (const std::exception& e) {
      error = fmt::format("{}: {}", Shown(), e.what());
      ended_because = "the source failed";
    } catch (...) {
      error = Shown() + ": an unknown error while reading";
      ended_because = "the source failed";
    }
    if (ended_because.empty()) ended_because = "stopped";
  }

  void Loop() {
    vision::InputFrame frame;
    std::string why;
    while (!stop->load()) {
      const vision::FrameRead r = source->Read(&frame, &why);
      if (r == vision::FrameRead::kFrame) {
        if (!queue->Push(std::move(frame))) break;
        frame = vision::InputFrame{};
        continue;
      }
      if (r == vision::FrameRead::kEnd) {
        ended_because = "the file ended";
        break;
      }
      if (r == vision::FrameRead::kStopped) break;
      // Dropped: reopen with back-off until it comes back or the watch stops.
      up = false;
      Warn(fmt::format("{}: {}; reconnecting", Shown(), why));
      source.reset();
      double wait_s = options.reconnect_initial_s;
      while (!source && Wait(wait_s)) {
        try {
          source = vision::OpenLiveSource(options.source, options.source_options, stop);
        } catch (const std::exception& e) {
          // Not there yet (refused, or the device's driver threw): try again later.
          Warn(fmt::format("{} (next try in {:g} s)", e.what(),
                           std::min(2 * wait_s, options.reconnect_max_s)));
          wait_s = std::min(2 * wait_s, options.reconnect_max_s);
        }
      }
      if (!source) break;
      ++reconnects;
      up = true;
      Warn(Shown() + ": reconnected");
    }
  }
};

// Measures each frame, tracking the strand, and says what it showed. A frame that cannot be
// measured is a frame without a view, with the reason why, never a stop.
class FrameMeasurer {
 public:
  explicit FrameMeasurer(const vision::StrandMeasureOptions& options)
      : tracker_(options), memory_(options.target) {}

  // The frame's view and measurement; *refused says why a frame was not measured (undecodable,
  // damaged, not the first frame's size, or the measurement threw), else empty.
  FrameView Measure(const vision::InputFrame& frame, vision::StrandMeasurement* m,
                    std::string* refused) {
    *m = vision::StrandMeasurement{};
    refused->clear();
    const cv::Size size = frame.image.size();
    if (frame.image.empty()) {
      *refused = frame.error.empty() ? "undecodable frame" : frame.error;
    } else if (!first_size_) {
      first_size_ = size;
    } else if (size != *first_size_) {
      // The pixel scale, ROI and band hold for the first frame's size only.
      *refused = fmt::format("the frame is {}×{}, the watch started on {}×{}", size.width,
                             size.height, first_size_->width, first_size_->height);
    }
    if (refused->empty()) {
      try {
        *m = tracker_.Measure(frame);
        if (m->valid()) {
          memory_.Remember(frame.image, *m);
          return FrameView::kStrand;
        }
        return memory_.SeesNozzle(frame.image) ? FrameView::kNozzleOnly : FrameView::kNothing;
      } catch (const std::exception& e) {
        *m = vision::StrandMeasurement{};
        *refused = std::string("cannot be measured: ") + e.what();
      }
    }
    m->status = vision::FrameStatus::kUnreadable;
    m->detail = *refused;
    return FrameView::kNothing;
  }

 private:
  vision::StrandTracker tracker_;
  vision::SceneMemory memory_;
  std::optional<cv::Size> first_size_;
};

// The median and 95th percentile of the recent latencies.
class LatencyLog {
 public:
  void Add(double ms) {
    if (values_.size() == kKeep) values_.pop_front();
    values_.push_back(ms);
    max_ = std::max(max_, ms);
  }
  double Quantile(double q) const {
    if (values_.empty()) return 0;
    std::vector<double> v(values_.begin(), values_.end());
    const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * v.size()));
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[k];
  }
  double max() const { return max_; }

 private:
  static constexpr size_t kKeep = 512;
  std::deque<double> values_;
  double max_ = 0;
};

}  // namespace

bool LiveWatchOptions::Validate(std::string* why) const {
  if (source.empty())
    *why = "no source given";
  else if (!source_options.Validate(why) || !watch.Validate(why) || !strand.Validate(why))
    return false;
  else if (!(report_every_s >= 0 && report_every_s <= 3600))
    *why = fmt::format("--report-s {:g}: must be in [0, 3600] s", report_every_s);
  else if (!(duration_s >= 0))
    *why = fmt::format("--duration-s {:g}: must not be negative", duration_s);
  else if (!(reconnect_initial_s > 0 && reconnect_max_s >= reconnect_initial_s))
    *why = "reconnect back-off: initial > 0 and max ≥ initial";
  else if (extruder && !conversion)
    *why = "--extruder needs a pixel scale (--scale-um-per-px or --calib) for the clog index";
  else
    return true;
  return false;
}

void WatchBoard::Publish(WatchSnapshot snapshot) {
  std::lock_guard<std::mutex> lock(mutex_);
  latest_ = std::move(snapshot);
  history_.Add(latest_.status);
}

void WatchBoard::PublishState(const WatchStatus& status, const std::optional<ClogIndex>& clog,
                              const WatchCounters& counters) {
  std::lock_guard<std::mutex> lock(mutex_);
  latest_.status = status;
  latest_.clog = clog;
  latest_.counters = counters;
  history_.Add(status);
}

WatchSnapshot WatchBoard::Read() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

std::vector<HistoryPoint> WatchBoard::History(double since_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return history_.Points(since_s);
}

LiveWatchSummary RunLiveWatch(const LiveWatchOptions& options, const LiveWatchEvents& events,
                              WatchBoard* board, std::atomic<bool>* stop) {
  std::string why;
  if (!options.Validate(&why)) throw std::invalid_argument(why);
  return RunLiveWatch(options, events, board, stop,
                      vision::OpenLiveSource(options.source, options.source_options, stop));
}

LiveWatchSummary RunLiveWatch(const LiveWatchOptions& options, const LiveWatchEvents& events,
                              WatchBoard* board, std::atomic<bool>* stop,
                              std::unique_ptr<vision::FrameSource> source) {
  std::string why;
  if (!options.Validate(&why)) throw std::invalid_argument(why);
  WatchState state(options.watch, options.conversion);
  FrameMeasurer measurer(options.strand);
  const auto started = Clock::now();

  Reader reader{options, events, std::move(source), nullptr, stop, {true}, {0}, {}, {}};
  const bool live = reader.source->live();
  FrameQueue queue(
      2, live || options.source_options.realtime ? QueueFull::kDropOldest : QueueFull::kWait);
  reader.queue = &queue;
  WatchCounters counters;
  counters.printer = options.printer;
  counters.source = vision::RedactCredentials(options.source);
  counters.http_url = options.http_url;
  counters.source_kind = vision::SourceKindName(reader.source->kind());
  Workers reading(1, [&](int) { reader.Run(); });
  // However this function ends (an event callback may throw), the reader is told to stop and woken
  // before `reading` waits for it.
  const StopOnExit stop_reader{stop, &queue};

  const double report_every =
      options.report_every_s > 0 ? options.report_every_s : options.watch.window_s;
  LiveWatchSummary summary;
  LatencyLog latency;
  std::optional<ClogIndex> clog;
  std::optional<double> next_report_s;
  bool refusing = false;  // the last frame was refused
  const auto emit = [&](const std::string& event) {
    if (events.on_line) events.on_line(StatusJson(state.status(), clog, counters, event));
    if (events.on_report) events.on_report(event, state.status(), clog);
  };
  const auto update_counters = [&] {
    counters.frames_skipped_total = queue.dropped();
    counters.reconnects_total = reader.reconnects;
    counters.latency_median_ms = latency.Quantile(0.5);
    counters.latency_max_ms = latency.max();
    counters.uptime_s = Seconds(Clock::now() - started);
  };
  // After each update of the state: its clog index and counters, the level's line, the board
  // (`publish`), the state to on_state, then the level change told (a reader of /status sees the
  // new level by then), then the periodic status line.
  const auto after_update = [&](bool changed, double t, const auto& publish) {
    if (options.extruder) {
      std::string no_index;
      clog = ComputeClogIndex(*options.extruder, options.temperature_c, state.status(), &no_index);
    }
    update_counters();
    if (changed) emit("level");
    if (board) publish();
    if (events.on_state) events.on_state(state.status());  // before a change's listeners wait
    if (changed && events.on_level_change) events.on_level_change(state.status(), clog);
    if (!next_report_s) next_report_s = t + report_every;
    if (t >= *next_report_s) {
      emit("status");
      // The next slot on the same grid after t (frames may skip slots).
      *next_report_s += report_every * (std::floor((t - *next_report_s) / report_every) + 1);
    }
  };

  vision::InputFrame frame;
  try {
    while (true) {
      bool ended = false;
      if (options.duration_s > 0 && Seconds(Clock::now() - started) >= options.duration_s) {
        summary.ended_because = "--duration-s reached";
        break;
      }
      if (stop->load()) {
        summary.ended_because = "stopped";
        break;
      }
      if (!queue.PopFor(&frame, std::chrono::milliseconds(100), &ended)) {
        if (ended) {
          summary.ended_because = reader.ended_because;
          summary.error = reader.error;
          break;
        }
        if (!live) continue;  // a file's clock is its own: no frame, no time
        const double t = Seconds(Clock::now() - started);
        state.SetSourceUp(reader.up, t);
        const bool changed = state.Tick(t);
        after_update(changed, t, [&] { board->PublishState(state.status(), clog, counters); });
        continue;
      }
      // A file read as fast as it decodes is read ahead by design: its frames' wait in the queue is
      // no latency anyone sees, so theirs counts from here.
      if (!live && !options.source_options.realtime) frame.arrival = Clock::now();
      vision::StrandMeasurement m;
      std::string refused;
      const FrameView view = measurer.Measure(frame, &m, &refused);
      if (!refused.empty()) {
        ++counters.frames_refused_total;
        // The first of a run of refused frames is told, the rest counted: a stream of garbage must
        // not flood the log.
        if (!refusing && events.on_warning)
          events.on_warning(
              fmt::format("{}: frame {} not measured: {}", counters.source, frame.index, refused));
      }
      refusing = !refused.empty();
      const double t = live ? Seconds(frame.arrival - started) : frame.time_s;
      const bool changed = state.Add(t, view, m.width_px);
      ++counters.frames_total;
      counters.frames_valid_total += view == FrameView::kStrand;
      after_update(changed, t, [&] {
        board->Publish({state.status(), clog, counters, std::move(frame.image), std::move(m),
                        counters.frames_total});
      });
      // Arrival (decoded, in hand) to the state published: what a reader of /status waits for.
      const double latency_s = Seconds(Clock::now() - frame.arrival);
      latency.Add(1e3 * latency_s);
      counters.latency.Add(latency_s);
      frame = vision::InputFrame{};
    }
  } catch (const std::exception& e) {
    // Whatever failed on this thread, the watch ends with a stop line and the reason.
    summary.ended_because = "the watch failed";
    summary.error = fmt::format("{}: the watch failed: {}", counters.source, e.what());
  }
  stop->store(true);  // the reader stops too
  queue.Cancel();     // and a reader waiting for room wakes
  reading.Join();     // the reader catches what it throws: nothing to rethrow
  update_counters();
  emit("stop");
  summary.frames = counters.frames_total;
  summary.valid_frames = counters.frames_valid_total;
  summary.skipped_frames = queue.dropped();
  summary.reconnects = reader.reconnects;
  summary.level_changes = state.status().level_changes;
  summary.final_level = state.status().level;
  summary.latency_median_ms = latency.Quantile(0.5);
  summary.latency_p95_ms = latency.Quantile(0.95);
  summary.latency_max_ms = latency.max();
  summary.seconds = Seconds(Clock::now() - started);
  return summary;
}

}  // namespace clogscope::watch
