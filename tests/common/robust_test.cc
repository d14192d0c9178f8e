#include "common/robust.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
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

// The median's standard error, estimated from one sample's own scatter, against the scatter of
// the medians of many samples of normal noise (sigma 2, 15 values: a caliper count).
TEST(MedianStandardErrorTest, MatchesTheScatterOfMediansOfNormalSamples) {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(5.0, 2.0);
  constexpr int kSamples = 4000, kValues = 15;
  double sum = 0, sum2 = 0, estimated = 0;
  for (int i = 0; i < kSamples; ++i) {
    std::vector<double> v(kValues);
    for (double& x : v) x = noise(rng);
    const double median = Median(v);
    sum += median;
    sum2 += median * median;
    estimated += MedianStandardError(v, median);
  }
  const double scatter = std::sqrt(sum2 / kSamples - (sum / kSamples) * (sum / kSamples));
  // sqrt(pi/2)·2/sqrt(15) = 0.647 for a large sample; at 15 values the medians scatter by 0.632
  // (20000 samples, computed apart), and the MAD's estimate averages 0.616.
  EXPECT_NEAR(scatter, 0.63, 0.03);
  EXPECT_NEAR(estimated / kSamples / scatter, 1.0, 0.15);
  EXPECT_EQ(MedianStandardError({}, 0), 0);
}

// The median networks give nth_element's middle values. On every input of 0s and 1s (a
// compare-exchange network that puts those right puts every input right: the 0-1 principle), and
// on random values with many ties.
TEST(MedianNetworkTest, GivesTheMiddleValuesOfASelection) {
  const auto selected = [](std::vector<double> v, size_t k) {
    std::nth_element(v.begin(), v.begin() + k, v.end());
    return v[k];
  };
  const auto check = [&](const std::vector<double>& values) {
    std::vector<double> v = values;
    if (values.size() == 8) {
      ASSERT_EQ(MedianOf8(v.data()), 0.5 * (selected(values, 4) + selected(values, 3)));
      v = values;
      ASSERT_EQ(MedianOf8(v.data()), Median(values));
    } else {
      ASSERT_EQ(UpperMedianOf12(v.data()), selected(values, 6));
    }
  };
  for (size_t n : {8, 12})
    for (unsigned bits = 0; bits < (1u << n); ++bits) {
      std::vector<double> v(n);
      for (size_t i = 0; i < n; ++i) v[i] = (bits >> i) & 1;
      check(v);
    }
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> level(0, 9);
  for (int trial = 0; trial < 20000; ++trial)
    for (size_t n : {8, 12}) {
      std::vector<double> v(n);
      for (double& x : v) x = level(rng) + 0.25 * (trial % 4);
      check(v);
    }
}

}  // namespace
}  // namespace clogscope
