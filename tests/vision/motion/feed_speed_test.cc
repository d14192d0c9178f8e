#include "vision/motion/feed_speed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "synthetic/synthetic.h"
#include "vision/scene/track.h"

namespace clogscope::vision {
namespace {

using synthetic::FeedstockScene;
using synthetic::FrameTruth;
using synthetic::FrameTruthFor;
using synthetic::RenderFrame;
using synthetic::SceneParams;

// The feedstock scene (synthetic.h) with its texture and tilt varied.
SceneParams Filament(double speed_mm_s, double texture = 8, double tilt_deg = 0) {
  SceneParams p = FeedstockScene(speed_mm_s);
  p.surface_texture_amplitude = texture;
  p.tilt_deg = tilt_deg;
  return p;
}

StrandMeasureOptions FilamentOptions() {
  StrandMeasureOptions o;
  o.target = MeasureTarget::kFilament;
  return o;
}

// Frames through the filament tracker and a FeedSpeedTracker, as `measure --speed` takes them.
class FilamentSpeeds {
 public:
  explicit FilamentSpeeds(const FeedSpeedOptions& fo = {})
      : strand_(FilamentOptions()), speed_(fo) {}
  FeedSpeedSample Next(const cv::Mat& frame, double time_s) {
    return speed_.Next(frame, time_s, strand_.Measure(frame));
  }
  // Frame i of p, rendered.
  FeedSpeedSample Next(const SceneParams& p, int i) {
    FrameTruth t;
    const cv::Mat f = RenderFrame(p, i, &t);
    return Next(f, t.time_s);
  }

