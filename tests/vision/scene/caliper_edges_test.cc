#include "vision/scene/caliper_edges.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

// The band's edges from its calipers: a width that changes as one edge alone drifts.
namespace clogscope::vision {
namespace {

// Calipers every 4 px over a 28 px band whose edges lie at left(s) and right(s), each with
// Gaussian noise of noise_px; all inliers.
template <typename Left, typename Right>
std::vector<Caliper> Band(Left left, Right right, double noise_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_px);
  std::vector<Caliper> out;
  for (double s = 10.0; s <= 38.0; s += 4.0) {
    Caliper c;
    c.s_px = s;
    c.left_u_px = left(s) + noise(rng);
    c.right_u_px = right(s) + noise(rng);
    c.width_px = c.right_u_px - c.left_u_px;
    c.fitted = c.inlier = true;
    out.push_back(c);
  }
  return out;
}

constexpr double kBandPx = 28.0;

// One edge sliding in by 0.06 px per px while the other holds: the width falls by 1.68 px over
// the band and the middle turns by half that; the doubt is half the change, 0.84 px. The same
// drift on the right edge gives the same doubt.
TEST(OneEdgeDriftTest, OneEdgeAloneCountsHalfTheWidthsChange) {
  const double drift = 0.06;
  const auto left_in =
      Band([&](double s) { return -40.0 + drift * s; }, [](double) { return 40.0; }, 0.02, 1);
  EXPECT_NEAR(OneEdgeDriftDoubtPx(left_in, 0, static_cast<int>(left_in.size()), -drift, kBandPx),
              0.5 * drift * kBandPx, 0.05);
  const auto right_in =
      Band([](double) { return -40.0; }, [&](double s) { return 40.0 - drift * s; }, 0.02, 2);
  EXPECT_NEAR(OneEdgeDriftDoubtPx(right_in, 0, static_cast<int>(right_in.size()), -drift, kBandPx),
              0.5 * drift * kBandPx, 0.05);
}

// A swell relaxing (both edges closing in alike, the middle still) and a strand turning off the
// axis at a constant width are not one edge's drift: no doubt, or next to none.
TEST(OneEdgeDriftTest, ASwellOrATurningStrandIsNotOneEdge) {
  const auto swell = Band([](double s) { return -40.0 + 0.03 * s; },
                          [](double s) { return 40.0 - 0.03 * s; }, 0.02, 3);
  EXPECT_LT(OneEdgeDriftDoubtPx(swell, 0, static_cast<int>(swell.size()), -0.06, kBandPx), 0.02);
  // Turning by 0.05 px per px with the width all but constant (a slope of 0.003 judged real).
  const auto turn = Band([](double s) { return -40.0 + 0.05 * s; },
                         [](double s) { return 40.0 + 0.053 * s; }, 0.02, 4);
  EXPECT_LT(OneEdgeDriftDoubtPx(turn, 0, static_cast<int>(turn.size()), 0.003, kBandPx), 0.01);
}

// A middle that does not turn beyond its calipers' noise and the pair axis's own doubt, or a width
// judged steady, is no drift. (A codec's shared errors tilt one edge's line by 0.3° and the
// width's with it: a 0.0098 px/px width slope seen with a 0.0049 turn on a straight strand.)
TEST(OneEdgeDriftTest, NoTurnBeyondTheNoiseNoDoubt) {
  const auto codec_tilt =
      Band([](double) { return -40.0; }, [](double s) { return 40.0 + 0.0098 * s; }, 0.002, 7);
  EXPECT_EQ(
      OneEdgeDriftDoubtPx(codec_tilt, 0, static_cast<int>(codec_tilt.size()), 0.0098, kBandPx),
      0.0);
  const auto noisy =
      Band([](double) { return -40.0; }, [](double s) { return 40.0 - 0.01 * s; }, 0.5, 5);
  EXPECT_EQ(OneEdgeDriftDoubtPx(noisy, 0, static_cast<int>(noisy.size()), -0.01, kBandPx), 0.0);
  const auto drifting =
      Band([](double s) { return -40.0 + 0.06 * s; }, [](double) { return 40.0; }, 0.02, 6);
  EXPECT_EQ(OneEdgeDriftDoubtPx(drifting, 0, static_cast<int>(drifting.size()), 0.0, kBandPx), 0.0);
}

}  // namespace
}  // namespace clogscope::vision
