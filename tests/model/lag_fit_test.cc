#include "model/lag_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace clogscope::model {
namespace {

// Flow steps up and down, like a test print's alternating speeds.
FlowProfile Steps() { return ProfileFromMoves({0, 1, 2.5, 4, 5.5}, {3, 9, 4, 12, 3}); }

std::vector<WidthSample> Widths(const FlowProfile& p, double k, double gain, double offset,
                                double noise, std::mt19937* rng, double fps = 25, double t1 = 7) {
  std::normal_distribution<double> n(0, noise);
  std::vector<double> t;
  for (double x = 0.02; x < t1; x += 1 / fps) t.push_back(x);
  std::vector<double> shifted = t;
  for (auto& x : shifted) x -= offset;
  const auto q = OutletFlow(p, k, 0.0, shifted);
  std::vector<WidthSample> s;
  for (size_t i = 0; i < t.size(); ++i) s.push_back({t[i], gain * q[i] + n(*rng)});
  return s;
}

TEST(LagFitTest, RecoversKGainAndOffset) {
  std::mt19937 rng(3);
  for (double k : {0.1, 0.5}) {
    const auto s = Widths(Steps(), k, 12.0, 0.03, 0.1, &rng);
    const auto f = FitLag(Steps(), s, LagFitOptions{});
    ASSERT_TRUE(f.usable) << f.message;
    EXPECT_NEAR(f.k_s, k, 0.02 * k);
    EXPECT_NEAR(f.gain, 12.0, 0.01 * 12);
    EXPECT_NEAR(f.offset_s, 0.03, 0.005);
    EXPECT_LT(std::abs(f.k_s - k), 4 * f.k_sigma_s);
    EXPECT_NEAR(f.rms, 0.1, 0.02);
    EXPECT_EQ(f.outliers, 0);
    EXPECT_DOUBLE_EQ(f.k_la_s, f.k_s);
  }
}

// The σ is honest: over many noise draws the spread of K matches the mean reported σ.
TEST(LagFitTest, SigmaMatchesMonteCarloSpread) {
  std::mt19937 rng(11);
  for (double k : {0.1, 0.5}) {
    std::vector<double> ks, sigmas;
    for (int trial = 0; trial < 150; ++trial) {
      const auto f = FitLag(Steps(), Widths(Steps(), k, 10.0, 0.0, 0.3, &rng), LagFitOptions{});
      ASSERT_TRUE(f.usable) << f.message;
      ks.push_back(f.k_s);
      sigmas.push_back(f.k_sigma_s);
    }
    double mean = 0, mean_sigma = 0, var = 0;
    for (size_t i = 0; i < ks.size(); ++i) mean += ks[i] / ks.size();
    for (size_t i = 0; i < ks.size(); ++i) {
      var += (ks[i] - mean) * (ks[i] - mean) / (ks.size() - 1);
      mean_sigma += sigmas[i] / ks.size();
    }
    const double ratio = std::sqrt(var) / mean_sigma;
    std::printf("K %.2f s: mean %.5f s, spread %.5f s, mean σ %.5f s, ratio %.2f\n", k, mean,
                std::sqrt(var), mean_sigma, ratio);
    EXPECT_GT(ratio, 1 / 1.5);
    EXPECT_LT(ratio, 1.5);
    EXPECT_NEAR(mean, k, 0.01 * k);
  }
}

TEST(LagFitTest, BadFramesAreLeftOutAndCounted) {
  std::mt19937 rng(5);
  auto s = Widths(Steps(), 0.2, 10.0, 0.0, 0.1, &rng);
  for (int i : {20, 60, 61, 130}) s[i].width += 25;  // a blob, a lost edge
  const auto f = FitLag(Steps(), s, LagFitOptions{});
  ASSERT_TRUE(f.usable) << f.message;
  EXPECT_EQ(f.outliers, 4);
  EXPECT_TRUE(f.outlier[60]);
  EXPECT_EQ(f.samples_used, f.samples_total - 4);
  EXPECT_NEAR(f.k_s, 0.2, 0.01);
}

TEST(LagFitTest, ProfilesThatCannotExplainTheFramesAreRefused) {
  std::mt19937 rng(1);
  const auto s = Widths(Steps(), 0.2, 10.0, 0.0, 0.1, &rng);
  try {
    FitLag(ProfileFromMoves({100, 101}, {3, 9}), s, LagFitOptions{});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("does not overlap"), std::string::npos) << e.what();
  }
  try {
    FitLag(ProfileFromMoves({0, 3}, {5, 5}), s, LagFitOptions{});
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("does not change"), std::string::npos) << e.what();
  }
  EXPECT_THROW(FitLag(Steps(), {s.begin(), s.begin() + 5}, LagFitOptions{}), std::invalid_argument);
}

