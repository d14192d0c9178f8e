#include "vision/scene/track.h"

#include <gtest/gtest.h>

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
