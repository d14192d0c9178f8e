#include "vision/motion/gear_speed.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "synthetic/synthetic.h"
#include "vision/motion/feed_speed.h"
#include "vision/scene/track.h"

namespace clogscope::vision {
namespace {

using synthetic::FeedstockScene;
using synthetic::FrameTruth;
using synthetic::FrameTruthFor;
using synthetic::RenderFrame;
using synthetic::SceneParams;

// The feedstock scene with its drive gear (synthetic.h): 2 mm tip radius, 100 px.
SceneParams GearScene(double surface_speed_mm_s) { return FeedstockScene(0, surface_speed_mm_s); }

GearSpeedOptions Options() {
  GearSpeedOptions o;
  o.roi = cv::Rect(70, 134, 213, 213);
  o.outer_radius_px = 100;
  return o;
}

// Each pair's error over its σ: their root mean square says whether σ is the size of the errors.
struct ErrorsOverSigma {
  double sum_sq = 0;
  int n = 0;
  double Rms() const { return std::sqrt(sum_sq / std::max(n, 1)); }
};

// Mean surface speed (mm/s) over `frames` − 1 pairs; every pair must be measured.
double MeanSurfaceSpeed(const SceneParams& p, const GearSpeedOptions& o, int frames,
                        ErrorsOverSigma* z = nullptr) {
  GearSpeedTracker tracker(o);
  double sum = 0;
  int valid = 0;
  for (int i = 0; i < frames; ++i) {
    FrameTruth t;
    const cv::Mat frame = RenderFrame(p, i, &t);  // fills t before t.time_s is read
    const GearSpeedSample s = tracker.Next(frame, t.time_s);
    if (i == 0) {
      EXPECT_EQ(s.reason, SpeedReason::kFirstFrame);
    }
    if (!s.valid) {
      if (i > 0) ADD_FAILURE() << SpeedReasonName(s.reason) << ": " << s.detail;
      continue;
    }
    ++valid;
    const double error_rad = s.rotation_rad - p.gear_surface_speed_mm_s / 30 / 2.0;
    EXPECT_LT(std::abs(error_rad), 3 * s.sigma_rad);  // σ not too small for any pair
    if (z) {
      z->sum_sq += std::pow(error_rad / s.sigma_rad, 2);
      ++z->n;
    }
    sum += s.RadPerS() * p.gear_radius_px * p.scale_um_per_px * 1e-3;
  }
  EXPECT_EQ(valid, frames - 1);
  return sum / std::max(valid, 1);
}

TEST(GearSpeedTest, RendererTurnsTheGearAtItsSurfaceSpeed) {
  const FrameTruth t = FrameTruthFor(GearScene(3.0), 30);  // 1 s
  EXPECT_NEAR(t.gear_angle_rad, 3.0 / 2.0, 1e-12);         // v / R, R = 2 mm
}

// Within 1 % of the surface speed over the roller-drive study's range; at rest, zero.
TEST(GearSpeedTest, RenderedSurfaceSpeedsWithinOnePercent) {
  ErrorsOverSigma z;
  for (double v : {0.5, 2.0, 5.0, 15.0, -4.0}) {
    EXPECT_NEAR(MeanSurfaceSpeed(GearScene(v), Options(), 11, &z), v, 0.01 * std::abs(v)) << v;
  }
  // …nor too large: a σ of 1 rad would pass every pair above. Against the rendered truth the
  // errors are about 0.6 σ (σ errs on the safe side); more than 2.5 σ apart would be no σ at all.
  std::printf("gear: rms error/sigma %.3f over %d pairs\n", z.Rms(), z.n);
  EXPECT_GT(z.Rms(), 0.4);
  EXPECT_LT(z.Rms(), 1.5);
  EXPECT_NEAR(MeanSurfaceSpeed(GearScene(0), Options(), 6), 0, 0.005);
}

// Slip 1 − v_filament / v_gear at the roller-drive study's slowest feed, where the filament moves
// under a pixel per frame: within ±0.5 percentage points for 0, 10 and 20 % slip. (With
// Catmull–Rom interpolation of the profiles the filament's speed carried a +0.5 % bias there, the
// same every frame, and slip came out 0.7–1.3 pp low.)
TEST(GearSpeedTest, SlipAtASlowFeedWithinHalfAPercentagePoint) {
  for (double slip_pct : {0.0, 10.0, 20.0}) {
    const double gear_mm_s = 0.5, feed_mm_s = gear_mm_s * (1 - slip_pct / 100);
    const SceneParams p = FeedstockScene(feed_mm_s, gear_mm_s);
    StrandMeasureOptions mo;
    mo.target = MeasureTarget::kFilament;
    StrandTracker strand(mo);
    FeedSpeedTracker feed(FeedSpeedOptions{});
    GearSpeedTracker gear(Options());
    double vf = 0, vg = 0;
    int pairs = 0;
    for (int i = 0; i < 21; ++i) {
      FrameTruth t;
      const cv::Mat frame = RenderFrame(p, i, &t);
      const FeedSpeedSample f = feed.Next(frame, t.time_s, strand.Measure(frame));
      const GearSpeedSample g = gear.Next(frame, t.time_s);
      if (i == 0) continue;
      ASSERT_TRUE(f.valid && g.valid)
          << SpeedReasonName(f.reason) << " " << SpeedReasonName(g.reason);
      vf += f.SpeedPxPerS() * p.scale_um_per_px * 1e-3;
      vg += std::abs(g.RadPerS()) * p.gear_radius_px * p.scale_um_per_px * 1e-3;
      ++pairs;
    }
    EXPECT_NEAR(100 * (1 - vf / vg), slip_pct, 0.5) << "slip " << slip_pct << " %";
  }
}

TEST(GearSpeedTest, TurnsBeyondTheSearchRangeAndROIsOffTheFrameGiveReasons) {
  GearSpeedOptions o = Options();
  o.max_rotation_deg = 2;  // 15 mm/s turns 14° per frame
  GearSpeedTracker fast(o);
  const SceneParams p = GearScene(15);
  fast.Next(RenderFrame(p, 0, nullptr), 0.0);
  EXPECT_EQ(fast.Next(RenderFrame(p, 1, nullptr), 1 / 30.0).reason, SpeedReason::kTooFast);
  o = Options();
  o.roi = cv::Rect(600, 400, 100, 100);
  GearSpeedTracker outside(o);
  EXPECT_EQ(outside.Next(RenderFrame(p, 0, nullptr), 0.0).reason, SpeedReason::kNoGear);
  std::string why;
  o.roi = cv::Rect(0, 0, 8, 8);
  EXPECT_FALSE(o.Validate(&why));
}

}  // namespace
}  // namespace clogscope::vision
