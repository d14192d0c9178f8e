#include "watch/watch_state.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "pipeline/experiment.h"
#include "watch/watch_report.h"

namespace clogscope::watch {
namespace {

constexpr double kScale = 3.0;  // µm/px, the reference camera
constexpr double kFps = 25.0;

// A simulated watch: per-frame diameters in µm (nozzle 400 µm) with 2 µm of jitter per frame: a
// wander of 1 µm (AR(1), 0.5 s correlation time) as a real strand wobbles, and √3 µm of white
// noise.
struct Simulation {
  WatchState state;
  std::mt19937_64 rng{7};
  std::normal_distribution<double> normal{0.0, 1.0};
  double wander_um = 0;
  int changes = 0;
  std::vector<std::pair<double, WatchLevel>> levels;  // every change: time, new level

  explicit Simulation(const WatchOptions& o = {}) : state(o, pipeline::PlainScale(kScale)) {}

  double Jittered(double diameter_um) {
    const double phi = std::exp(-1.0 / (0.5 * kFps));
    wander_um = phi * wander_um + std::sqrt(1 - phi * phi) * normal(rng);
    return diameter_um + wander_um + std::sqrt(3.0) * normal(rng);
  }
  // Frames from t0 to t1; `frame(t)` says what each shows (view and diameter in µm).
  void Run(double t0, double t1, const std::function<std::pair<FrameView, double>(double)>& frame) {
    const int n0 = static_cast<int>(std::ceil(t0 * kFps)), n1 = static_cast<int>(t1 * kFps);
    for (int i = n0; i < n1; ++i) {
      const double t = i / kFps;
      const auto [view, d_um] = frame(t);
      if (state.Add(t, view, view == FrameView::kStrand ? Jittered(d_um) / kScale : 0.0))
        levels.emplace_back(t, state.status().level);
    }
  }
  // Time passing without frames, ticked every 0.1 s as the live loop does: `stall_s` of silence
  // while the source still counts as up (its read timeout running), then `down_s` with it down
  // (reconnecting). Returns the time it is back.
  double Outage(double t0, double stall_s, double down_s) {
    double t = t0;
    const auto tick_until = [&](double end) {
      for (; t < end - 1e-9; t += 0.1)
        if (state.Tick(t)) levels.emplace_back(t, state.status().level);
    };
    tick_until(t0 + stall_s);
    state.SetSourceUp(false, t);
    tick_until(t0 + stall_s + down_s);
    state.SetSourceUp(true, t);
    return t;
  }
  std::optional<double> FirstTimeAt(WatchLevel level) const {
    for (const auto& [t, l] : levels)
      if (l == level) return t;
    return std::nullopt;
  }
};

std::pair<FrameView, double> Strand(double d_um) { return {FrameView::kStrand, d_um}; }

TEST(WatchStateTest, WilsonIntervalMatchesPublishedValues) {
  // Newcombe (1998), Table I: 81/263 → 0.2553…0.3662; 15/148 → 0.0624…0.1605.
  auto [lo, hi] = WilsonInterval(81, 263);
  EXPECT_NEAR(lo, 0.2553, 5e-4);
  EXPECT_NEAR(hi, 0.3662, 5e-4);
  std::tie(lo, hi) = WilsonInterval(15, 148);
  EXPECT_NEAR(lo, 0.0624, 5e-4);
  EXPECT_NEAR(hi, 0.1605, 5e-4);
  std::tie(lo, hi) = WilsonInterval(0, 0);
  EXPECT_EQ(lo, 0.0);
  EXPECT_EQ(hi, 1.0);
}

TEST(WatchStateTest, EffectiveSampleSizeOfAnAr1SeriesIsNearItsTheory) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  std::vector<double> white(20000), ar(20000);
  double x = 0;
  for (size_t i = 0; i < white.size(); ++i) {
    white[i] = n01(rng);
    x = 0.8 * x + n01(rng);
    ar[i] = x;
  }
  EXPECT_NEAR(EffectiveSampleSize(white) / 20000, 1.0, 0.05);
  EXPECT_NEAR(EffectiveSampleSize(ar) / 20000, 0.2 / 1.8, 0.02);  // 1/τ = (1 − φ)/(1 + φ)
}

TEST(WatchStateTest, RollingMeanAndCiOfASteadyStrand) {
  Simulation sim;
  sim.Run(0, 30, [](double) { return Strand(400); });
  const WatchStatus& s = sim.state.status();
  ASSERT_TRUE(s.baseline_ready);
  EXPECT_EQ(s.baseline_source, "measured");
  EXPECT_NEAR(s.frame_rate_hz, kFps, 1e-6);
  EXPECT_NEAR(s.frames, 10 * kFps, 1);
  EXPECT_NEAR(s.valid_fraction, 1.0, 0.01);
  // The 95 % CI covers the truth and is honest about the wander: wider than the white-noise SEM.
  EXPECT_LT(std::abs(s.diameter_um - 400), s.diameter_ci95_um);
  EXPECT_GT(s.diameter_ci95_um, 1.96 * 2.0 / std::sqrt(s.n_used));
  EXPECT_LT(s.diameter_ci95_um, 2.0);
  EXPECT_NEAR(s.diameter_std_um, 2.0, 0.6);
  EXPECT_LT(s.n_effective, s.n_used);
  EXPECT_EQ(s.level, WatchLevel::kOk);
}

TEST(WatchStateTest, TheWindowMeansCiCoversTheTruthAtItsConfidence) {
  // 400 disjoint 10-s windows of the wandering strand: the 95 % CI should hold the true 400 µm in
  // about 95 % of them. It holds it in 89 %: the autocorrelation time estimated from 250 frames
  // runs a little short.
  Simulation sim;
  int covered = 0, windows = 0;
  for (int k = 1; k <= 400; ++k) {
    sim.Run(10.0 * (k - 1), 10.0 * k, [](double) { return Strand(400); });
    const WatchStatus& s = sim.state.status();
    ++windows;
    covered += std::abs(s.diameter_um - 400) <= s.diameter_ci95_um;
  }
  const double coverage = static_cast<double>(covered) / windows;
  // Against the nominal 95 %: with 400 windows the binomial σ of the coverage is 1.1 %. Above
  // 95 % + 3σ the interval is too wide (a CI of ±∞ would cover every window); below, the known
  // shortfall above is allowed down to 85 %.
  const double sigma = std::sqrt(0.95 * 0.05 / windows);
  EXPECT_GT(coverage, 0.85);
  EXPECT_LT(coverage, 0.95 + 3 * sigma);
  RecordProperty("coverage", std::to_string(coverage));
  std::cout << "coverage of the 95 % CI: " << coverage << "\n";
}

TEST(WatchStateTest, WarnWithinFiveSecondsOfAThreePercentDrop) {
  Simulation sim;
  sim.Run(0, 60, [](double) { return Strand(400); });
  EXPECT_EQ(sim.levels.size(), 0u);
  sim.Run(60, 90, [](double) { return Strand(388); });  // −3 %
  const auto warn = sim.FirstTimeAt(WatchLevel::kWarn);
  ASSERT_TRUE(warn.has_value());
  EXPECT_GT(*warn, 60.0 + sim.state.options().hold_s);  // not before the condition could hold
  EXPECT_LE(*warn, 65.0);
  EXPECT_FALSE(sim.FirstTimeAt(WatchLevel::kClog).has_value());
  const WatchStatus& s = sim.state.status();
  EXPECT_EQ(s.level, WatchLevel::kWarn);
  EXPECT_NEAR(s.drift_pct, -3.0, 0.3);
  EXPECT_LT(std::abs(s.drift_pct + 3.0), s.drift_ci95_pct + 0.3);
  EXPECT_NEAR(s.drift_um, -12.0, 1.2);
}

TEST(WatchStateTest, ClogAfterWarnAndBackToOkWithHysteresis) {
  WatchOptions o;
  o.hysteresis_pct = 1.0;  // bands: clog left above −4 %, warn above −1 %
  Simulation sim(o);
  sim.Run(0, 30, [](double) { return Strand(400); });
  sim.Run(30, 50, [](double) { return Strand(376); });  // −6 %
  const auto warn = sim.FirstTimeAt(WatchLevel::kWarn), clog = sim.FirstTimeAt(WatchLevel::kClog);
  ASSERT_TRUE(warn && clog);
  EXPECT_LE(*warn, *clog);
  EXPECT_LE(*clog, 36.0);
  // Back to −4.5 %: inside the clog's hysteresis band: stays clog.
  sim.Run(50, 70, [](double) { return Strand(382); });
  EXPECT_EQ(sim.state.status().level, WatchLevel::kClog);
  // −3 %: leaves clog for warn. −1.5 %: inside the warn band: stays warn.
  sim.Run(70, 90, [](double) { return Strand(388); });
  EXPECT_EQ(sim.state.status().level, WatchLevel::kWarn);
  sim.Run(90, 110, [](double) { return Strand(394); });
  EXPECT_EQ(sim.state.status().level, WatchLevel::kWarn);
  // Recovered: ok after hold_s.
  sim.Run(110, 130, [](double) { return Strand(400); });
  EXPECT_EQ(sim.state.status().level, WatchLevel::kOk);
  // Exactly four changes: warn, clog, warn, ok — no flapping at the thresholds.
  ASSERT_EQ(sim.levels.size(), 4u);
  EXPECT_EQ(sim.levels[2].second, WatchLevel::kWarn);
  EXPECT_EQ(sim.levels[3].second, WatchLevel::kOk);
}

TEST(WatchStateTest, ThirtyMinutesOfSteadyStrandWithOcclusionsAndAPurgeBlobRaiseNoAlert) {
  Simulation sim;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> uni(0, 1);
  // Occlusions: 0.2–1.5 s without anything recognisable, about once a minute.
  std::vector<std::pair<double, double>> occluded;
  for (double t = 20; t < 1800; t += 30 + 60 * uni(rng))
    occluded.emplace_back(t, 0.2 + 1.3 * uni(rng));
  const auto frame = [&](double t) -> std::pair<FrameView, double> {
    for (const auto& [t0, len] : occluded)
      if (t >= t0 && t < t0 + len) return {FrameView::kNothing, 0};
    // The purge blob (at 900 s, 2 s): mostly no strand under the nozzle, a third of the frames a
    // wild width where the blob's outline passes for edges.
    if (t >= 900 && t < 902)
      return uni(rng) < 0.33 ? Strand(250 + 400 * uni(rng))
                             : std::make_pair(FrameView::kNozzleOnly, 0.0);
    return Strand(400);
  };
  sim.Run(0, 1800, frame);
  EXPECT_EQ(sim.levels.size(), 0u)
      << "first change to " << (sim.levels.empty() ? "" : WatchLevelName(sim.levels[0].second))
      << " at " << (sim.levels.empty() ? 0 : sim.levels[0].first) << " s";
  // Memory stays bounded: the window holds window_s of frames, never the half hour.
  EXPECT_LE(sim.state.status().frames, 10 * kFps + 1);
}

TEST(WatchStateTest, NotExtrudingWhenOnlyTheNozzleIsSeenAndNoViewWhenNothingIs) {
  Simulation sim;
  sim.Run(0, 30, [](double) { return Strand(400); });
  sim.Run(30, 50, [](double) { return std::make_pair(FrameView::kNozzleOnly, 0.0); });
  const auto stop = sim.FirstTimeAt(WatchLevel::kNotExtruding);
  ASSERT_TRUE(stop.has_value());
  EXPECT_GT(*stop, 32.0);
  EXPECT_LT(*stop, 40.0);
  EXPECT_FALSE(sim.FirstTimeAt(WatchLevel::kWarn).has_value());
  sim.Run(50, 70, [](double) { return std::make_pair(FrameView::kNothing, 0.0); });
  EXPECT_EQ(sim.state.status().level, WatchLevel::kNoView);
  sim.Run(70, 90, [](double) { return Strand(400); });
  EXPECT_EQ(sim.state.status().level, WatchLevel::kOk);
}

TEST(WatchStateTest, ASourceThatGoesDownIsNoViewAfterTheHold) {
  Simulation sim;
  sim.Run(0, 30, [](double) { return Strand(400); });
  sim.state.SetSourceUp(false, 30.0);
  EXPECT_FALSE(sim.state.Tick(31.0));
  EXPECT_FALSE(sim.state.Tick(32.9));
  EXPECT_TRUE(sim.state.Tick(33.1));
  EXPECT_EQ(sim.state.status().level, WatchLevel::kNoView);
  EXPECT_EQ(sim.state.status().reason, "the source is down (reconnecting)");
  // Frames that simply stop coming (no word from the source) count as missing frames.
  Simulation quiet;
  quiet.Run(0, 30, [](double) { return Strand(400); });
  for (double t = 30; t < 45; t += 0.2)
    if (quiet.state.Tick(t)) quiet.levels.emplace_back(t, quiet.state.status().level);
  EXPECT_EQ(quiet.state.status().level, WatchLevel::kNoView);
  // …frames without a view: a silence after strand frames shows no nozzle that stopped.
  EXPECT_FALSE(quiet.FirstTimeAt(WatchLevel::kNotExtruding).has_value());
}

// An outage (a stream closed, or silent until its read timeout, then reopened with back-off) says
// no_view once it lasted hold_s, and the strand frames after it bring back the level from before:
// nothing else, however long it was. The window then holds strand frames from before and after;
// the time between is the outage's, not frames missing from a nozzle in view.
TEST(WatchStateTest, AnOutageInventsNoLevelChange) {
  for (const double stall_s : {0.0, 5.0}) {
    for (const double down_s : {1.0, 4.0, 15.0, 30.0}) {
      SCOPED_TRACE(testing::Message() << "silent " << stall_s << " s, down " << down_s << " s");
      Simulation sim;
      sim.Run(0, 30, [](double) { return Strand(400); });
      ASSERT_TRUE(sim.levels.empty());
      const double back_s = sim.Outage(30, stall_s, down_s);
      sim.Run(back_s, back_s + 20, [](double) { return Strand(400); });
      EXPECT_EQ(sim.state.status().level, WatchLevel::kOk);
      std::vector<WatchLevel> seen;
      for (const auto& [t, level] : sim.levels) seen.push_back(level);
      if (down_s < sim.state.options().hold_s) {
        EXPECT_TRUE(seen.empty()) << WatchLevelName(seen[0]) << " at " << sim.levels[0].first;
        continue;
      }
      ASSERT_EQ(seen, (std::vector<WatchLevel>{WatchLevel::kNoView, WatchLevel::kOk}))
          << WatchLevelName(seen[0]) << " at " << sim.levels[0].first << " s, then "
          << (seen.size() > 1 ? WatchLevelName(seen[1]) : "-") << " at "
          << (seen.size() > 1 ? sim.levels[1].first : 0) << " s";
      // Back to ok once the returning view held hold_s (plus a frame).
      EXPECT_LE(sim.levels[1].first, back_s + sim.state.options().hold_s + 0.1);
    }
  }
}

// A narrowed strand that was at warn before an outage is at warn after it: the view's return does
// not pass through ok while the alert window refills.
TEST(WatchStateTest, AWarnOutlivesAnOutage) {
  Simulation sim;
  sim.Run(0, 30, [](double) { return Strand(400); });
  sim.Run(30, 50, [](double) { return Strand(388); });  // −3 %
  ASSERT_EQ(sim.state.status().level, WatchLevel::kWarn);
  const size_t before = sim.levels.size();
  const double back_s = sim.Outage(50, 0, 10);
  sim.Run(back_s, back_s + 20, [](double) { return Strand(388); });
  std::vector<WatchLevel> after;
  for (size_t i = before; i < sim.levels.size(); ++i) after.push_back(sim.levels[i].second);
  EXPECT_EQ(after, (std::vector<WatchLevel>{WatchLevel::kNoView, WatchLevel::kWarn}));
}

// Before the first frame nothing is known: the level is `starting` and the source not up (the
// state /status and /metrics serve while a source opens); the first frame sets the first level
// without a level change (no `level` line, no --on-alert).
TEST(WatchStateTest, StartingUntilTheFirstFrame) {
  WatchState state(WatchOptions{}, pipeline::PlainScale(kScale));
  const auto metrics = [&] { return PrometheusText(state.status(), std::nullopt, {}); };
  EXPECT_EQ(state.status().level, WatchLevel::kStarting);
  EXPECT_FALSE(state.status().source_up);
  state.SetSourceUp(true, 0.0);  // opened, nothing delivered yet
  for (double t = 0; t < 12; t += 0.1) EXPECT_FALSE(state.Tick(t));
  EXPECT_EQ(state.status().level, WatchLevel::kStarting);
  EXPECT_FALSE(state.status().source_up);
  EXPECT_EQ(state.status().reason, "waiting for the first frame");
  const auto j = nlohmann::json::parse(StatusJson(state.status(), std::nullopt, {}, "status"));
  EXPECT_EQ(j["level"], "starting");
  EXPECT_EQ(j["source_up"], false);
  EXPECT_NE(metrics().find("clogscope_level{level=\"starting\"} 1\n"), std::string::npos);
  EXPECT_NE(metrics().find("clogscope_level{level=\"ok\"} 0\n"), std::string::npos);
  EXPECT_NE(metrics().find("clogscope_source_up 0\n"), std::string::npos) << metrics();

  EXPECT_FALSE(state.Add(12.0, FrameView::kStrand, 400 / kScale));
  EXPECT_EQ(state.status().level, WatchLevel::kOk);
  EXPECT_EQ(state.status().previous_level, WatchLevel::kStarting);
  EXPECT_EQ(state.status().level_changes, 0);
  EXPECT_TRUE(state.status().source_up);
  EXPECT_NE(metrics().find("clogscope_level{level=\"starting\"} 0\n"), std::string::npos);
  EXPECT_NE(metrics().find("clogscope_source_up 1\n"), std::string::npos);
}

// /metrics counts every level change, and as alerts only the changes into warn, clog,
// not_extruding or no_view (a return to ok is no alert), each by its level.
TEST(WatchStateTest, AlertsCountChangesIntoAlertLevelsNotReturnsToOk) {
  Simulation sim;
  sim.Run(0, 30, [](double) { return Strand(400); });
  sim.Run(30, 50, [](double) { return Strand(388); });   // −3 %: warn
  sim.Run(50, 80, [](double) { return Strand(400); });   // back to ok
  sim.Run(80, 100, [](double) { return Strand(370); });  // −7.5 %: clog
  std::map<WatchLevel, int> into;
  for (const auto& [t, l] : sim.levels) ++into[l];
  ASSERT_GE(into[WatchLevel::kOk], 1);
  ASSERT_GE(into[WatchLevel::kClog], 1);
  const WatchStatus& s = sim.state.status();
  EXPECT_EQ(s.level_changes, static_cast<int>(sim.levels.size()));
  const std::string metrics = PrometheusText(s, std::nullopt, {});
  EXPECT_NE(metrics.find(fmt::format("clogscope_level_changes_total {}\n", sim.levels.size())),
            std::string::npos)
      << metrics;
  for (WatchLevel l : kWatchLevels) {
    EXPECT_EQ(s.changes_into[static_cast<size_t>(l)], into[l]) << WatchLevelName(l);
    const std::string alerts =
        fmt::format("clogscope_alerts_total{{level=\"{}\"}}", WatchLevelName(l));
    if (IsAlertLevel(l))
      EXPECT_NE(metrics.find(fmt::format("{} {}\n", alerts, into[l])), std::string::npos)
          << metrics;
    else
      EXPECT_EQ(metrics.find(alerts), std::string::npos) << metrics;
  }
}

// The frame latency histogram: per bucket here, cumulative in /metrics, in seconds.
TEST(WatchStateTest, TheLatencyHistogramIsCumulativeInSeconds) {
  WatchCounters c;
  for (double s : {0.0004, 0.003, 0.003, 0.04, 3.0}) c.latency.Add(s);
  const std::string metrics = PrometheusText(WatchStatus{}, std::nullopt, c);
  for (const auto& [le, n] : std::vector<std::pair<std::string, int>>{
           {"0.0005", 1}, {"0.001", 1}, {"0.005", 3}, {"0.05", 4}, {"2", 4}, {"+Inf", 5}})
    EXPECT_NE(metrics.find(
                  fmt::format("clogscope_frame_latency_seconds_bucket{{le=\"{}\"}} {}\n", le, n)),
              std::string::npos)
        << le << "\n"
        << metrics;
  EXPECT_NE(metrics.find("clogscope_frame_latency_seconds_count 5\n"), std::string::npos);
  EXPECT_NE(metrics.find("clogscope_frame_latency_seconds_sum 3.0464"), std::string::npos)
      << metrics;
  EXPECT_NE(metrics.find("# TYPE clogscope_frame_latency_seconds histogram\n"), std::string::npos);
}

TEST(WatchStateTest, AGivenBaselineIsUsedFromTheFirstFrame) {
  WatchOptions o;
  o.baseline_um = 412;  // the strand at 400 µm is 2.9 % below it
  Simulation sim(o);
  sim.Run(0, 10, [](double) { return Strand(400); });
  EXPECT_EQ(sim.state.status().baseline_source, "given");
  EXPECT_NEAR(sim.state.status().drift_pct, 100 * (400.0 / 412 - 1),
              2 * sim.state.status().drift_ci95_pct);
  const auto warn = sim.FirstTimeAt(WatchLevel::kWarn);
  ASSERT_TRUE(warn.has_value());
  EXPECT_LT(*warn, 5.0);
  EXPECT_THROW(WatchState(o, std::nullopt), std::invalid_argument);  // needs a scale
}

TEST(WatchStateTest, InvalidThresholdsNameTheirOption) {
  const auto why = [](const std::function<void(WatchOptions&)>& change) {
    WatchOptions o;
    change(o);
    std::string w;
    EXPECT_FALSE(o.Validate(&w));
    return w;
  };
  EXPECT_NE(why([](WatchOptions& o) { o.clog_drift_pct = -1; }).find("--clog-pct"),
            std::string::npos);
  EXPECT_NE(why([](WatchOptions& o) { o.warn_drift_pct = 2; }).find("--warn-pct"),
            std::string::npos);
  EXPECT_NE(why([](WatchOptions& o) { o.hold_s = -1; }).find("--hold-s"), std::string::npos);
  EXPECT_NE(why([](WatchOptions& o) { o.alert_window_s = 20; }).find("--alert-window-s"),
            std::string::npos);
  EXPECT_NE(why([](WatchOptions& o) { o.hysteresis_pct = 3; }).find("--hysteresis-pct"),
            std::string::npos);
  WatchOptions zero_window;
  zero_window.window_s = 0;
  EXPECT_THROW(WatchState(zero_window, std::nullopt), std::invalid_argument);
}

// Without a scale the µm quantities are unknown: null in the status JSON (never 0.0), while the px
// quantities are there.
TEST(WatchStateTest, WithoutAScaleTheMicrometreFieldsAreNull) {
  WatchState state(WatchOptions{}, std::nullopt);
  for (int i = 0; i < 30 * 25; ++i) state.Add(i / 25.0, FrameView::kStrand, 100.0 + (i % 3));
  const WatchStatus& s = state.status();
  ASSERT_TRUE(s.has_diameter);
  ASSERT_TRUE(s.baseline_ready);
  ASSERT_FALSE(s.has_scale);
  const auto j = nlohmann::json::parse(StatusJson(s, std::nullopt, WatchCounters{}, "status"));
  // Widths cycle 100, 101, 102 px: any window's mean is within a third of a pixel-cycle of 101.
  EXPECT_NEAR(j["diameter"]["px"].get<double>(), 101.0, 0.01);
  EXPECT_NEAR(j["baseline"]["px"].get<double>(), 101.0, 0.01);
  for (const char* key : {"um", "ci95_um", "std_um"})
    EXPECT_TRUE(j["diameter"][key].is_null()) << key << ": " << j["diameter"][key];
  for (const char* key : {"um", "ci95_um"})
    EXPECT_TRUE(j["baseline"][key].is_null()) << key << ": " << j["baseline"][key];
  EXPECT_TRUE(j["drift"]["um"].is_null()) << j["drift"]["um"];
  EXPECT_NEAR(j["drift"]["pct"].get<double>(), 0.0, 0.02);
}

}  // namespace
}  // namespace clogscope::watch
