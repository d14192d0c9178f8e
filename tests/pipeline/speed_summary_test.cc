#include "pipeline/speed_summary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "pipeline/statistics.h"

namespace clogscope::pipeline {
namespace {

vision::FeedSpeedSample Speed(double shift_px, int baseline, int wanted) {
  vision::FeedSpeedSample s;
  s.valid = true;
  s.shift_px = shift_px;
  s.dt_s = baseline / 30.0;
  s.baseline_frames = baseline;
  s.wanted_baseline_frames = wanted;
  return s;
}

vision::FeedSpeedSample Without(vision::SpeedReason reason) {
  vision::FeedSpeedSample s;
  s.reason = reason;
  return s;
}

// A slow filament (0.5 px per frame, 16 frames wanted): the rows before the 16th frame compare
// with nearer frames and are left out, as are a row without a speed and an outlier; the mean is
// that of the rows left in.
TEST(SpeedSummaryTest, LeavesOutShortBaselinesAndOutliersAndSaysWhy) {
  std::vector<vision::FeedSpeedSample> rows = {Without(vision::SpeedReason::kFirstFrame)};
  for (int k = 1; k < 16; ++k) rows.push_back(Speed(0.49 * k, k, 16));  // 14.7 px/s
  for (int i = 0; i < 20; ++i) rows.push_back(Speed(8.0 + 0.01 * (i % 5 - 2), 16, 16));
  rows.push_back(Without(vision::SpeedReason::kNoTexture));
  rows.push_back(Speed(12.0, 16, 16));  // 22.5 px/s
  const FeedSpeedSummary s = SummariseFeedSpeeds(rows);
  ASSERT_EQ(s.use.size(), rows.size());
  EXPECT_EQ(s.use[0], SpeedUse::kNoSpeed);
  EXPECT_EQ(s.use[1], SpeedUse::kShortBaseline);
  EXPECT_EQ(s.use[15], SpeedUse::kShortBaseline);
  EXPECT_EQ(s.use[16], SpeedUse::kUsed);
  EXPECT_EQ(s.use[36], SpeedUse::kNoSpeed);
  EXPECT_EQ(s.use[37], SpeedUse::kOutlier);
  EXPECT_EQ(s.pairs, 37);  // all but the first frame
  EXPECT_EQ(s.with_speed, 36);
  EXPECT_EQ(s.used, 20);
  EXPECT_EQ(s.short_baseline, 15);
  EXPECT_EQ(s.outliers, 1);
  EXPECT_EQ(s.baseline_frames, 16);
  double sum = 0;
  for (size_t i = 0; i < rows.size(); ++i)
    if (s.use[i] == SpeedUse::kUsed) sum += rows[i].SpeedPxPerS();
  EXPECT_DOUBLE_EQ(s.mean_px_per_s, sum / 20);
  EXPECT_NEAR(s.mean_px_per_s, 15.0, 1e-9);
  // One run of 20 rows 16 frames apart: its sum telescopes to its first and last 16 frames, which
  // may err together: the interval is t·sd·√(16²)/20, wider than t·sd/√20.
  EXPECT_NEAR(s.ci95_px_per_s, StudentT975(19) * s.std_px_per_s * 16 / 20, 1e-12);
  EXPECT_STREQ(SpeedUseName(s.use[1]), "short_baseline");
  EXPECT_STREQ(SpeedUseName(s.use[37]), "outlier");
}

// A video too short for any row to reach the baseline it wants: those rows are all there is.
TEST(SpeedSummaryTest, UsesShortBaselinesWhenNoRowReachesItsOwn) {
  const std::vector<vision::FeedSpeedSample> rows = {Without(vision::SpeedReason::kFirstFrame),
                                                     Speed(0.5, 1, 16), Speed(1.0, 2, 16),
                                                     Speed(1.5, 3, 16)};
  const FeedSpeedSummary s = SummariseFeedSpeeds(rows);
  EXPECT_EQ(s.used, 3);
  EXPECT_EQ(s.short_baseline, 0);
  EXPECT_NEAR(s.mean_px_per_s, 15.0, 1e-9);
}

// Consecutive frames (baseline 1) in two runs: the plain t·sd/√n.
TEST(SpeedSummaryTest, ConsecutiveFramesHaveThePlainInterval) {
  std::vector<vision::FeedSpeedSample> rows = {Without(vision::SpeedReason::kFirstFrame)};
  for (int i = 0; i < 30; ++i) rows.push_back(Speed(10.0 + 0.1 * (i % 3 - 1), 1, 1));
  rows.push_back(Without(vision::SpeedReason::kTooFast));
  for (int i = 0; i < 10; ++i) rows.push_back(Speed(10.0 + 0.1 * (i % 3 - 1), 1, 1));
  const FeedSpeedSummary s = SummariseFeedSpeeds(rows);
  EXPECT_EQ(s.used, 40);
  // By hand from the rows: 297, 300 and 303 px/s (a shift of 9.9, 10 or 10.1 px in 1/30 s) 14,
  // 13 and 13 times; t(0.975, 39) = 2.0227 from a table.
  const double mean = (14 * 297.0 + 13 * 300.0 + 13 * 303.0) / 40;
  const double sd = std::sqrt(
      (14 * std::pow(297 - mean, 2) + 13 * std::pow(300 - mean, 2) + 13 * std::pow(303 - mean, 2)) /
      39);
  EXPECT_NEAR(s.mean_px_per_s, mean, 1e-9);
  EXPECT_NEAR(s.std_px_per_s, sd, 1e-9);
  EXPECT_NEAR(s.ci95_px_per_s, 2.0227 * sd / std::sqrt(40.0), 1e-4 * s.ci95_px_per_s);
  EXPECT_DOUBLE_EQ(s.sigma_scale, 1);  // the rows have no σ of their own here
}

TEST(SpeedSummaryTest, NoSpeedsNoMean) {
  const FeedSpeedSummary s = SummariseFeedSpeeds({Without(vision::SpeedReason::kFirstFrame),
                                                  Without(vision::SpeedReason::kNoTexture),
                                                  Without(vision::SpeedReason::kNoTime)});
  EXPECT_EQ(s.pairs, 1);
  EXPECT_EQ(s.used, 0);
  EXPECT_EQ(s.mean_px_per_s, 0);
}

}  // namespace
}  // namespace clogscope::pipeline
