#include "vision/edges/residual_structure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace clogscope::vision {
namespace {

// Residuals of 20 calipers × 4 rows at sub-pixel spread distances from the edge.
ResidualStructure Pool(double shared_amplitude, double noise, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, noise);
  ResidualStructure r(10.0);
  for (int caliper = 0; caliper < 20; ++caliper) {
    for (int row = 0; row < 4; ++row) {
      for (double u = -10 + 0.23 * row; u <= 10; u += 1.0)
        r.Add(u, shared_amplitude * std::sin(0.7 * u) + n(rng));
    }
  }
  return r;
}

TEST(ResidualStructureTest, NoiseAloneSharesNothing) {
  for (uint32_t seed = 1; seed <= 5; ++seed) {
    const ResidualStructure r = Pool(0.0, 5.0, seed);
    EXPECT_NEAR(r.ResidualRms(), 5.0, 0.3);
    // What 21 bin means of ~80 samples each leave by chance: about σ/√80 ≈ 0.6 at most.
    EXPECT_LT(r.SharedRms(), 0.8) << seed;
  }
}

TEST(ResidualStructureTest, StructureRepeatedAlongTheBandIsFound) {
  // A sine of amplitude 3 has RMS 3/√2 ≈ 2.12 over many periods.
  for (uint32_t seed = 1; seed <= 5; ++seed)
    EXPECT_NEAR(Pool(3.0, 5.0, seed).SharedRms(), 3.0 / std::sqrt(2.0), 0.35) << seed;
}

TEST(ResidualStructureTest, EdgeDoubtScalesWithTheSharedStructure) {
  // An edge fitted to ±0.1 px from residuals of RMS 5 over 80 samples across 20 px: one sample
  // per px gives √(80/20) = 2 times that per unit of noise, 0.04 px per grey level.
  EXPECT_NEAR(SharedStructureEdgeDoubtPx(2.0, 5.0, 0.1, 80, 20.0), 0.08, 1e-12);
  EXPECT_EQ(SharedStructureEdgeDoubtPx(2.0, 0.0, 0.1, 80, 20.0), 0.0);
}

}  // namespace
}  // namespace clogscope::vision
