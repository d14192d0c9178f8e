// The history behind the web page's plot: fed by a real WatchState with widths the test chose, its
// points hold the diameter of each second's window; it stays within its bound however long the
// watch runs.
#include "watch/watch_history.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <nlohmann/json.hpp>
#include <random>

#include "pipeline/experiment.h"
#include "watch/live_watch.h"

namespace clogscope::watch {
namespace {

constexpr double kScaleUmPerPx = 3.0;
constexpr double kFps = 25.0;

// The width fed at time t: 100 px, 90 px from 6 s on, with 0.3 px of white noise.
double TrueWidthPx(double t_s) { return t_s >= 6.0 ? 90.0 : 100.0; }

struct Fed {
  WatchState state;
  WatchHistory history;
  std::mt19937_64 rng{3};
  std::normal_distribution<double> noise{0.0, 0.3};
  Fed(const WatchOptions& o, const WatchHistoryOptions& h)
      : state(o, pipeline::PlainScale(kScaleUmPerPx)), history(h) {}
  void Run(int frames) {
    for (int i = 0; i < frames; ++i) {
      const double t = i / kFps;
      state.Add(t, FrameView::kStrand, TrueWidthPx(t) + noise(rng));
      history.Add(state.status());
    }
  }
};

WatchOptions ShortWindows() {
  WatchOptions o;
  o.window_s = 1;
  o.alert_window_s = 1;
  o.baseline_s = 3;
  return o;
}

TEST(WatchHistoryTest, OnePointPerSecondHoldsThatSecondsWindow) {
  Fed f(ShortWindows(), {});
  f.Run(static_cast<int>(12 * kFps));  // 0 to 11.96 s
  const std::vector<HistoryPoint> points = f.history.Points();
  ASSERT_EQ(points.size(), 12u);  // seconds 0..11, each its last state
  for (size_t i = 0; i < points.size(); ++i) {
    const HistoryPoint& p = points[i];
    EXPECT_NEAR(p.time_s, i + 0.96, 1e-9) << i;  // the last frame of second i
    ASSERT_TRUE(p.has_diameter) << i;
    // A window that holds one width only (the 1 s before the point, not across 6 s).
    if (p.time_s - 1.0 < 6.0 && p.time_s >= 6.0) continue;
    const double truth_px = TrueWidthPx(p.time_s);
    EXPECT_NEAR(p.diameter_px, truth_px, 0.2) << p.time_s;
    EXPECT_NEAR(p.diameter_um, truth_px * kScaleUmPerPx, 0.6) << p.time_s;
    EXPECT_GT(p.diameter_ci95_px, 0);
    EXPECT_LT(std::abs(p.diameter_px - truth_px), 3 * p.diameter_ci95_px + 0.05) << p.time_s;
  }
  // The baseline from 3 s on (the first 3 s of frames), the drift from it after the narrowing.
  EXPECT_TRUE(std::isnan(points[1].baseline_px));
  EXPECT_NEAR(points.back().baseline_px, 100.0, 0.2);
  EXPECT_NEAR(points.back().drift_pct, -10.0, 0.3);
  EXPECT_EQ(points.back().level, WatchLevel::kClog);
  EXPECT_EQ(points[4].level, WatchLevel::kOk);
  // The newest point is the latest state: what /status tells.
  EXPECT_EQ(points.back().diameter_px, f.state.status().diameter_px);
  // Since a time: the points at or after it.
  const std::vector<HistoryPoint> since = f.history.Points(9.0);
  ASSERT_EQ(since.size(), 3u);
  EXPECT_NEAR(since.front().time_s, 9.96, 1e-9);
  EXPECT_TRUE(f.history.Points(100).empty());
}

TEST(WatchHistoryTest, TwoHoursAtTwentyFiveFramesASecondKeepTheLastTenMinutes) {
  WatchOptions o = ShortWindows();
  Fed f(o, {});
  const int frames = static_cast<int>(2 * 3600 * kFps);
  f.Run(frames);
  const std::vector<HistoryPoint> points = f.history.Points();
  ASSERT_EQ(points.size(), 600u);
  EXPECT_EQ(f.history.size(), 600u);
  const double last_s = (frames - 1) / kFps;
  EXPECT_NEAR(points.back().time_s, last_s, 1e-9);
  EXPECT_NEAR(points.front().time_s, last_s - 599, 1e-9);
  for (size_t i = 1; i < points.size(); ++i)
    EXPECT_NEAR(points[i].time_s - points[i - 1].time_s, 1.0, 1e-9);
  const std::string json = HistoryJson(points, f.history.options(), true);
  std::cout << "600 points: " << sizeof(HistoryPoint) << " bytes each in memory, " << json.size()
            << " bytes of /history.json\n";
  EXPECT_LT(json.size(), 300u * 600);
}

TEST(WatchHistoryTest, NothingBeforeTheFirstFrameAndPixelsOnlyWithoutAScale) {
  WatchHistory h;
  WatchStatus starting;  // kStarting: nothing known
  h.Add(starting);
  EXPECT_EQ(h.size(), 0u);
  WatchState state(ShortWindows(), std::nullopt);
  for (int i = 0; i < 50; ++i) {
    state.Add(i / kFps, FrameView::kStrand, 80.0 + 0.1 * (i % 3));
    h.Add(state.status());
  }
  ASSERT_EQ(h.size(), 2u);
  const nlohmann::json j = nlohmann::json::parse(HistoryJson(h.Points(), h.options(), false));
  EXPECT_EQ(j["unit"], "px");
  EXPECT_EQ(j["period_s"], 1.0);
  EXPECT_EQ(j["max_points"], 600);
  const nlohmann::json& last = j["points"].back();
  EXPECT_NEAR(last["diameter_px"].get<double>(), 80.1, 0.1);
  EXPECT_LT(last["ci95_low_px"].get<double>(), last["diameter_px"].get<double>());
  EXPECT_GT(last["ci95_high_px"].get<double>(), last["diameter_px"].get<double>());
  EXPECT_TRUE(last["diameter_um"].is_null());
  EXPECT_TRUE(last["ci95_low_um"].is_null());
  EXPECT_TRUE(last["baseline_um"].is_null());
  EXPECT_EQ(last["level"], "ok");
}

TEST(WatchHistoryTest, OptionsOutOfRangeAreRefused) {
  WatchHistoryOptions o;
  o.period_s = 0;
  EXPECT_THROW(WatchHistory{o}, std::invalid_argument);
  o = {};
  o.max_points = 1;
  EXPECT_THROW(WatchHistory{o}, std::invalid_argument);
  EXPECT_THROW(WatchBoard{o}, std::invalid_argument);
}

// The board feeds its history from every state published, frames and ticks alike.
TEST(WatchHistoryTest, TheBoardKeepsTheHistoryOfWhatItPublished) {
  WatchBoard board;
  WatchState state(ShortWindows(), pipeline::PlainScale(kScaleUmPerPx));
  for (int i = 0; i < 75; ++i) {  // 3 s of frames
    state.Add(i / kFps, FrameView::kStrand, 100.0 + 0.1 * (i % 2));
    WatchSnapshot s;
    s.status = state.status();
    board.Publish(s);
  }
  state.Tick(4.5);  // no frames for 1.5 s: a point for second 4
  board.PublishState(state.status(), std::nullopt, {});
  const std::vector<HistoryPoint> points = board.History();
  ASSERT_EQ(points.size(), 4u);
  EXPECT_NEAR(points[2].diameter_um, 300.15, 0.2);
  EXPECT_EQ(points[3].time_s, 4.5);
  EXPECT_EQ(board.History(4.0).size(), 1u);
}

}  // namespace
}  // namespace clogscope::watch
