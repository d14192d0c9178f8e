// clogscope_bench watch-farm: how many 720p cameras at 25 frames/s one core keeps up with, for
// `watch --config`. N cameras run in one process as the farm runs them (apps::WatchFarm: a reader
// decoding its own file, a measuring thread, the rolling state and board each), on a rendered
// 10-s clip as MJPEG (what most webcams send) and H.264. First unpaced (every frame read and
// measured as fast as it goes): CPU time per frame gives cameras per core. Then paced at 25
// frames/s with that many cameras: the frames skipped and the latency say whether they kept up.
// Run it on one core: taskset -c 1 clogscope_bench watch-farm.
#include <fmt/format.h>
#include <sched.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "apps/watch_farm.h"
#include "synthetic/synthetic.h"

namespace clogscope::bench {
namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct FarmRun {
  long long frames = 0, skipped = 0;
  double wall_s = 0, cpu_s = 0, worst_p95_ms = 0;
  int clogs = 0;  // cameras that ended in an alert level (none expected: the strand is steady)
};

FarmRun RunFarm(const std::string& clip, int cameras, bool paced) {
  apps::WatchFarmOptions farm;
  farm.path = "bench";
  for (int i = 0; i < cameras; ++i) {
    apps::WatchCameraConfig c;
    c.name = fmt::format("cam{}", i);
    c.options.live.source = clip;
    c.options.live.source_options.realtime = paced;
    c.options.measure.scale_um_per_px = 3.0;
    c.options.log_path = "/dev/null";
    farm.cameras.push_back(c);
  }
  std::atomic<bool> stop{false};
  const double cpu0 = CpuSeconds();
  const auto t0 = Clock::now();
  const apps::WatchFarmReport r = apps::WatchFarm(farm, &stop);
  FarmRun out;
  out.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  out.cpu_s = CpuSeconds() - cpu0;
  for (const apps::WatchReport& c : r.cameras) {
    out.frames += c.summary.frames;
    out.skipped += c.summary.skipped_frames;
    out.worst_p95_ms = std::max(out.worst_p95_ms, c.summary.latency_p95_ms);
    out.clogs += watch::IsAlertLevel(c.summary.final_level);
  }
  for (const std::string& e : r.errors) fmt::print("watch-farm: error: {}\n", e);
  return out;
}

}  // namespace
}  // namespace clogscope::bench

void BenchWatchFarm() {
  using namespace clogscope;
  using namespace clogscope::bench;
  spdlog::set_level(spdlog::level::warn);  // the farm's start and end lines, per camera
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  sched_getaffinity(0, sizeof cpus, &cpus);
  fmt::print("watch-farm: {} core(s) allowed (run under taskset -c 1 for the one-core figure)\n",
             CPU_COUNT(&cpus));
  const fs::path dir = fs::temp_directory_path() / fmt::format("clogscope_bench_farm_{}", getpid());
  fs::create_directories(dir);
  synthetic::SceneParams s;  // the reference camera: 1280×720, 3 µm/px, a 400 µm strand
  s.width_jitter_um = 2.0;
  for (const char* ext : {".avi", ".mp4"}) {
    const std::string clip = (dir / (std::string("clip") + ext)).string();
    synthetic::RenderSequence(s, 250, 25, clip, (dir / "truth.json").string());
    const std::string codec = ext == std::string(".avi") ? "MJPEG" : "H.264";
    double cameras_per_core = 0;
    for (int n : {1, 4}) {
      const FarmRun u = RunFarm(clip, n, /*paced=*/false);
      const double cpu_ms = 1e3 * u.cpu_s / u.frames;
      cameras_per_core = 1e3 / (25 * cpu_ms);
      fmt::print(
          "watch-farm: {} 720p, {} camera(s) unpaced: {} frames in {:.2f} s ({:.0f} frames/s), "
          "CPU {:.2f} ms a frame (decode, measure, state) -> {:.1f} cameras at 25 frames/s per "
          "core\n",
          codec, n, u.frames, u.wall_s, u.frames / u.wall_s, cpu_ms, cameras_per_core);
    }
    // Paced at 25 frames/s, every camera's frames due at the same instants (the worst case: all
    // of them want the core at once): kept up when under 1 % of the frames are skipped and the
    // worst camera's p95 latency is under a frame's 40 ms.
    int kept_up = 0;
    for (double share : {0.5, 0.7, 0.9}) {
      const int n = std::max(1, static_cast<int>(std::lround(share * cameras_per_core)));
      const FarmRun p = RunFarm(clip, n, /*paced=*/true);
      const double skipped_pct = 100.0 * p.skipped / std::max(1LL, p.frames + p.skipped);
      const bool ok = skipped_pct < 1 && p.worst_p95_ms < 40;
      if (ok) kept_up = std::max(kept_up, n);
      fmt::print(
          "watch-farm: {} 720p, {} cameras paced at 25 frames/s for 10 s: {} frames, {} skipped "
          "({:.2f} %), latency p95 of the worst camera {:.1f} ms, CPU {:.0f} % of the core(s), {} "
          "camera(s) in an alert level: {}\n",
          codec, n, p.frames, p.skipped, skipped_pct, p.worst_p95_ms, 100 * p.cpu_s / p.wall_s,
          p.clogs, ok ? "kept up" : "fell behind");
    }
    fmt::print("watch-farm: {} 720p at 25 frames/s: {} cameras kept up (of those tried)\n", codec,
               kept_up);
  }
  fs::remove_all(dir);
}
