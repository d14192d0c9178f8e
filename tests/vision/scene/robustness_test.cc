// Scenes far from the defaults (RandomRealisticScene), and scenes without a strand. Statistical:
// labelled slow.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "synthetic/synthetic.h"
#include "tests/running_stats.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {
namespace {

using synthetic::FrameTruth;
using synthetic::RandomRealisticScene;
using synthetic::RenderFrame;
using synthetic::SceneParams;

StrandMeasureOptions OptionsFor(const SceneParams& p) {
  StrandMeasureOptions o;
  if (!p.nozzle) {  // a filament through the frame: the whole stretch
    o.target = MeasureTarget::kFilament;
    o.band_start_px = 0;
    o.band_height_px = 1e6;
  }
  return o;
}

using Stats = testing::RunningStats;

// 200 frames: either polarity, tilt ±20°, blur to 3 px, any nozzle or none, texture, discs, gears,
// shading, clear strands, colour on colour, vignetting, gradients, highlights, beds.
TEST(RobustnessTest, RandomisedScenesAgainstTruth) {
  constexpr int kFrames = 200;
  Stats plain, shaded;
  int valid = 0, wrong = 0;
  for (int seed = 0; seed < kFrames; ++seed) {
    const SceneParams p = RandomRealisticScene(seed);
    FrameTruth t;
    const StrandMeasurement m = MeasureStrand(RenderFrame(p, 0, &t), OptionsFor(p));
    if (!m.valid()) {
      std::printf("seed %d: %s: %s\n", seed, FrameStatusName(m.status), m.detail.c_str());
      continue;
    }
    ++valid;
    (p.shading_ambient < 1.0 ? shaded : plain).Add(m.width_px - t.width_px);
    // Confidently wrong, as the adversarial matrix counts it.
    if (std::abs(m.width_px - t.width_px) > std::max(0.3, 0.005 * t.width_px)) {
      ++wrong;
      std::printf("seed %d: error %+.2f px\n", seed, m.width_px - t.width_px);
    }
  }
  std::printf("%d of %d valid; unshaded %+.4f ± %.4f px (%d); shaded %+.4f ± %.4f px (%d)\n", valid,
              kFrames, plain.mean(), plain.sd(), plain.n, shaded.mean(), shaded.sd(), shaded.n);
  // Measured on this suite: 184 of 200 valid, none confidently wrong; unshaded −0.008 ± 0.045 px;
  // shaded −0.014 ± 0.083 px. (185 before the slopes read along the band past an edge's window
  // were doubted, 2026-11-30: seed 160, right to 0.08 px, is `imprecise` at σ 0.21, its
  // background's slope a line over no reach. 186 before a strand shaded on both sides was held to
  // 15 % between its edges' blurs, 2026-11-30: seed 98, a gear against the band's edge, 0.53 px
  // narrow at σ 0.19, is `imprecise` at σ 0.38. 187 on an earlier day. 190 valid before the tip was
  // read on the strand's own end, one of them wrong: seed 98, a gear against the band's edge, −0.86
  // px at 4.4σ, now `imprecise`; seeds 173 and 175, a disc by the band's lower end, are `imprecise`
  // too, ±0.19–0.27 px. 198 before issue 22's self-checks: a highlight clipped inside a shaded
  // strand (seeds 20, 89) and a disc against the strand's edge (seed 31) are refused now, as the
  // rules say; 195 before the σ carried the edge model's doubt: seeds 14, 38, 133 and 194 are
  // `imprecise`, ±0.2–0.4 px.)
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(valid, 0.92 * kFrames);
  EXPECT_LE(std::abs(plain.mean()), 0.05);
  EXPECT_LE(plain.sd(), 0.06);
  EXPECT_LE(std::abs(shaded.mean()), 0.1);
  EXPECT_LE(shaded.sd(), 0.15);
}

// Empty textured backgrounds, clutter only, a nozzle with nothing below: never a width.
TEST(RobustnessTest, NoStrandNeverGivesAWidth) {
  constexpr int kFrames = 150;
  int widths = 0;
  for (int i = 0; i < kFrames; ++i) {
    SceneParams p = RandomRealisticScene(1000 + i);
    p.strand = false;
    if (i % 3 == 0) p.nozzle = false;
    if (i % 3 == 1) {
      p.clutter_discs = 3;
      p.clutter_gears = 2;
      p.nozzle = false;
    }
    StrandMeasureOptions o;
    if (i % 2) o.target = MeasureTarget::kFilament;
    const StrandMeasurement m = MeasureStrand(RenderFrame(p, 0, nullptr), o);
    if (m.valid()) {
      ++widths;
      std::printf("seed %d: a width of %.1f px with no strand (%s)\n", 1000 + i, m.width_px,
                  p.nozzle ? "nozzle" : "no nozzle");
    }
  }
  // None measured (1 of 150 when this test was written: a disc's tangents).
  EXPECT_EQ(widths, 0);
}

}  // namespace
}  // namespace clogscope::vision
