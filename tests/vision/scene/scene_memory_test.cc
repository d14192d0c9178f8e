#include "vision/scene/scene_memory.h"

#include <gtest/gtest.h>

#include "synthetic/synthetic.h"

namespace clogscope::vision {
namespace {

using synthetic::FrameTruth;
using synthetic::RenderFrame;
using synthetic::SceneParams;

SceneParams Scene() {
  SceneParams s;
  s.width_px = 640;
  s.height_px = 360;
  s.tip_x_px = 320;
  s.tip_y_px = 120;
  s.texture_amplitude = 12;  // something for the correlation to hold on to
  return s;
}

cv::Mat Render(const SceneParams& s, int frame = 0) {
  FrameTruth t;
  return RenderFrame(s, frame, &t);
}

TEST(SceneMemoryTest, TheNozzleWithoutAStrandIsToldFromALostView) {
  StrandMeasureOptions o;
  const cv::Mat with = Render(Scene());
  const StrandMeasurement m = MeasureStrand(with, o);
  ASSERT_TRUE(m.valid()) << m.detail;
  SceneMemory memory(MeasureTarget::kStrand);
  EXPECT_FALSE(memory.SeesNozzle(with));  // nothing remembered yet
  memory.Remember(with, m);
  ASSERT_FALSE(memory.empty());
  // The same nozzle, nothing below it (new noise): seen.
  SceneParams stopped = Scene();
  stopped.strand = false;
  const cv::Mat nozzle_only = Render(stopped, 7);
  EXPECT_FALSE(MeasureStrand(nozzle_only, o).valid());
  EXPECT_TRUE(memory.SeesNozzle(nozzle_only));
  // No nozzle, a dark frame, a different scene (the camera moved by 60 px): not seen.
  SceneParams gone = Scene();
  gone.nozzle = false;
  gone.strand = false;
  EXPECT_FALSE(memory.SeesNozzle(Render(gone)));
  EXPECT_FALSE(memory.SeesNozzle(cv::Mat(360, 640, CV_8UC1, cv::Scalar(3))));
  SceneParams moved = Scene();
  moved.tip_x_px += 60;
  moved.strand = false;
  EXPECT_FALSE(memory.SeesNozzle(Render(moved)));
  // A filament has no nozzle: nothing is remembered.
  SceneMemory filament(MeasureTarget::kFilament);
  filament.Remember(with, m);
  EXPECT_TRUE(filament.empty());
}

}  // namespace
}  // namespace clogscope::vision
