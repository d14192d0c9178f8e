#include "pipeline/statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace clogscope::pipeline {
namespace {

TEST(StatisticsTest, StudentQuantilesMatchTables) {
  // Two-sided 95 % critical values of Student's t (standard tables).
  const std::pair<int, double> table[] = {{1, 12.706},  {2, 4.303},  {5, 2.571},  {6, 2.447},
                                          {9, 2.262},   {10, 2.228}, {20, 2.086}, {29, 2.045},
                                          {49, 2.0096}, {100, 1.984}};
  for (const auto& [dof, t] : table) EXPECT_NEAR(StudentT975(dof), t, 1.5e-3) << dof;
  EXPECT_TRUE(std::isnan(StudentT975(0)));
}

TEST(StatisticsTest, RobustStatsRejectsOnlyTheOutliers) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(133.3, 0.5);
  std::vector<double> v;
  for (int i = 0; i < 48; ++i) v.push_back(n(rng));
  v.push_back(140);  // a drop of melt on the strand
  v.push_back(120);
  const SampleStats s = RobustStats(v);
  EXPECT_EQ(s.n_rejected, 2);
  EXPECT_FALSE(s.used[48]);
  EXPECT_FALSE(s.used[49]);
  EXPECT_NEAR(s.mean, 133.3, 0.3);
  EXPECT_NEAR(s.std, 0.5, 0.15);
  // The kept 48 by hand: their mean, sample standard deviation, its SEM, and t(0.975, 47) = 2.0117
  // from a table.
  double sum = 0, squares = 0;
  for (int i = 0; i < 48; ++i) sum += v[i];
  const double mean = sum / 48;
  for (int i = 0; i < 48; ++i) squares += (v[i] - mean) * (v[i] - mean);
  const double sem = std::sqrt(squares / 47) / std::sqrt(48.0);
  EXPECT_NEAR(s.mean, mean, 1e-12);
  EXPECT_NEAR(s.sem, sem, 1e-12);
  EXPECT_NEAR(s.ci95_half_width, 2.0117 * sem, 1e-4 * s.ci95_half_width);
  // Identical values: the MAD floor keeps a 0.01 px difference from being an outlier.
  const SampleStats flat = RobustStats({5, 5, 5, 5, 5.01}, 3.5, 0.02);
  EXPECT_EQ(flat.n_rejected, 0);
}

// The share of simulated steps whose 95 % interval covers the true width: each step is 50 frames
// with a shared error (drawn from N(0, shared_px)), each frame's own noise (N(0, noise_px)) and,
// when `repeat`, every frame a copy of the first one's noise; the frames report their σ as a
// measurement does (the whole, and the model's part).
double Coverage(double shared_px, double noise_px, bool repeat, double reported_model_px,
                bool* flagged_all) {
  std::mt19937 rng(7);
  std::normal_distribution<double> unit(0.0, 1.0);
  constexpr double kTruePx = 50.0;
  constexpr int kSteps = 2000, kFrames = 50;
  int covered = 0;
  *flagged_all = true;
  for (int s = 0; s < kSteps; ++s) {
    const double shared = shared_px * unit(rng);
    const double first = noise_px * unit(rng);
    FrameWidths widths;
    for (int f = 0; f < kFrames; ++f) {
      // A codec's copies still differ in the last bits of their fit.
      const double noise = repeat ? first + 1e-4 * unit(rng) : noise_px * unit(rng);
      widths.Add(kTruePx + shared + noise, std::hypot(noise_px, reported_model_px),
                 reported_model_px);
    }
    const WidthStats st = RobustWidthStats(widths);
    *flagged_all = *flagged_all && st.frames_repeat == repeat;
    covered += std::abs(st.mean - kTruePx) <= st.ci95_half_width;
  }
  return static_cast<double>(covered) / kSteps;
}

TEST(StatisticsTest, AStepsIntervalCoversTheWidthWhenFramesAreIndependent) {
  bool flagged = false;
  EXPECT_NEAR(Coverage(0.0, 0.07, false, 0.0, &flagged), 0.95, 0.015);
  EXPECT_TRUE(flagged);  // none taken for repeats
}

TEST(StatisticsTest, AStepsIntervalCoversAnErrorEveryFrameShares) {
  // The model's doubt (a shading or structure the frames share) does not average down: the
  // scatter alone covered 30 % of such steps.
  bool flagged = false;
  EXPECT_NEAR(Coverage(0.05, 0.07, false, 0.05, &flagged), 0.95, 0.02);
  EXPECT_TRUE(flagged);
}

TEST(StatisticsTest, AStepOfRepeatedFramesCountsAsOneFrame) {
  // Fifty copies of one frame (a still scene through H.264, whose skipped blocks repeat one
  // frame's noise): their scatter is nothing, their mean one frame's error. The scatter alone
  // covered 0.03 % of such steps.
  bool flagged = false;
  EXPECT_NEAR(Coverage(0.0, 0.07, true, 0.0, &flagged), 0.95, 0.015);
  EXPECT_TRUE(flagged);  // every step said so
}

TEST(StatisticsTest, HoldsFromATemperatureLog) {
  // 220 for 60 s, ramp down to 210 over 20 s, 210 for 60 s, ramp, 200 for 10 s (too short).
  std::vector<TemperatureSample> log;
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0, 0.2);
  for (int t = 0; t <= 170; ++t) {
    double temp;
    if (t < 60)
      temp = 220;
    else if (t < 80)
      temp = 220 - 0.5 * (t - 60);
    else if (t < 140)
      temp = 210;
    else if (t < 160)
      temp = 210 - 0.5 * (t - 140);
    else
      temp = 200;
    log.push_back({double(t), temp + noise(rng)});
  }
  const auto holds = FindHolds(log, 1.0, 15.0, 20.0);
  ASSERT_EQ(holds.size(), 2u);
  EXPECT_NEAR(holds[0].temperature_c, 220, 0.2);
  EXPECT_NEAR(holds[0].start_s, 15, 1e-9);
  EXPECT_NEAR(holds[0].end_s, 60, 2.5);
  EXPECT_NEAR(holds[1].temperature_c, 210, 0.2);
  EXPECT_GT(holds[1].start_s, 78);
  // Never settles: a steady ramp.
  std::vector<TemperatureSample> ramp;
  for (int t = 0; t < 100; ++t) ramp.push_back({double(t), 220 - 0.5 * t});
  EXPECT_TRUE(FindHolds(ramp, 1.0, 5.0, 10.0).empty());
}

}  // namespace
}  // namespace clogscope::pipeline
