#include "vision/edges/residual_structure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/edge_fit.h"

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

// A vertical edge at x = 120.3 of a flat object (level 60) against a background that rises away
// from it by `gradient` grey levels per px and `curvature` per px² (a lamp's spot), on the right
// (or, mirrored, the left), blurred (σ 2.5 px) and averaged over each pixel, with noise of 1 grey
// level; 16 bit at 100 counts a grey level. Calipers of 4 rows each fit the plain step, as a
// band's calipers do.
struct GradedEdge {
  static constexpr double kEdgeX = 120.3, kBlur = 2.5, kScale = 100.0;
  cv::Mat image;
  AxisFrame axis;  // origin (100, 10), down the column: u = x − 100
  int background_side = +1;
  std::vector<CaliperEdge> calipers;
  double mean_edge_u = 0;
  double window_px = 12.0;  // each caliper's fit, and the band's judging, this far either side
  GradedEdge(double gradient, double curvature, bool mirrored, double noise_sigma = 1.0,
             uint32_t seed = 11, double background = 200.0, double window = 12.0,
             double hair_at_px = 0.0)
      : background_side(mirrored ? -1 : +1), window_px(window) {
    image.create(60, 200, CV_16U);
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0, noise_sigma);
    std::vector<double> column(image.cols);
    for (int x = 0; x < image.cols; ++x) {
      double sum = 0, weight = 0;
      for (double t = x - 0.5 - 6 * kBlur; t <= x + 0.5 + 6 * kBlur; t += 0.005) {
        // The pixel's box [x − ½, x + ½] convolved with the Gaussian: Φ differences.
        const double w = 0.5 * (std::erf((x + 0.5 - t) / (std::sqrt(2.0) * kBlur)) -
                                std::erf((x - 0.5 - t) / (std::sqrt(2.0) * kBlur)));
        const double d = background_side * (t - kEdgeX);  // into the background
        // A dark hair 3 px wide, hair_at_px into the background (none at 0).
        const double hair =
            hair_at_px > 0 ? 100.0 * std::exp(-0.5 * std::pow((d - hair_at_px) / 1.5, 2)) : 0.0;
        sum += w * (d < 0 ? 60.0 : background + gradient * d + curvature * d * d - hair);
        weight += w;
      }
      column[x] = sum / weight;
    }
    for (int y = 0; y < image.rows; ++y)
      for (int x = 0; x < image.cols; ++x)
        image.at<uint16_t>(y, x) = cv::saturate_cast<uint16_t>(kScale * (column[x] + noise(rng)));
    axis.ox = 100;
    axis.oy = 10;
    const GreyImage img{image, true};
    const ClipLevels clip{0, 65535};
    std::vector<EdgeSample> samples;
    const double e0 = kEdgeX - axis.ox;
    for (int k = 0; k < 10; ++k) {
      const double s0 = 4.0 * k, s1 = s0 + 4.0;
      if (!GatherEdgeSamples(img, axis, s0, s1, e0 - window_px, e0 + window_px, clip, &samples))
        continue;
      const EdgeFit fit = FitBlurredStep(samples, e0, 2.0, e0);
      if (!fit.converged) continue;
      calipers.push_back({s0, s1, fit});
      mean_edge_u += fit.edge_px;
    }
    mean_edge_u /= std::max<size_t>(1, calipers.size());
  }
  double TruthU() const { return kEdgeX - axis.ox; }
  BandEdgeDoubt Judge(int side) const {
    const GreyImage img{image, true};
    return JudgeBandEdge(img, axis, ClipLevels{0, 65535}, calipers, window_px, window_px, side,
                         3.0 * window_px);
  }
};

TEST(JudgeBandEdgeTest, ABackgroundSlopingToAFlatObjectMovesTheEdgeWhereItLies) {
  // 3 grey levels per px away from the edge: the plain steps put it 0.53 px off; the pooled
  // two-slope step puts it back within 0.02 px (0.011) and leaves a doubt well below the bias
  // (0.07 px). Mirrored alike.
  for (const bool mirrored : {false, true}) {
    const GradedEdge scene(3.0, 0.0, mirrored);
    ASSERT_EQ(scene.calipers.size(), 10u);
    const double bias = scene.mean_edge_u - scene.TruthU();
    ASSERT_GT(std::abs(bias), 0.1) << "the plain steps should be pulled by the slope";
    const BandEdgeDoubt judged = scene.Judge(scene.background_side);
    EXPECT_NEAR(scene.mean_edge_u + judged.shift_px, scene.TruthU(), 0.02)
        << "mirrored " << mirrored << ", plain bias " << bias;
    EXPECT_LT(judged.doubt_px(), 0.3 * std::abs(bias)) << "mirrored " << mirrored;
    // Told the background is on the object's side, the premise (a flat object) fails: no move,
    // and the move it would have made counts whole as doubt.
    const BandEdgeDoubt wrong_side = scene.Judge(-scene.background_side);
    EXPECT_EQ(wrong_side.shift_px, 0.0) << "mirrored " << mirrored;
    EXPECT_GT(wrong_side.doubt_px(), 0.8 * std::abs(bias)) << "mirrored " << mirrored;
  }
}

