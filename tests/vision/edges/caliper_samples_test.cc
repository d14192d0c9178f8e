#include "vision/edges/caliper_samples.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/core.hpp>
#include <random>
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

// The pixels come in order of u with ties in their own order, as a stable sort puts them:
// slabs' rows (runs in order of u, ties included), and samples in no order at all.
TEST(GroupByUTest, OrdersPixelsAsAStableSort) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<EdgeSample> samples;
    const int rows = 1 + trial % 9, per_row = 1 + static_cast<int>(rng() % 30);
    for (int r = 0; r < rows; ++r) {
      const float shift = static_cast<float>(rng() % 5) * 0.5f;  // rows that tie with others
      for (int k = 0; k < per_row; ++k) {
        const float u = trial % 4 == 3 ? static_cast<float>(rng() % 11)  // no order, many ties
                                       : shift + 0.5f * static_cast<float>(k / 2);
        samples.push_back({u, static_cast<float>(samples.size())});
      }
    }
    std::vector<int> expected(samples.size());
    std::iota(expected.begin(), expected.end(), 0);
    std::stable_sort(expected.begin(), expected.end(),
                     [&](int a, int b) { return samples[a].u_px < samples[b].u_px; });
    ASSERT_EQ(GroupByU(samples, 0.05).pixels, expected) << "trial " << trial;
  }
}

// A dark strand's right edge with a bright stripe 6 px inside it (a glossy strand's highlight),
// blurred: along +u the stripe falls to the strand's level and the silhouette rises to the
// background's. The profile's mid-level lies above the background, so only the stripe's edge
// crosses it: a start that takes any crossing puts the silhouette on the stripe.
TEST(RefineEdgeGuessTest, TakesOnlyACrossingInTheEdgesDirection) {
  constexpr double kStripeEdge = 20, kSilhouette = 26, kBlur = 1.5;
  const auto render = [&](bool stripe) {
    cv::Mat img(16, 64, CV_8U);
    for (int x = 0; x < img.cols; ++x) {
      const auto step = [&](double at) { return 0.5 * std::erfc(-(x - at) / (kBlur * M_SQRT2)); };
      const double v = 62 + (stripe ? (204 - 62) * (1 - step(kStripeEdge)) : 0.0) +
                       (116 - 62) * step(kSilhouette);
      img.col(x).setTo(std::round(v));
    }
    return img;
  };
  const AxisFrame f{0, 0, 0, 1};  // u along +x
  const cv::Mat striped = render(true), plain = render(false);
  const GreyImage a{striped, false}, b{plain, false};
  const double guess = 27.0;
  // Either direction: the stripe's edge (the old start, 6 px inside the silhouette).
  EXPECT_NEAR(RefineEdgeGuess(a, f, 8, guess, 10, 10, 0), kStripeEdge, 0.6);
  // The silhouette's direction: no crossing of its own, so the guess stands.
  EXPECT_EQ(RefineEdgeGuess(a, f, 8, guess, 10, 10, +1), guess);
  // A plain edge is found in its direction to a fraction of a px, and not against it.
  EXPECT_NEAR(RefineEdgeGuess(b, f, 8, guess, 10, 10, +1), kSilhouette, 0.1);
  EXPECT_EQ(RefineEdgeGuess(b, f, 8, guess, 10, 10, -1), guess);
}

// A slab of 3000 px (50 × 60, the image's top left) whose pixels take the given values, count
// times each, the rest `fill`. The axis runs down the image (s = y, u = x).
struct Level {
  int value, count;
};
void FillSlab(const std::vector<Level>& levels, int fill, cv::Mat* m) {
  (*m)(cv::Rect(0, 0, 50, 60)).setTo(fill);
  int k = 0;
  for (const Level& l : levels)
    for (int i = 0; i < l.count; ++i, ++k) m->at<uint8_t>(k / 50, k % 50) = l.value;
  EXPECT_LE(k, 3000);
}
ClipLevels SlabClips(const cv::Mat& m, const DataLevels& data) {
  return FindClipLevels(GreyImage{m, false}, AxisFrame{}, 0, 59.5, 0, 49, data);
}
// Such a slab as the whole image.
ClipLevels ClipsOf(const std::vector<Level>& levels, int fill, const DataLevels& data) {
  cv::Mat m(60, 50, CV_8UC1);
  FillSlab(levels, fill, &m);
  return SlabClips(m, data);
}
constexpr DataLevels kFullRange{255, 0, 255}, kLimitedRange{255, 16, 235};

TEST(FindClipLevelsTest, AClipAtLimitedWhiteWithRingingAboveIsFoundThereOnly) {
  // x264's clipped background in one key frame (matrix seed 14): 296 pixels at 235, 180 above
  // it up to 246 (more than half the spike), a few in the four levels below, the strand at 117.
  const std::vector<Level> clip = {{231, 5},  {232, 14}, {233, 16}, {234, 59}, {235, 296},
                                   {236, 54}, {237, 45}, {238, 63}, {239, 8},  {240, 5},
                                   {241, 2},  {242, 1},  {243, 1},  {246, 1}};
  const ClipLevels limited = ClipsOf(clip, 117, kLimitedRange);
  EXPECT_NEAR(limited.high, 234.5, 1e-3);
  EXPECT_NEAR(limited.clipped_high_fraction, (296 + 180) / 3000.0, 1e-9);
  EXPECT_EQ(limited.low, 0);
  // Read as full range, 235 is no clip level: only 255 is.
  const ClipLevels full = ClipsOf(clip, 117, kFullRange);
  EXPECT_EQ(full.high, 255);
  EXPECT_EQ(full.clipped_high_fraction, 0);
}

