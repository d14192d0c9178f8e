// The pause decision under simulated time: the watch's levels and the printer's states fed in the
// order and at the times a live watch would see them.
#include "watch/pause_policy.h"

#include <gtest/gtest.h>

#include <vector>

namespace clogscope::watch {
namespace {

using L = WatchLevel;
using P = PrintState;

// A printer that does what it is told: a pause sent succeeds and leaves it paused.
struct Sim {
  PausePolicy policy;
  std::vector<double> pauses_s;  // when a pause went out

  explicit Sim(const PausePolicyOptions& o = {}) : policy(o) {}
  // Reports every 0.5 s from t0 to t1 at `level`, the printer in `state` throughout (a pause
  // sent turns it to paused, as Klipper does).
  P Run(double t0, double t1, L level, P state) {
    for (double t = t0; t < t1 - 1e-9; t += 0.5) {
      policy.OnPrinterState(t, state);
      if (policy.OnLevel(t, level)) {
        pauses_s.push_back(t);
        policy.OnPauseResult(t, true);
        state = P::kPaused;
      }
    }
    return state;
  }
};

TEST(PausePolicyTest, PausesOnceWhenTheLevelReachesClogWhilePrinting) {
  Sim sim;
  sim.Run(0, 10, L::kOk, P::kPrinting);
  sim.Run(10, 12, L::kWarn, P::kPrinting);  // warn does not pause at the default level
  EXPECT_TRUE(sim.pauses_s.empty());
  const P after = sim.Run(12, 30, L::kClog, P::kPrinting);
  ASSERT_EQ(sim.pauses_s.size(), 1u);
  EXPECT_DOUBLE_EQ(sim.pauses_s[0], 12.0);
  EXPECT_EQ(after, P::kPaused);
  EXPECT_EQ(sim.policy.pauses_requested(), 1);
}

TEST(PausePolicyTest, AWarnLevelPausesOnWarnAndClogAsOneEpisode) {
  PausePolicyOptions o;
  o.pause_level = L::kWarn;
  PausePolicy p(o);
  p.OnPrinterState(0, P::kPrinting);
  EXPECT_FALSE(p.OnLevel(1, L::kOk));
  EXPECT_TRUE(p.OnLevel(2, L::kWarn));
  p.OnPauseResult(2, true);
  // The printer has not said "paused" yet: still one episode, no second request.
  EXPECT_FALSE(p.OnLevel(3, L::kClog));
  EXPECT_FALSE(p.OnLevel(4, L::kWarn));
  EXPECT_EQ(p.pauses_requested(), 1);
}

TEST(PausePolicyTest, AResumeIsNotPausedAgainWithinTheHoldOffAndIsRearmedAfterIt) {
  PausePolicyOptions o;
  o.holdoff_s = 30;
  Sim sim(o);
  sim.Run(0, 10, L::kOk, P::kPrinting);
  sim.Run(10, 20, L::kClog, P::kPrinting);  // paused at 10 s
  ASSERT_EQ(sim.pauses_s.size(), 1u);
  // Resumed at 20 s while the strand still looks clogged: nothing until 50 s.
  EXPECT_TRUE(sim.policy.OnPrinterState(20, P::kPrinting));
  ASSERT_TRUE(sim.policy.holdoff_until_s());
  EXPECT_DOUBLE_EQ(*sim.policy.holdoff_until_s(), 50.0);
  sim.Run(20, 50, L::kClog, P::kPrinting);
  EXPECT_EQ(sim.pauses_s.size(), 1u);
  // The clog is still there after the hold-off: paused again, once.
  sim.Run(50, 70, L::kClog, P::kPrinting);
  ASSERT_EQ(sim.pauses_s.size(), 2u);
  EXPECT_DOUBLE_EQ(sim.pauses_s[1], 50.0);
}

TEST(PausePolicyTest, ANewEpisodeAfterTheHoldOffPausesAgain) {
  PausePolicyOptions o;
  o.holdoff_s = 10;
  Sim sim(o);
  sim.Run(0, 5, L::kClog, P::kPrinting);  // paused at 0
  EXPECT_TRUE(sim.policy.OnPrinterState(5, P::kPrinting));
  sim.Run(5, 30, L::kOk, P::kPrinting);  // cleared
  sim.Run(30, 40, L::kClog, P::kPrinting);
  ASSERT_EQ(sim.pauses_s.size(), 2u);
  EXPECT_DOUBLE_EQ(sim.pauses_s[1], 30.0);
}

TEST(PausePolicyTest, DisarmedWhileNotPrinting) {
  for (const P state : {P::kUnknown, P::kIdle, P::kPaused}) {
    PausePolicy p({});
    p.OnPrinterState(0, state);
    EXPECT_FALSE(p.armed()) << PrintStateName(state);
    EXPECT_FALSE(p.OnLevel(1, L::kClog)) << PrintStateName(state);
    // Armed as soon as it prints, the clog still there: paused then (no hold-off for a start).
    p.OnPrinterState(2, P::kPrinting);
    EXPECT_TRUE(p.armed());
    EXPECT_EQ(p.OnLevel(3, L::kClog), state != P::kPaused) << PrintStateName(state);
  }
  // An unanswered question in the middle disarms, and no resume is made of it.
  PausePolicy p({});
  p.OnPrinterState(0, P::kPrinting);
  p.OnPrinterState(1, P::kUnknown);
  EXPECT_FALSE(p.OnLevel(2, L::kClog));
  EXPECT_FALSE(p.OnPrinterState(3, P::kPrinting));
  EXPECT_TRUE(p.OnLevel(4, L::kClog));
}

TEST(PausePolicyTest, ViewLevelsNeverPause) {
  PausePolicyOptions o;
  o.pause_level = L::kWarn;
  PausePolicy p(o);
  p.OnPrinterState(0, P::kPrinting);
  for (const L level : {L::kStarting, L::kOk, L::kNotExtruding, L::kNoView})
    EXPECT_FALSE(p.OnLevel(1, level)) << WatchLevelName(level);
}

TEST(PausePolicyTest, AFailedPauseIsRetriedAfterTheRetryIntervalWithinTheEpisode) {
  PausePolicyOptions o;
  o.retry_s = 5;
  PausePolicy p(o);
  p.OnPrinterState(0, P::kPrinting);
  EXPECT_TRUE(p.OnLevel(10, L::kClog));
  // While the request is out, nothing more.
  EXPECT_FALSE(p.OnLevel(10.5, L::kClog));
  p.OnPauseResult(11, false);
  EXPECT_FALSE(p.OnLevel(12, L::kClog));
  EXPECT_FALSE(p.OnLevel(15.9, L::kClog));
  EXPECT_TRUE(p.OnLevel(16, L::kClog));
  p.OnPauseResult(16, true);
  EXPECT_FALSE(p.OnLevel(30, L::kClog));
  EXPECT_EQ(p.pauses_requested(), 2);
}

TEST(PausePolicyTest, AJobThatEndsWhilePausedIsNoResume) {
  PausePolicy p({});
  p.OnPrinterState(0, P::kPrinting);
  EXPECT_TRUE(p.OnLevel(1, L::kClog));
  p.OnPauseResult(1, true);
  p.OnPrinterState(2, P::kPaused);
  p.OnPrinterState(3, P::kIdle);                    // cancelled
  EXPECT_FALSE(p.OnPrinterState(4, P::kPrinting));  // a new job: no hold-off
  EXPECT_FALSE(p.holdoff_until_s());
}

// Resumed, then cancelled and a new print started within the resume's hold-off: the new job's
// clog pauses it at once (the hold-off, and the episode's pause, were the old job's).
TEST(PausePolicyTest, ANewJobWithinTheOldOnesHoldOffIsPausedOnItsClog) {
  Sim sim;  // hold-off 60 s
  sim.Run(0, 5, L::kOk, P::kPrinting);
  sim.Run(5, 6, L::kClog, P::kPrinting);  // paused at 5 s
  sim.Run(6, 8, L::kClog, P::kPaused);
  sim.Run(8, 10, L::kClog, P::kPrinting);  // resumed at 8 s: held off until 68 s
  ASSERT_EQ(sim.pauses_s.size(), 1u);
  sim.Run(10, 12, L::kClog, P::kIdle);  // cancelled
  sim.Run(12, 15, L::kOk, P::kPrinting);
  sim.Run(15, 16, L::kClog, P::kPrinting);
  ASSERT_EQ(sim.pauses_s.size(), 2u);
  EXPECT_DOUBLE_EQ(sim.pauses_s[1], 15.0);
}

TEST(PausePolicyTest, OptionsNameTheirFlag) {
  std::string why;
  PausePolicyOptions o;
  EXPECT_TRUE(o.Validate(&why));
  o.pause_level = L::kNoView;
  EXPECT_FALSE(o.Validate(&why));
  EXPECT_NE(why.find("--pause-level"), std::string::npos);
  o = {};
  o.holdoff_s = -1;
  EXPECT_FALSE(o.Validate(&why));
  EXPECT_NE(why.find("--pause-holdoff-s"), std::string::npos);
  WatchLevel level = L::kOk;
  EXPECT_TRUE(ParsePauseLevel("warn", &level));
  EXPECT_EQ(level, L::kWarn);
  EXPECT_FALSE(ParsePauseLevel("no_view", &level));
}

}  // namespace
}  // namespace clogscope::watch