 private:
  StrandTracker strand_;
  FeedSpeedTracker speed_;
};

struct SpeedRun {
  int valid = 0, pairs = 0, within_4_sigma = 0;
  double error_over_sigma_sq = 0;  // Σ (error / σ)² over the valid pairs
  double mean_speed_mm_s = 0;
  AxisShift last;
};

SpeedRun MeasureSpeeds(const SceneParams& p, int frames, const FeedSpeedOptions& fo = {}) {
  StrandTracker tracker(FilamentOptions());
  cv::Mat prev;
  StrandMeasurement prev_m;
  FrameTruth prev_t;
  SpeedRun r;
  for (int i = 0; i < frames; ++i) {
    FrameTruth t;
    const cv::Mat f = RenderFrame(p, i, &t);
    const StrandMeasurement m = tracker.Measure(f);
    EXPECT_TRUE(m.valid()) << m.detail;
    if (i > 0) {
      ++r.pairs;
      r.last = EstimateFeedShift(prev, f, prev_m, fo);
      if (r.last.valid()) {
        ++r.valid;
        const double truth = t.feed_offset_px - prev_t.feed_offset_px;
        r.within_4_sigma += std::abs(r.last.shift_px - truth) <= 4 * r.last.sigma_px;
        r.error_over_sigma_sq += std::pow((r.last.shift_px - truth) / r.last.sigma_px, 2);
        r.mean_speed_mm_s +=
            r.last.shift_px * p.scale_um_per_px * 1e-3 / (t.time_s - prev_t.time_s);
      }
    }
    prev = f;
    prev_m = m;
    prev_t = t;
  }
  if (r.valid > 0) r.mean_speed_mm_s /= r.valid;
  return r;
}

TEST(FeedSpeedTest, RendererMovesTheSurfaceAtTheFeedSpeed) {
  const SceneParams p = Filament(6);
  const FrameTruth t = FrameTruthFor(p, 45);
  EXPECT_DOUBLE_EQ(t.time_s, 1.5);
  EXPECT_NEAR(t.feed_offset_px, 6 * 1.5 * 1e3 / 20, 1e-12);  // 450 px
}

// Within 1 % of the speed, or 0.02 mm/s at the lowest; every pair measured, and the per-pair σ
// covers its error.
TEST(FeedSpeedTest, RenderedSpeedsWithinOnePercent) {
  double z_sq = 0;
  int n = 0;
  for (double v : {0.5, 2.0, 5.0, 15.0}) {
    const SpeedRun r = MeasureSpeeds(Filament(v), 16);
    EXPECT_EQ(r.valid, r.pairs) << v << " mm/s: " << r.last.detail;
    EXPECT_NEAR(r.mean_speed_mm_s, v, std::max(0.01 * v, 0.02)) << v << " mm/s";
    EXPECT_GE(r.within_4_sigma, r.valid - 1) << v << " mm/s";
    z_sq += r.error_over_sigma_sq;
    n += r.valid;
  }
  // σ is the size of the errors against the rendered truth (about 0.6 σ: on the safe side), not
  // so large that "within 4 σ" says nothing.
  std::printf("feed: rms error/sigma %.3f over %d pairs\n", std::sqrt(z_sq / n), n);
  EXPECT_GT(std::sqrt(z_sq / n), 0.4);
  EXPECT_LT(std::sqrt(z_sq / n), 1.5);
  const SpeedRun tilted = MeasureSpeeds(Filament(2.0, 8, 7), 16);
  EXPECT_NEAR(tilted.mean_speed_mm_s, 2.0, 0.02);
}

TEST(FeedSpeedTest, AFilamentAtRestReadsZero) {
  const SpeedRun r = MeasureSpeeds(Filament(0), 16);
  EXPECT_EQ(r.valid, r.pairs);
  EXPECT_NEAR(r.mean_speed_mm_s, 0, 0.005);
}

TEST(FeedSpeedTest, AFeaturelessFilamentHasNoSpeed) {
  const SpeedRun r = MeasureSpeeds(Filament(2.0, 0), 6);
  EXPECT_EQ(r.valid, 0);
  EXPECT_EQ(r.last.status, FeedShiftStatus::kNoTexture);
  EXPECT_NE(r.last.detail.find("noise"), std::string::npos) << r.last.detail;
}

TEST(FeedSpeedTest, BeyondTheSearchRangeIsTooFast) {
  FeedSpeedOptions fo;
  fo.max_shift_px = 10;  // 6 mm/s at these settings; the filament runs at 15
  const SpeedRun r = MeasureSpeeds(Filament(15.0), 4, fo);
  EXPECT_EQ(r.valid, 0);
  EXPECT_EQ(r.last.status, FeedShiftStatus::kTooFast);
}

// The tracker along a video with dropped frames: each pair's speed comes from the frames' own
// timestamps, not a nominal rate; the axis sways by 0.3° per frame, so the reference geometry is
// renewed along the way.
TEST(FeedSpeedTest, TrackerUsesTheFramesOwnTimesAndFollowsTheAxis) {
  SceneParams p = Filament(4.0);
  p.sway_deg = 0.3;
  FilamentSpeeds speed;
  double sum = 0;
  int valid = 0;
  for (int i : {0, 1, 3, 4, 7, 8, 9, 12, 13, 15}) {
    const FeedSpeedSample v = speed.Next(p, i);
    if (i == 0) {
      EXPECT_EQ(v.reason, SpeedReason::kFirstFrame);
    }
    if (!v.valid) continue;
    ++valid;
    sum += v.SpeedPxPerS() * p.scale_um_per_px * 1e-3;
  }
  EXPECT_EQ(valid, 9);
  EXPECT_NEAR(sum / valid, 4.0, 0.04);
  // Still images have no times: no speed, a reason.
  FilamentSpeeds still;
  const cv::Mat f = RenderFrame(p, 0, nullptr);
  EXPECT_EQ(still.Next(f, -1).reason, SpeedReason::kNoTime);
  EXPECT_EQ(still.Next(f, -1).reason, SpeedReason::kNoTime);
}

// The reasons' words are those of measure's speed_reason and gear_reason columns.
TEST(SpeedReasonTest, EachReasonHasItsWord) {
  const std::vector<std::pair<SpeedReason, std::string>> words = {
      {SpeedReason::kFirstFrame, "first_frame"}, {SpeedReason::kNoTime, "no_time"},
      {SpeedReason::kBadTime, "bad_time"},       {SpeedReason::kNoStrand, "no_strand"},
      {SpeedReason::kNoTexture, "no_texture"},   {SpeedReason::kTooFast, "too_fast"},
      {SpeedReason::kNoGear, "no_gear"}};
  for (const auto& [reason, word] : words) EXPECT_EQ(SpeedReasonName(reason), word);
}

// A slow filament (0.3 mm/s, 0.5 px per frame): each frame is compared with the one 16 back (8 px)
// once there is one, with every earlier frame before that; the speeds over 16 frames are within
// 0.2 % of the truth.
TEST(FeedSpeedTest, TrackerComparesASlowFilamentOverLongerBaselines) {
  const SceneParams p = Filament(0.3);
  FilamentSpeeds speed;
  double sum = 0;
  int full = 0;
  for (int i = 0; i < 24; ++i) {
    const FeedSpeedSample v = speed.Next(p, i);
    if (i == 0) continue;
    ASSERT_TRUE(v.valid) << i << ": " << v.detail;
    EXPECT_EQ(v.wanted_baseline_frames, 16) << i;
    EXPECT_EQ(v.baseline_frames, std::min(i, 16)) << i;
    EXPECT_NEAR(v.dt_s, v.baseline_frames / 30.0, 1e-9) << i;
    if (v.baseline_frames < 16) continue;
    ++full;
    sum += v.SpeedPxPerS() * p.scale_um_per_px * 1e-3;
  }
  EXPECT_EQ(full, 8);
  EXPECT_NEAR(sum / full, 0.3, 0.0006);
  // Comparing consecutive frames only (the former behaviour) is an option.
  FeedSpeedOptions one;
  one.baseline_shift_px = 0;
  FilamentSpeeds consecutive(one);
  for (int i = 0; i < 3; ++i) {
    const FeedSpeedSample v = consecutive.Next(p, i);
    if (i > 0) {
      EXPECT_EQ(v.baseline_frames, 1);
    }
  }
}

}  // namespace
}  // namespace clogscope::vision
