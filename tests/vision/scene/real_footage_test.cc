// Real footage nobody here designed the measurement around (testdata/README.md, real/greeff).
#include <gtest/gtest.h>

#include <cmath>

#include "vision/io/frame_source.h"
#include "vision/motion/feed_speed.h"
#include "vision/scene/batch.h"

namespace clogscope::vision {
namespace {

const std::string kGreeff =
    std::string(CLOGSCOPE_TESTDATA_DIR) + "/real/greeff/Test_2017_04_12__10_38_57.avi";

// As `measure --target filament` with no band given: the whole stretch.
StrandMeasureOptions FilamentOptions() {
  StrandMeasureOptions o;
  o.target = MeasureTarget::kFilament;
  const BandPx band = DefaultBand(o.target, kNominalScaleUmPerPx);
  o.band_start_px = band.start_px;
  o.band_height_px = band.height_px;
  return o;
}

// White PLA at rest between a knurled drive gear and an idler, no nozzle, no ROI. Their tool:
// 137.08 px, frame-to-frame σ 0.27 px (the largest gradient of the column mean of rows 11–51,
// above the gear; re-implemented on these 281 frames it gives 137.17 px); the spool: 2.85 ±
// 0.05 mm = 138.3 ± 2.4 px at their 0.0206 mm/px. Below the gear's grip the knurl has marked the
// filament's left edge (a saw tooth ~13 px deep): the width is taken on the straight part above
// (straight_run.h). Our edges are the silhouette of a shaded cylinder, a little outside the
// steepest point of its blurred edge.
// The filament does not move: its feed speed from consecutive frames must read 0 ± 0.05 mm/s on at
// least 95 % of the frame pairs (the feedstock issue's target).
TEST(RealFootageTest, GreeffFilamentWithoutRoi) {
  auto source = FrameSource::Open(kGreeff);
  const StrandMeasureOptions o = FilamentOptions();
  int frames = 0, valid = 0, pairs = 0, at_rest = 0;
  double s1 = 0, s2 = 0;
  cv::Mat previous;
  StrandMeasurement previous_m;
  double previous_t = 0;
  MeasureFrames(*source, o, [&](InputFrame& f, StrandMeasurement& m) {
    ++frames;
    if (!previous.empty() && previous_m.valid()) {
      ++pairs;
      const AxisShift shift = EstimateFeedShift(previous, f.image, previous_m, FeedSpeedOptions{});
      const double speed_mm_s = shift.shift_px * 0.0206 / (f.time_s - previous_t);
      at_rest += shift.valid() && std::abs(speed_mm_s) <= 0.05;
    }
    previous = f.image.clone();
    previous_m = m;
    previous_t = f.time_s;
    if (!m.valid()) return;
    ++valid;
    s1 += m.width_px;
    s2 += m.width_px * m.width_px;
    EXPECT_NEAR(m.angle_deg, 0.9, 1.0);  // the filament leans about 1° in this view
  });
  ASSERT_EQ(frames, 281);
  const double mean = s1 / valid, sd = std::sqrt(std::max(0.0, s2 / valid - mean * mean));
  // Measured: 281 of 281 valid, mean 137.65 px, σ 0.08 px on the straight part (the whole
  // stretch with its knurl marks: 139.57 px, σ 0.10 px).
  EXPECT_GE(valid, 0.95 * frames);
  EXPECT_NEAR(mean, 137.08, 1.5);  // the real-footage issue's target
  EXPECT_LE(sd, 0.15);
  // Measured: 269 of 280 pairs within ±0.05 mm/s, mean 0.0006 mm/s (unsmoothed profiles: 275;
  // smoothed at 1.5 px: 240); most beyond are the MPEG-4 key frames (every 12th), where the codec
  // redraws the texture.
  EXPECT_GE(at_rest, 0.95 * pairs) << at_rest << " of " << pairs;
}

// Every frame on its own, as inspect and the first frame of a video see it: the gears, the idler
// and the filament's own shading offer many straight pairs.
TEST(RealFootageTest, GreeffFramesFoundAfresh) {
  auto source = FrameSource::Open(kGreeff);
  const StrandMeasureOptions o = FilamentOptions();
  InputFrame f;
  int frames = 0, valid = 0, wrong = 0;
  while (source->Next(&f)) {
    ++frames;
    const StrandMeasurement m = MeasureStrand(f.image, o);
    if (!m.valid()) continue;
    ++valid;
    if (std::abs(m.width_px - 138.3) > 10) ++wrong;
  }
  // Measured: 257 of 281 valid (267 before issue 22's first round, whose checks refuse more of
  // the frames among gears; before it, 1 of the valid ones was another pair: a 13.5 px gap between
  // the gear and the filament).
  EXPECT_GE(valid, 0.9 * frames);
  EXPECT_LE(wrong, 0.015 * frames);
}

}  // namespace
}  // namespace clogscope::vision
