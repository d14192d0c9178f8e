#include "vision/scene/edge_segments.h"

#include <gtest/gtest.h>

#include <cmath>

#include "synthetic/synthetic.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {
namespace {

// An upright strand of known edges and noise: the detection's noise is the rendered noise at the
// detection scale, and every sampled row below the tip has a point on each edge, of the edge's
// sign, where the renderer put it. 8-bit frames (noise read off counts of whole levels) and the
// same frames as 16-bit (read off the values themselves) alike.
TEST(DetectEdgePointsTest, NoiseAndEdgesAreTheRenderedOnes) {
  for (double noise : {2.0, 6.0}) {
    synthetic::SceneParams p;
    p.noise_sigma = noise;
    p.tilt_deg = 0;
    p.sway_deg = 0;
    synthetic::FrameTruth t;
    const cv::Mat frame8 = synthetic::RenderFrame(p, 0, &t);
    cv::Mat frame16;
    frame8.convertTo(frame16, CV_16U, 256.0);
    for (const cv::Mat* frame : {&frame8, static_cast<const cv::Mat*>(&frame16)}) {
      const double scale = frame->depth() == CV_16U ? 256.0 : 1.0;
      StrandMeasureOptions o;
      const Detection d = DetectEdgePoints(*frame, SceneOptionsFor(o, DataMax(*frame)));
      ASSERT_EQ(d.factor, 2);
      // White noise of σ averaged over 2×2 px: σ/2, and the 8-bit rounding's 1/12 grey².
      const double expected = std::sqrt(noise * noise / 4 + 1.0 / 12) * scale;
      EXPECT_NEAR(d.noise / 0.433, expected, 0.12 * expected)
          << "noise " << noise << ", " << (scale > 1 ? "16" : "8") << " bit";
      // Full px x = 2·x_d + 0.5 (ToSegment).
      const double left = (t.tip_x_px - 0.5 * t.width_px - 0.5) / 2;
      const double right = (t.tip_x_px + 0.5 * t.width_px - 0.5) / 2;
      int rows = 0;
      for (size_t r = 0; r < d.rows.size(); ++r) {
        if (2 * d.row_y[r] < t.tip_y_px + 40) continue;  // below the tip and its corners
        ++rows;
        bool found_left = false, found_right = false;
        for (const EdgePoint& e : d.rows[r]) {
          found_left = found_left || (std::abs(e.x - left) < 0.35 && e.sign == +1);  // brighter to +x
          found_right = found_right || (std::abs(e.x - right) < 0.35 && e.sign == -1);
        }
        EXPECT_TRUE(found_left && found_right) << "row " << d.row_y[r] << ", noise " << noise;
      }
      EXPECT_GT(rows, 50);
    }
  }
}

}  // namespace
}  // namespace clogscope::vision