TEST(JudgeBandEdgeTest, ACurvedBackgroundIsNotMovedButDoubted) {
  // A lamp's spot: the background bends away from the edge (0.3 grey levels per px²). The
  // two-slope step's move changes with the window's reach: no move, and the plain steps' bias is
  // within the doubt.
  const GradedEdge scene(0.0, 0.3, false);
  ASSERT_EQ(scene.calipers.size(), 10u);
  const double bias = scene.mean_edge_u - scene.TruthU();
  ASSERT_GT(std::abs(bias), 0.05);
  const BandEdgeDoubt judged = scene.Judge(scene.background_side);
  EXPECT_EQ(judged.shift_px, 0.0) << "bias " << bias;
  EXPECT_GT(judged.doubt_px(), 0.5 * std::abs(bias)) << "bias " << bias;
}

TEST(JudgeBandEdgeTest, ABackgroundSlopeTheWindowCannotSeeIsDoubtedFromBeyondIt) {
  // A 40-level step whose background rises 0.6 grey levels per px away from it, under noise of 8,
  // windows of 10 px: the plain steps lie 0.16–0.45 px off, and the window's pooled profile can
  // rarely tell its two slopes from the noise (a doubt of 0.04 px or none in 8 of these 12
  // scenes). The slopes read along the band past it can: the doubt is half the bias or more in
  // each, about the bias on average and not twice it. A flat background under the same noise is
  // doubted little.
  double ratio_sum = 0, flat_sum = 0;
  int scenes = 0;
  for (const bool mirrored : {false, true}) {
    for (const uint32_t seed : {1u, 2u, 3u, 4u, 5u, 6u}) {
      const GradedEdge scene(0.6, 0.0, mirrored, 8.0, seed, 100.0, 10.0);
      ASSERT_GE(scene.calipers.size(), 5u) << "mirrored " << mirrored << ", seed " << seed;
      const double bias = scene.mean_edge_u - scene.TruthU();
      ASSERT_GT(std::abs(bias), 0.15) << "mirrored " << mirrored << ", seed " << seed;
      const BandEdgeDoubt judged = scene.Judge(scene.background_side);
      EXPECT_EQ(judged.shift_px, 0.0) << "mirrored " << mirrored << ", seed " << seed;
      EXPECT_GT(judged.doubt_px(), 0.5 * std::abs(bias))
          << "mirrored " << mirrored << ", seed " << seed;
      ratio_sum += judged.doubt_px() / std::abs(bias);
      const GradedEdge flat(0.0, 0.0, mirrored, 8.0, seed, 100.0, 10.0);
      flat_sum += flat.Judge(flat.background_side).doubt_px();
      ++scenes;
    }
  }
  EXPECT_GT(ratio_sum / scenes, 0.8);
  EXPECT_LT(ratio_sum / scenes, 1.6);
  EXPECT_LT(flat_sum / scenes, 0.1);
}

TEST(JudgeBandEdgeTest, AHairFartherOutIsNotTheBackgroundsSlope) {
  // A flat background with a dark hair 26 px beyond the edge (the reach the slopes are read over
  // is three windows of 10 px): read to the hair, the background would slope by several grey
  // levels per px toward the edge; read short of it, it is flat. The edge is where it was, and
  // doubted no more than without the hair.
  for (const bool mirrored : {false, true}) {
    for (const uint32_t seed : {1u, 2u, 3u}) {
      const GradedEdge hair(0.0, 0.0, mirrored, 8.0, seed, 100.0, 10.0, 26.0);
      const GradedEdge bare(0.0, 0.0, mirrored, 8.0, seed, 100.0, 10.0);
      ASSERT_GE(hair.calipers.size(), 5u) << "mirrored " << mirrored << ", seed " << seed;
      const BandEdgeDoubt judged = hair.Judge(hair.background_side);
      EXPECT_EQ(judged.shift_px, 0.0) << "mirrored " << mirrored << ", seed " << seed;
      EXPECT_LE(judged.doubt_px(), bare.Judge(bare.background_side).doubt_px() + 0.05)
          << "mirrored " << mirrored << ", seed " << seed;
    }
  }
}

TEST(JudgeBandEdgeTest, AFlatBackgroundLeavesTheEdgeInPlace) {
  const GradedEdge scene(0.0, 0.0, false);
  ASSERT_EQ(scene.calipers.size(), 10u);
  EXPECT_NEAR(scene.mean_edge_u, scene.TruthU(), 0.02);
  const BandEdgeDoubt judged = scene.Judge(scene.background_side);
  EXPECT_EQ(judged.shift_px, 0.0);
  EXPECT_LT(judged.doubt_px(), 0.05);
}

}  // namespace
}  // namespace clogscope::vision
