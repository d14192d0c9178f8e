#include "vision/scene/track.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "synthetic/synthetic.h"

namespace clogscope::vision {
namespace {

using synthetic::FrameTruth;
using synthetic::RenderFrame;
using synthetic::SceneParams;

// Tracking must give the widths a fresh search gives, while searching only when it must.
TEST(StrandTrackerTest, TrackedWidthsMatchFreshSearchesWithFewDetections) {
  SceneParams p;
  p.width_jitter_um = 3;
  p.sway_deg = 0.4;
  p.tilt_deg = 5;
  StrandTracker tracker({});
  for (int i = 0; i < 20; ++i) {
    FrameTruth t;
    const cv::Mat img = RenderFrame(p, i, &t);
    const StrandMeasurement tracked = tracker.Measure(img);
    const StrandMeasurement fresh = MeasureStrand(img, {});
    ASSERT_TRUE(tracked.valid()) << i << ": " << tracked.detail;
    ASSERT_TRUE(fresh.valid()) << i << ": " << fresh.detail;
    EXPECT_NEAR(tracked.width_px, t.width_px, 0.06) << "frame " << i;
    EXPECT_NEAR(tracked.width_px, fresh.width_px, 0.05) << "frame " << i;
    EXPECT_NEAR(tracked.tip_y_px, t.tip_y_px, 1.5) << "frame " << i;
  }
  EXPECT_LE(tracker.full_detections(), 2);
  EXPECT_GE(tracker.tracked_frames(), 18);
}

// A lit filament (Lambertian shading, surface texture) feeding down, its width wandering by
// 2 µm (0.1 px at 20 µm/px: within a template's reach), and its whole stretch measured.
SceneParams LitFilament() {
  SceneParams p = synthetic::FeedstockScene(2.0);
  p.shading_ambient = 0.5;
  p.width_jitter_um = 2;
  return p;
}
StrandMeasureOptions WholeStretch() {
  StrandMeasureOptions o;
  o.target = MeasureTarget::kFilament;
  o.band_start_px = 0;
  o.band_height_px = 1e6;
  return o;
}

// A lit filament (Lambertian shading, surface texture) feeding down a rendered video whose width
// wanders by a few µm: tracked, its calipers' lit cylinders are fitted from the templates the
// first frame left (cylinder_memory.h), and the widths are the rendered ones as closely as the
// full measurement of each frame gets them.
TEST(StrandTrackerTest, FilamentFromCylinderTemplatesMatchesTheTruth) {
  const SceneParams p = LitFilament();
  const StrandMeasureOptions o = WholeStretch();
  StrandTracker tracker(o);
  constexpr int kFrames = 24;
  double worst_tracked = 0, worst_fresh = 0;
  for (int i = 0; i < kFrames; ++i) {
    FrameTruth t;
    const cv::Mat img = RenderFrame(p, i, &t);
    const StrandMeasurement tracked = tracker.Measure(img);
    const StrandMeasurement fresh = MeasureStrand(img, o);
    ASSERT_TRUE(tracked.valid()) << i << ": " << tracked.detail;
    ASSERT_TRUE(fresh.valid()) << i << ": " << fresh.detail;
    EXPECT_NEAR(tracked.width_px, t.width_px, 0.05) << "frame " << i;
    EXPECT_NEAR(fresh.width_px, t.width_px, 0.05) << "frame " << i;
    worst_tracked = std::max(worst_tracked, std::abs(tracked.width_px - t.width_px));
    worst_fresh = std::max(worst_fresh, std::abs(fresh.width_px - t.width_px));
  }
  std::printf(
      "worst |width - truth|: tracked %.4f px, full %.4f px; %d of %d frames from "
      "templates\n",
      worst_tracked, worst_fresh, tracker.cylinders().frames_from_templates, kFrames);
  EXPECT_LE(tracker.full_detections(), 2);
  // All but the first two frames from them: the first is found afresh (no templates kept), the
  // second measured in full (which keeps them). Measured: 22 of 24.
  EXPECT_GE(tracker.cylinders().frames_from_templates, kFrames - 3);
}

// The same filament on a black background (level 1, noise 3): a third of the background's pixels
// are clipped at 0, a few blurs beyond the silhouettes. The frame measured in full judges
// clipping in each edge's transition; the templates judged it over their whole slab, background
// included (10 % of it clipped), refused the tracked frames as saturated, and the tracker searched
// 6 of 12 frames afresh.
TEST(StrandTrackerTest, FilamentFromTemplatesJudgesClippingAtItsEdges) {
  SceneParams p = LitFilament();
  p.background_level = 1;
  StrandTracker tracker(WholeStretch());
  constexpr int kFrames = 12;
  for (int i = 0; i < kFrames; ++i) {
    FrameTruth t;
    const cv::Mat img = RenderFrame(p, i, &t);
    const StrandMeasurement tracked = tracker.Measure(img);
    ASSERT_TRUE(tracked.valid()) << i << ": " << tracked.detail;
    EXPECT_NEAR(tracked.width_px, t.width_px, 0.05) << "frame " << i;
  }
  EXPECT_LE(tracker.full_detections(), 2);
  EXPECT_GE(tracker.cylinders().frames_from_templates, kFrames - 3);
}

// Frame i of the lit filament, with a gear tooth over its left silhouette (a dark block across it
// at the middle of the stretch) in frames tooth_from ≤ i < tooth_until, measured by the tracker:
// valid, and the rendered width within 0.05 px.
StrandMeasurement MeasureLitFilamentFrame(StrandTracker* tracker, int i, int tooth_from,
                                          int tooth_until) {
  FrameTruth t;
  cv::Mat img = RenderFrame(LitFilament(), i, &t);
  if (i >= tooth_from && i < tooth_until) {
    const int left = static_cast<int>(std::lround(t.tip_x_px - 0.5 * t.width_px));
    cv::rectangle(img, cv::Rect(left - 12, img.rows / 2, 24, 16), cv::Scalar::all(0), cv::FILLED);
  }
  const StrandMeasurement m = tracker->Measure(img);
  EXPECT_TRUE(m.valid()) << i << ": " << m.detail;
  EXPECT_NEAR(m.width_px, t.width_px, 0.05) << "frame " << i;
  return m;
}

// The lit filament's frames 0 … frames − 1 with a gear tooth over its left silhouette in frames
// tooth_from ≤ i < tooth_until, tracked: fewer calipers used than in the frame before the tooth
// while fewer_until > i ≥ tooth_from, all of them again from frame back_from on, and at most two
// searches afresh.
void ExpectToothCostsCalipers(int frames, int tooth_from, int tooth_until, int fewer_until,
                              int back_from) {
  StrandTracker tracker(WholeStretch());
  int calipers_clean = 0;
  for (int i = 0; i < frames; ++i) {
    const StrandMeasurement m = MeasureLitFilamentFrame(&tracker, i, tooth_from, tooth_until);
    if (::testing::Test::HasFailure()) return;
    if (i == tooth_from - 1) calipers_clean = m.calipers_used;
    if (i >= tooth_from && i < fewer_until) {
      EXPECT_LT(m.calipers_used, calipers_clean) << i;
    }
    if (i >= back_from) {
      EXPECT_EQ(m.calipers_used, calipers_clean) << i;
    }
  }
  EXPECT_LE(tracker.full_detections(), 2);
}

// A gear tooth over the left silhouette for three frames (a dark block across it at the middle of
// the stretch): the calipers it spoils fail their full fits and rest (CylinderMemory::kRestFrames)
// instead of being fitted in full again in every frame; once it has gone they are fitted again
// and count again. The widths stay the rendered ones throughout.
TEST(StrandTrackerTest, FilamentCalipersSpoiledForAWhileRestThenReturn) {
  constexpr int kFrames = 16, kToothFrom = 3, kToothUntil = 6;
  ExpectToothCostsCalipers(kFrames, kToothFrom, kToothUntil, kToothUntil,
                           kToothUntil + CylinderMemory::kRestFrames);
}

// A tooth that stays over the silhouette longer than one rest: the calipers it spoils fail their
// full fit again when their first rest ends, and rest twice as long (CylinderMemory::
// kMaxRestDoublings), so they come back 8 frames after that second failure, not 4 after the tooth
// has gone.
TEST(StrandTrackerTest, FilamentCalipersFailingAgainRestTwiceAsLong) {
  constexpr int kToothFrom = 3, kToothUntil = 10;  // first failure 3, again at 3 + 1 + 4 = 8
  constexpr int kBack = 8 + 1 + 2 * CylinderMemory::kRestFrames, kFrames = kBack + 2;
  // Gone at 10, but resting until 16 (a single rest of 4 would have tried them again at 13).
  ExpectToothCostsCalipers(kFrames, kToothFrom, kToothUntil, kBack, kBack);
}

TEST(StrandTrackerTest, LosesTheStrandAndFindsItAgain) {
  SceneParams p;
  StrandTracker tracker({});
  ASSERT_TRUE(tracker.Measure(RenderFrame(p, 0, nullptr)).valid());
  const cv::Mat blank(p.height_px, p.width_px, CV_8UC1, cv::Scalar(40));
  const StrandMeasurement lost = tracker.Measure(blank);
  EXPECT_EQ(lost.status, FrameStatus::kNoStrand);
  // The strand comes back 60 px further right: found again by a fresh search.
  p.tip_x_px += 60;
  FrameTruth t;
  const StrandMeasurement back = tracker.Measure(RenderFrame(p, 1, &t));
  ASSERT_TRUE(back.valid()) << back.detail;
  EXPECT_NEAR(back.tip_x_px, t.tip_x_px, 1.0);
  EXPECT_NEAR(back.width_px, t.width_px, 0.06);
}

}  // namespace
}  // namespace clogscope::vision
