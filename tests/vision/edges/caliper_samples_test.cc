#include "vision/edges/caliper_samples.h"

#include <gtest/gtest.h>

#include <vector>

namespace clogscope::vision {
namespace {

// Unsorted samples, each value its expected group's number: groups 0.05 px wide, 2 px wide from
// where one starts inside [3, 5), never past 5.
const std::vector<EdgeSample> kSamples = {{4.9f, 2}, {0.02f, 0}, {9.0f, 4}, {0.5f, 1},
                                          {3.0f, 2}, {0.0f, 0},  {5.5f, 3}, {0.52f, 1},
                                          {3.5f, 2}, {0.04f, 0}, {4.0f, 2}};

TEST(GroupByUTest, GroupsPixelsWithinTheirSpanAndTheInteriorsWiderOne) {
  const PixelGroups g = GroupByU(kSamples, 0.05, 3.0, 5.0, 2.0);
  ASSERT_EQ(g.size(), 5u);
  ASSERT_EQ(g.pixels.size(), kSamples.size());
  int k = 0;
  for (size_t group = 0; group < g.size(); ++group) {
    double sum = 0, offsets = 0;
    const int begin = k;
    for (; k < g.end[group]; ++k) {
      const EdgeSample& s = kSamples[g.pixels[k]];
      EXPECT_EQ(s.value, static_cast<float>(group)) << "pixel at u " << s.u_px;
      EXPECT_NEAR(s.u_px - g.offset_px[k], g.mean_u_px[group], 1e-6);
      sum += s.u_px;
      offsets += g.offset_px[k];
    }
    ASSERT_GT(k, begin);
    EXPECT_NEAR(g.mean_u_px[group], sum / (k - begin), 1e-6);
    EXPECT_NEAR(offsets, 0.0, 1e-6);
  }
  // Without an interior every group is 0.05 px wide: 3.0, 3.5, 4.0 and 4.9 stand alone.
  EXPECT_EQ(GroupByU(kSamples, 0.05).size(), 8u);
  EXPECT_EQ(GroupByU({}, 0.05).size(), 0u);
}

}  // namespace
}  // namespace clogscope::vision
