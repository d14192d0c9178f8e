#include "vision/edges/straight_run.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "synthetic/synthetic.h"
#include "vision/scene/track.h"

namespace clogscope::vision {
namespace {

using synthetic::FeedstockScene;
using synthetic::FrameTruth;
using synthetic::RenderFrame;
using synthetic::SceneParams;

// n calipers 4 px apart with edges at ∓50 px, leaning 0.02 px/px, with 0.05 px of fitting noise.
std::vector<Caliper> StraightCalipers(int n, uint64_t seed = 1) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.05);
  std::vector<Caliper> c(n);
  for (int k = 0; k < n; ++k) {
    c[k].s_px = 4.0 * k + 2.0;
    c[k].left_u_px = -50 + 0.02 * c[k].s_px + noise(rng);
    c[k].right_u_px = 50 + 0.02 * c[k].s_px + noise(rng);
    c[k].width_px = c[k].right_u_px - c[k].left_u_px;
    c[k].fitted = true;
  }
  return c;
}

// Knurl marks on the left edge from caliper k0 on: a saw tooth `depth` px deep, 44 px long, as a
// drive gear leaves on the filament below its grip (see Greeff's video).
void Knurl(std::vector<Caliper>* c, int k0, double depth = 9) {
  for (int k = k0; k < static_cast<int>(c->size()); ++k) {
    Caliper& x = (*c)[k];
    const double ph = (x.s_px - (*c)[k0].s_px) / 44.0;
    x.left_u_px -= depth * (ph - std::floor(ph) - 1.0 / 3.0);
    x.width_px = x.right_u_px - x.left_u_px;
  }
}

TEST(StraightRunTest, AStraightLeaningFilamentIsStraightAlongItsWholeLength) {
  const StraightRun r = FindStraightRun(StraightCalipers(100));
  EXPECT_EQ(r.sections, 0);
  EXPECT_EQ(r.begin, 0);
  EXPECT_EQ(r.end, 100);
  EXPECT_EQ(r.rough, 0);
}

TEST(StraightRunTest, KnurlMarksEndTheStraightPart) {
  std::vector<Caliper> c = StraightCalipers(110);
  Knurl(&c, 40);
  const StraightRun r = FindStraightRun(c);
  EXPECT_GE(r.sections, 1);
  EXPECT_EQ(r.begin, 0);
  // The straight part ends where the marks begin (a caliper or two early: the first tooth's
  // flank starts inside the window).
  EXPECT_LE(r.end, 41);
  EXPECT_GE(r.end, 36);
  EXPECT_GE(r.rough, 50);
}

TEST(StraightRunTest, OneBadCaliperDoesNotSplitTheStretch) {
  std::vector<Caliper> c = StraightCalipers(100);
  c[50].left_u_px -= 3;  // a speck on the edge
  c[51].fitted = false;
  const StraightRun r = FindStraightRun(c);
  EXPECT_EQ(r.sections, 0);
  EXPECT_EQ(r.end - r.begin, 100);
  EXPECT_EQ(r.state[50], -1);
}

// The long flank of a knurl tooth is a straight edge; it is not parallel to the other.
TEST(StraightRunTest, AStraightEdgeThatClosesOnTheOtherIsNotStraightStrand) {
  std::vector<Caliper> c = StraightCalipers(100);
  for (int k = 30; k < 60; ++k) {
    c[k].left_u_px += 0.2 * (c[k].s_px - c[30].s_px);
    c[k].width_px = c[k].right_u_px - c[k].left_u_px;
  }
  // Beyond the ramp the edge is straight again, 24 px further in: three parts; the first and
  // last are 30 and 40 calipers long.
  for (int k = 60; k < 100; ++k) {
    c[k].left_u_px += 0.2 * (c[59].s_px - c[30].s_px);
    c[k].width_px = c[k].right_u_px - c[k].left_u_px;
  }
  const StraightRun r = FindStraightRun(c);
  EXPECT_GE(r.sections, 1);
  EXPECT_GE(r.begin, 60);
  EXPECT_EQ(r.end, 100);
}

