// clogscope_bench watch: the live watch's loop (tracking, scene memory, rolling state, alerts) on
// rendered 720p frames: false alarms and memory over an hour of a steady strand with jitter,
// occlusions and a purge blob, fed at full speed; how soon a 3 % and a 6 % narrowing raise warn
// and clog; the latency from a frame's arrival to the published state at 25 frames/s.
#include <fmt/format.h>

#include <chrono>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <thread>

#include "pipeline/experiment.h"
#include "synthetic/synthetic.h"
#include "watch/live_watch.h"

namespace clogscope::bench {
namespace {

using Clock = std::chrono::steady_clock;

enum class Shows { kSteady, kNarrowed, kOccluded, kBlob };

// Frames from pools of pre-rendered ones, chosen per frame time by a schedule; paced at 25
// frames/s (live clock) or as fast as they are taken (the frame times as clock).
class PoolSource : public vision::FrameSource {
 public:
  PoolSource(std::function<const cv::Mat&(int64_t)> frame, int64_t frames, bool paced)
      : FrameSource("pool", vision::SourceKind::kVideo),
        frame_(std::move(frame)),
        frames_(frames),
        paced_(paced),
        start_(Clock::now()) {}
  bool live() const override { return paced_; }
  vision::FrameRead Read(vision::InputFrame* out, std::string*) override {
    if (index_ >= frames_) return vision::FrameRead::kEnd;
    const double t = index_ / 25.0;
    if (paced_) std::this_thread::sleep_until(start_ + std::chrono::microseconds(int64_t(t * 1e6)));
    out->image = frame_(index_);
    out->time_s = t;
    out->index = index_++;
    out->arrival = Clock::now();
    return vision::FrameRead::kFrame;
  }

 private:
  std::function<const cv::Mat&(int64_t)> frame_;
  int64_t frames_, index_ = 0;
  bool paced_;
  Clock::time_point start_;
};

double RssMb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0;
}

std::vector<cv::Mat> Pool(synthetic::SceneParams s, int n, uint64_t seed) {
  std::vector<cv::Mat> out;
  s.seed = seed;
  for (int i = 0; i < n; ++i) {
    synthetic::FrameTruth truth;
    out.push_back(synthetic::RenderFrame(s, i, &truth));
  }
  return out;
}

struct Outcome {
  watch::LiveWatchSummary summary;
  std::vector<std::pair<double, std::string>> changes;
};

Outcome Watch(std::function<const cv::Mat&(int64_t)> frame, int64_t frames, bool paced) {
  watch::LiveWatchOptions o;
  o.source = "pool";
  o.conversion = pipeline::PlainScale(3.0);
  o.strand.band_start_px = 50.0 / 3;
  o.strand.band_height_px = 50;
  Outcome out;
  watch::LiveWatchEvents events;
  events.on_level_change = [&](const watch::WatchStatus& s,
                               const std::optional<watch::ClogIndex>&) {
    out.changes.emplace_back(s.time_s, watch::WatchLevelName(s.level));
  };
  watch::WatchBoard board;
  std::atomic<bool> stop{false};
  out.summary = watch::RunLiveWatch(o, events, &board, &stop,
                                    std::make_unique<PoolSource>(frame, frames, paced));
  return out;
}

}  // namespace
}  // namespace clogscope::bench

