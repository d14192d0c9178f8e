#pragma once

// A watch held at its first level change, for tests that look at what its HTTP server serves then.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "apps/watch_command.h"
#include "synthetic/synthetic.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps::testing {

// The clip the HTTP tests watch: 10 s at 25 frames/s of a 400 µm strand (3 µm/px, 2 µm jitter,
// the watch camera's scene with `seed`) narrowing to 360 µm at 4 s (−10 %: past the clog
// threshold), rendered to DIR/clog.avi; the frames' truths.
inline constexpr double kClipScaleUmPerPx = 3.0;
inline constexpr double kClipNarrowAtS = 4.0;
inline constexpr double kClipBaselineUm = 400.0, kClipNarrowedUm = 360.0;
inline std::vector<synthetic::FrameTruth> RenderNarrowingClip(const std::filesystem::path& dir,
                                                              uint64_t seed) {
  synthetic::SceneParams s = WatchCameraScene(seed);
  for (int i = 0; i < 250; ++i)
    s.frame_width_um.push_back(i / 25.0 >= kClipNarrowAtS ? kClipNarrowedUm : kClipBaselineUm);
  return synthetic::RenderSequence(s, 250, 25, (dir / "clog.avi").string(),
                                   (dir / "clog.truth.json").string());
}

// The true mean diameter, µm (or the apparent width in px), of the frames within [from_s, to_s].
inline double TruthMean(const std::vector<synthetic::FrameTruth>& truths, double from_s,
                        double to_s, bool px = false) {
  double sum = 0;
  int n = 0;
  for (const synthetic::FrameTruth& f : truths) {
    if (f.time_s < from_s - 1e-9 || f.time_s > to_s + 1e-9) continue;
    sum += px ? f.width_px : f.width_um;
    ++n;
  }
  return n ? sum / n : NAN;
}

// Runs the watch `o` with --http 127.0.0.1:0 and calls check(port, state) at its first level
// change, while the server serves that state (the watch waits for check); fails the test when the
// level never changes.
inline void WatchHeldAtFirstChange(
    WatchCommandOptions o, const std::function<void(int port, const watch::WatchStatus&)>& check) {
  o.http = "127.0.0.1:0";
  int port = 0;
  bool called = false;
  WatchObservers observers;
  observers.on_started = [&](int p) { port = p; };
  observers.on_level_change = [&](const watch::WatchStatus& s) {
    if (called) return;
    called = true;
    check(port, s);
  };
  std::atomic<bool> stop{false};
  WatchNozzle(o, &stop, observers);
  EXPECT_TRUE(called) << "the watch never changed level";
}

// One sample of the text format: `name{labels}` → value.
inline std::map<std::string, double> ParseMetrics(const std::string& text) {
  std::map<std::string, double> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    const size_t space = line.rfind(' ');
    out[line.substr(0, space)] = std::stod(line.substr(space + 1));
  }
  return out;
}

// The sample's value; a failure when it is absent.
inline double At(const std::map<std::string, double>& metrics, const std::string& sample) {
  const auto it = metrics.find(sample);
  if (it != metrics.end()) return it->second;
  ADD_FAILURE() << sample << " is not in /metrics";
  return NAN;
}

}  // namespace clogscope::apps::testing