TEST(StraightRunTest, TrackingKeepsThePartMeasuredBefore) {
  std::vector<Caliper> c = StraightCalipers(110);
  Knurl(&c, 20);                    // calipers 0–19 straight, then marks ...
  for (int k = 60; k < 110; ++k) {  // ... and a longer straight part from 60 on
    c[k].left_u_px = c[k].right_u_px - 100;
    c[k].width_px = 100;
  }
  EXPECT_GE(FindStraightRun(c).begin, 60);
  StraightRunOptions o;
  o.prefer_begin = 2;
  o.prefer_end = 18;
  const StraightRun r = FindStraightRun(c, o);
  EXPECT_EQ(r.begin, 2);
  EXPECT_EQ(r.end, 18);
  // Too little of the preferred range left straight: the longest part again.
  o.prefer_begin = 15;
  o.prefer_end = 25;
  EXPECT_GE(FindStraightRun(c, o).begin, 60);
}

// Rendered: the feedstock scene (synthetic.h), shaded like Greeff's filament, its left edge marked
// by a knurl below y = 200 that moves with a 3 mm/s feed. The width must be the unmarked
// filament's; over the whole stretch the marks would add 0.6–0.9 px. The first frame looks at the
// whole stretch; the tracked ones at its straight part and a few calipers beside it.
TEST(StraightRunTest, RenderedKnurledFilamentIsMeasuredOnItsUnmarkedPart) {
  SceneParams p = FeedstockScene(3.0);
  p.shading_ambient = 0.5;
  p.tilt_deg = 1.0;
  p.knurl_depth_px = 9;
  p.knurl_pitch_px = 44;
  p.knurl_start_px = 200;
  StrandMeasureOptions o;
  o.target = MeasureTarget::kFilament;
  o.band_start_px = 0;
  o.band_height_px = kWholeStretchPx;
  StrandTracker tracker(o);
  for (int i = 0; i < 6; ++i) {
    FrameTruth t;
    const StrandMeasurement m = tracker.Measure(RenderFrame(p, i, &t));
    ASSERT_TRUE(m.valid()) << m.detail;
    EXPECT_NEAR(m.width_px, t.width_px, 0.05) << "frame " << i;
    EXPECT_LE(m.straight_end_px, p.knurl_start_px);
    EXPECT_GE(m.straight_end_px - m.straight_start_px, 150);
    if (i > 0) {
      EXPECT_EQ(tracker.full_detections(), 1);
      EXPECT_LE(m.band_end_px - m.band_start_px, p.knurl_start_px + 30);
      continue;
    }
    EXPECT_GE(m.rough_calipers, 30);
    double all = 0;
    int n = 0;
    for (const Caliper& c : m.calipers) {
      if (!c.fitted) continue;
      all += c.width_px;
      ++n;
    }
    EXPECT_GT(all / n - t.width_px, 0.4) << "the marks would have counted";
  }
}

// Marks along the whole stretch: no straight part to measure, so no width.
TEST(StraightRunTest, RenderedFilamentMarkedAllAlongGivesNoWidth) {
  SceneParams p = FeedstockScene(0.0);
  p.shading_ambient = 0.5;
  p.knurl_depth_px = 9;
  p.knurl_pitch_px = 44;
  p.knurl_start_px = -1000;
  StrandMeasureOptions o;
  o.target = MeasureTarget::kFilament;
  o.band_start_px = 0;
  o.band_height_px = kWholeStretchPx;
  for (int i = 0; i < 3; ++i) {
    const StrandMeasurement m = MeasureStrand(RenderFrame(p, i, nullptr), o);
    EXPECT_FALSE(m.valid()) << "width " << m.width_px;
  }
}

}  // namespace
}  // namespace clogscope::vision