void BenchWatch() {
  using namespace clogscope;
  using namespace clogscope::bench;
  synthetic::SceneParams s;  // the reference camera: 1280×720, 3 µm/px, a 400 µm strand
  s.width_jitter_um = 2.0;
  const auto t0 = Clock::now();
  const std::vector<cv::Mat> steady = Pool(s, 64, 1);
  synthetic::SceneParams narrowed = s, narrowed6 = s, occluded = s, blob = s;
  narrowed.strand_width_um = 388;
  narrowed6.strand_width_um = 376;
  occluded.occlusion_start_s = {0};
  occluded.occlusion_duration_s = 1e9;
  blob.purge_start_s = 0;
  blob.purge_duration_s = 1e9;
  const std::vector<cv::Mat> low3 = Pool(narrowed, 32, 2), low6 = Pool(narrowed6, 32, 3),
                             hidden = Pool(occluded, 8, 4), purge = Pool(blob, 8, 5);
  fmt::print("watch: rendered {} pool frames (720p) in {:.1f} s\n",
             steady.size() + low3.size() + low6.size() + hidden.size() + purge.size(),
             std::chrono::duration<double>(Clock::now() - t0).count());
  std::mt19937_64 rng(9);
  // Pool frames in random order, so the jitter is frame to frame.
  const auto pick = [&](const std::vector<cv::Mat>& pool) -> const cv::Mat& {
    return pool[std::uniform_int_distribution<size_t>(0, pool.size() - 1)(rng)];
  };

  // 1. An hour of a steady strand at full speed: occlusions of 0.2–1.5 s about once a minute, a
  // purge blob of 2 s at 15 minutes. Memory is read at 5, 30 and 60 minutes.
  std::vector<std::pair<double, double>> occlusions;
  std::uniform_real_distribution<double> uni(0, 1);
  for (double t = 20; t < 3600; t += 30 + 60 * uni(rng))
    occlusions.emplace_back(t, 0.2 + 1.3 * uni(rng));
  double rss_5 = 0, rss_30 = 0;
  const auto steady_frame = [&](int64_t i) -> const cv::Mat& {
    if (i == 25 * 300) rss_5 = RssMb();
    if (i == 25 * 1800) rss_30 = RssMb();
    const double t = i / 25.0;
    for (const auto& [a, len] : occlusions)
      if (t >= a && t < a + len) return pick(hidden);
    if (t >= 900 && t < 902) return pick(purge);
    return pick(steady);
  };
  const auto t1 = Clock::now();
  const Outcome quiet = Watch(steady_frame, 25 * 3600, false);
  const double secs = std::chrono::duration<double>(Clock::now() - t1).count();
  int in_30_min = 0;
  for (const auto& change : quiet.changes) in_30_min += change.first < 1800;
  fmt::print(
      "watch: 60 min steady (90000 frames, {} occlusions, a 2 s purge blob at 15 min): {} level "
      "change(s) in the first 30 min, {} in the hour{}; {} valid; {:.0f} frames/s; RSS at 5 / 30 / "
      "60 min: {:.0f} / {:.0f} / {:.0f} MB\n",
      occlusions.size(), in_30_min, quiet.changes.size(),
      quiet.changes.empty() ? ""
                            : fmt::format(" (first: {} at {:.1f} s)", quiet.changes[0].second,
                                          quiet.changes[0].first),
      quiet.summary.valid_frames, 90000 / secs, rss_5, rss_30, RssMb());

  // 2. A 3 % and a 6 % narrowing at 60 s.
  for (const auto* pool : {&low3, &low6}) {
    const Outcome o = Watch(
        [&](int64_t i) -> const cv::Mat& { return i / 25.0 >= 60 ? pick(*pool) : pick(steady); },
        25 * 90, false);
    std::string seen;
    for (const auto& [t, level] : o.changes) seen += fmt::format(" {} at +{:.2f} s", level, t - 60);
    fmt::print("watch: {} % narrowing at 60 s:{}\n", pool == &low3 ? -3 : -6, seen);
  }

  // 3. Latency at 25 frames/s (paced like a camera), 30 s.
  const Outcome paced =
      Watch([&](int64_t) -> const cv::Mat& { return pick(steady); }, 25 * 30, true);
  fmt::print(
      "watch: latency at 25 frames/s (arrival → state published), 720p: median {:.2f} ms, p95 "
      "{:.2f} ms, max {:.2f} ms; {} skipped\n",
      paced.summary.latency_median_ms, paced.summary.latency_p95_ms, paced.summary.latency_max_ms,
      paced.summary.skipped_frames);
}