TEST(FindClipLevelsTest, AClipWithItsRingingInsideOrSplitOverTwoLevelsIsFound) {
  // x264's clipped backlight beside a dark strand at a low rate (matrix seed 1316): the ringing
  // mostly below 235, little above.
  const std::vector<Level> inside = {{229, 8},   {230, 7},   {231, 14}, {232, 71}, {233, 205},
                                     {234, 171}, {235, 488}, {236, 36}, {237, 16}, {238, 14},
                                     {239, 5},   {240, 4},   {241, 3},  {243, 2},  {244, 3}};
  EXPECT_NEAR(ClipsOf(inside, 16, kLimitedRange).high, 234.5, 1e-3);
  // The same clip split over 235 and 236 (seed 1318).
  const std::vector<Level> split = {{230, 4},  {231, 5},   {232, 4},   {233, 10},
                                    {234, 45}, {235, 374}, {236, 334}, {237, 37},
                                    {238, 16}, {239, 6},   {240, 7},   {241, 4}};
  const ClipLevels s = ClipsOf(split, 16, kLimitedRange);
  EXPECT_NEAR(s.high, 234.5, 1e-3);
  EXPECT_NEAR(s.clipped_high_fraction, (374 + 334 + 37 + 16 + 6 + 7 + 4) / 3000.0, 1e-9);
}

TEST(FindClipLevelsTest, AClipHiddenInTheSlabsRingingIsFoundInTheFrame) {
  // A slab beside a dark strand whose clipped backlight x264 rang down to 231-232 (matrix seed
  // 1912): no spike in the slab. The frame around it, clipped at 235, has one; a frame whose
  // background lies unclipped at 234 (noise σ 1) has none.
  const std::vector<Level> slab = {{231, 900}, {232, 700}, {233, 100}, {234, 200}, {235, 300}};
  for (const int outside : {235, 234}) {
    cv::Mat m(200, 200, CV_8UC1, cv::Scalar(outside));
    if (outside == 234) cv::RNG(7).fill(m, cv::RNG::NORMAL, 234, 1);
    FillSlab(slab, 16, &m);
    const ClipLevels c = SlabClips(m, kLimitedRange);
    if (outside == 235) {
      EXPECT_NEAR(c.high, 234.5, 1e-3);
      EXPECT_NEAR(c.clipped_high_fraction, 300 / 3000.0, 1e-9);
    } else {
      EXPECT_EQ(c.high, 255);
    }
  }
}

TEST(FindClipLevelsTest, UnclippedPlateausByLimitedWhiteAreNotClips) {
  // A plateau of noise σ 1 exactly at white: 5.3 times its neighbours, a third of it above.
  const std::vector<Level> at_white = {{231, 1},   {232, 10},  {233, 108}, {234, 484}, {235, 798},
                                       {236, 484}, {237, 108}, {238, 10},  {239, 1}};
  EXPECT_EQ(ClipsOf(at_white, 117, kLimitedRange).high, 255);
  // The same plateau halfway between 235 and 236: the pair of bins has 0.21 of itself above it.
  const std::vector<Level> between = {{232, 2},   {233, 35},  {234, 260}, {235, 706},
                                      {236, 706}, {237, 260}, {238, 35},  {239, 2}};
  EXPECT_EQ(ClipsOf(between, 117, kLimitedRange).high, 255);
  // And half a level below white, whichever of its two fullest levels holds a pixel more.
  for (const int extra : {0, 1}) {
    const std::vector<Level> below = {{231, 2},   {232, 35},  {233, 260}, {234, 706 + extra},
                                      {235, 706}, {236, 260}, {237, 35},  {238, 2}};
    EXPECT_EQ(ClipsOf(below, 117, kLimitedRange).high, 255) << extra;
  }
  // A camera's superwhite plateau (at 240, noise σ 1), which limited range allows.
  std::vector<Level> superwhite = at_white;
  for (Level& l : superwhite) l.value += 5;
  const ClipLevels s = ClipsOf(superwhite, 117, kLimitedRange);
  EXPECT_EQ(s.high, 255);
  EXPECT_EQ(s.clipped_high_fraction, 0);
  // Greeff's MPEG-4 background: a peak at 231 with a third of it above, up to 243.
  const std::vector<Level> greeff = {{228, 60}, {229, 120}, {230, 250}, {231, 900},
                                     {232, 95}, {233, 65},  {234, 56},  {235, 33},
                                     {236, 18}, {237, 10},  {240, 5},   {243, 2}};
  EXPECT_EQ(ClipsOf(greeff, 117, kLimitedRange).high, 255);
}

TEST(FindClipLevelsTest, AFullRangeClipIsFoundInAFrameTakenForLimitedRange) {
  // JPEG's clipped white at 252 (a camera whose range V4L2 did not say, taken as limited).
  const std::vector<Level> clip = {{249, 4}, {250, 8}, {251, 12}, {252, 400}, {253, 40}, {254, 9}};
  for (const DataLevels& data : {kFullRange, kLimitedRange})
    EXPECT_NEAR(ClipsOf(clip, 117, data).high, 251.5, 1e-3) << data.white;
}

TEST(FindClipLevelsTest, ClippedBlackInLimitedRangeIsFoundAtSixteen) {
  // A dark strand clipped at limited black, its ringing below 16.
  const std::vector<Level> clip = {{12, 20}, {14, 40}, {15, 60}, {16, 400}, {17, 30}, {18, 10}};
  const ClipLevels limited = ClipsOf(clip, 180, kLimitedRange);
  EXPECT_NEAR(limited.low, 16.5, 1e-3);
  EXPECT_NEAR(limited.clipped_low_fraction, (20 + 40 + 60 + 400) / 3000.0, 1e-9);
  EXPECT_EQ(ClipsOf(clip, 180, kFullRange).low, 0);
}

}  // namespace
}  // namespace clogscope::vision