// A width that does not follow the flow at all: no K, and the summary says so.
TEST(LagFitTest, WidthsUnrelatedToTheFlowAreNotUsable) {
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0, 0.1);
  std::vector<WidthSample> s;
  for (double t = 0.02; t < 7; t += 0.04) s.push_back({t, 100 + n(rng)});
  const auto f = FitLag(Steps(), s, LagFitOptions{});
  EXPECT_FALSE(f.usable);
  EXPECT_FALSE(f.message.empty());
}

// Every search has a stated bound: the offset range is limited to 60 s (the count of offsets tried
// once overflowed an int at 2147483648 s, and 1e5 s took minutes), refused in one line past it
// that names the option (the lag command's --max-offset-s) and the value.
TEST(LagFitTest, OffsetRangesPastTheLimitAreRefusedInOneLine) {
  std::mt19937 rng(5);
  const auto s = Widths(Steps(), 0.2, 10.0, 0.0, 0.1, &rng);
  const std::pair<double, const char*> cases[] = {
      {2147483648.0, "--max-offset-s 2.14748e+09: must be in [0, 60] s"},
      {1e5, "--max-offset-s 100000: must be in [0, 60] s"},
      {60.5, "--max-offset-s 60.5: must be in [0, 60] s"},
      {-0.1, "--max-offset-s -0.1: must be in [0, 60] s"}};
  for (const auto& [max_offset_s, expect] : cases) {
    LagFitOptions o;
    o.max_offset_s = max_offset_s;
    std::string why;
    EXPECT_FALSE(o.Validate(&why)) << max_offset_s;
    EXPECT_EQ(why.rfind(expect, 0), 0u) << why;
    EXPECT_EQ(why.find('\n'), std::string::npos) << why;
  }
  LagFitOptions o;
  o.max_offset_s = 2147483648.0;
  EXPECT_THROW(FitLag(Steps(), s, o), std::invalid_argument);
  o.max_offset_s = 60;
  std::string why;
  EXPECT_TRUE(o.Validate(&why)) << why;
}

// At the widest allowed range (and with the offset held at 0) the fit still finds the truth.
TEST(LagFitTest, TheWidestOffsetRangeAndAHeldOffsetStillRecoverTheTruth) {
  std::mt19937 rng(6);
  for (const auto& [max_offset_s, offset_s] : {std::pair{60.0, 0.05}, std::pair{0.0, 0.0}}) {
    LagFitOptions o;
    o.max_offset_s = max_offset_s;
    const auto f = FitLag(Steps(), Widths(Steps(), 0.3, 12.0, offset_s, 0.1, &rng), o);
    ASSERT_TRUE(f.usable) << max_offset_s << ": " << f.message;
    EXPECT_NEAR(f.k_s, 0.3, 0.02 * 0.3) << max_offset_s;
    EXPECT_NEAR(f.offset_s, offset_s, 0.005) << max_offset_s;
    EXPECT_GT(f.k_sigma_s, 0) << max_offset_s;
  }
}

}  // namespace
}  // namespace clogscope::model
