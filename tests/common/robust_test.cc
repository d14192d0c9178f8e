#include "common/robust.h"

#include <gtest/gtest.h>

#include <random>

namespace clogscope {
namespace {

// The counts' median is the values' median, odd and even counts alike (Median is the truth: a
// selection over the values themselves).
TEST(MedianOfCountsTest, IsTheMedianOfTheValuesCounted) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + static_cast<int>(rng() % 60);
    const int range = 1 + static_cast<int>(rng() % 30);
    std::vector<double> values;
    std::vector<int> counts(range, 0);
    for (int i = 0; i < n; ++i) {
      const int v = static_cast<int>(rng() % range);
      values.push_back(v);
      ++counts[v];
    }
    ASSERT_DOUBLE_EQ(MedianOfCounts(counts), Median(values)) << "trial " << trial << ", n " << n;
  }
}

TEST(MedianOfCountsTest, EvenCountAveragesTheMiddleTwoAcrossAGap) {
  std::vector<int> counts(10, 0);
  counts[2] = 2;
  counts[7] = 2;  // values 2 2 7 7: the middle two are 2 and 7
  EXPECT_DOUBLE_EQ(MedianOfCounts(counts), 4.5);
  EXPECT_DOUBLE_EQ(MedianOfCounts(std::vector<int>(5, 0)), 0.0);
}

}  // namespace
}  // namespace clogscope
