#include "vision/edges/cylinder_track.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/running_stats.h"
#include "vision/edges/cylinder_fit.h"

namespace clogscope::vision {
namespace {

constexpr double kBackground = 35, kLevel = 160;
constexpr double kCentre = 80.3, kRadius = 30, kBlur = 1.5, kAmbient = 0.4, kTilt = 10;
constexpr double kNoise = 1.5;

// A lit cylinder's profile on one caliper's fixed pixels (four rows at 1 px from u = 30 to 130,
// each shifted by shear_px from the last, as a later frame gives the same pixels), blurred by
// numerical convolution — independent of the fit's closed forms — over a background line
// 35 + 0.05·(u − 80) seen beside and behind it. shading_gain scales the Lambertian part,
// light_gain the whole object.
std::vector<EdgeSample> Profile(double centre, double radius, double shading_gain = 1.0,
                                double light_gain = 1.0, double shear_px = 0.27) {
  const auto object = [&](double t) {
    const double x = (t - centre) / radius;
    if (std::abs(x) >= 1) return 0.0;
    return light_gain *
           (kLevel * (kAmbient + shading_gain * (1 - kAmbient) * std::sqrt(1 - x * x)) + kTilt * x);
  };
  std::vector<EdgeSample> s;
  const double h = 0.004;
  for (int row = 0; row < 4; ++row) {
    for (double u = 30 + shear_px * row; u <= 130; u += 1.0) {
      double v = 0, wsum = 0;
      for (double t = u - 6 * kBlur; t <= u + 6 * kBlur; t += h) {
        const double w = std::exp(-0.5 * (u - t) * (u - t) / (kBlur * kBlur));
        v += w * object(t);
        wsum += w;
      }
      s.push_back(
          {static_cast<float>(u), static_cast<float>(kBackground + 0.05 * (u - 80) + v / wsum)});
    }
  }
  return s;
}

std::vector<EdgeSample> Noisy(std::vector<EdgeSample> s, double sigma, std::mt19937* rng) {
  std::normal_distribution<double> n(0, sigma);
  for (auto& smp : s) smp.value = static_cast<float>(smp.value + n(*rng));
  return s;
}

// The template of a full fit on one noisy frame at the reference geometry.
CylinderTemplate ReferenceTemplate(std::mt19937* rng) {
  const auto s = Noisy(Profile(kCentre, kRadius), kNoise, rng);
  const CylinderFit full = FitLitCylinder(s, kCentre - kRadius + 1, kCentre + kRadius - 1, 1.5,
                                          CylinderBackground::kOneLine);
  EXPECT_TRUE(full.converged);
  CylinderTemplate t;
  EXPECT_TRUE(MakeCylinderTemplate(s, full, &t));
  return t;
}

using Stats = testing::RunningStats;

// Frames whose cylinder moved by less than the template's limit: its edges as unbiased as a full
// fit's on the same pixels, as scattered, and its σ describing the scatter. Measured over 100
// draws per move: mean edge and width errors within 0.005 px, the width's scatter within 5 % of the
// full fit's (0.037–0.048 px), the reported width σ 0.81–1.11 of the scatter.
TEST(CylinderTrackTest, SmallMovesAgreeWithTheTruthAsTheFullFitDoes) {
  std::mt19937 rng(17);
  const CylinderTemplate t = ReferenceTemplate(&rng);
  // Centre and radius moves (px) inside the 0.3 px limit by more than the reference fit's own
  // error and a frame's noise (each ~0.03 px).
  const double moves[][2] = {{0.2, 0.0}, {-0.15, 0.1}, {0.1, -0.15}, {-0.05, 0.2}};
  constexpr int kDraws = 100;
  for (const auto& move : moves) {
    const double c = kCentre + move[0], r = kRadius + move[1];
    const auto clean = Profile(c, r);
    Stats track_l, track_r, track_w, full_l, full_r, full_w;
    double reported_w = 0, reported_l = 0;
    for (int i = 0; i < kDraws; ++i) {
      const auto s = Noisy(clean, kNoise, &rng);
      CylinderFit tracked;
      CylinderTemplate each = t;  // the same template in every draw
      ASSERT_EQ(TrackLitCylinder(&each, s, {}, &tracked), CylinderTrackRefusal::kNone)
          << move[0] << " " << move[1] << " draw " << i;
      ASSERT_TRUE(tracked.converged);
      const CylinderFit full = FitLitCylinder(s, t.reference.left_px, t.reference.right_px,
                                              t.reference.sigma_px, CylinderBackground::kOneLine);
      ASSERT_TRUE(full.converged);
      track_l.Add(tracked.left_px - (c - r));
      track_r.Add(tracked.right_px - (c + r));
      track_w.Add(tracked.right_px - tracked.left_px - 2 * r);
      full_l.Add(full.left_px - (c - r));
      full_r.Add(full.right_px - (c + r));
      full_w.Add(full.right_px - full.left_px - 2 * r);
      reported_w += tracked.width_sigma_px / kDraws;
      reported_l += tracked.left_sigma_px / kDraws;
    }
    const std::string where = ::testing::PrintToString(std::vector<double>{move[0], move[1]});
    // The mean over the draws is known to ±2.5 σ/√n ≈ 0.01 px at these noise levels; the
    // tracker's first order in the geometry must not add more than 0.02 px to it.
    EXPECT_NEAR(track_l.mean(), 0, 0.02) << where;
    EXPECT_NEAR(track_r.mean(), 0, 0.02) << where;
    EXPECT_NEAR(track_w.mean(), 0, 0.02) << where;
    EXPECT_NEAR(track_w.mean(), full_w.mean(), 0.01) << where;
    // As scattered as the full fit (same pixels, same loss) ...
    EXPECT_LT(track_w.sd(), 1.2 * full_w.sd()) << where;
    EXPECT_LT(track_l.sd(), 1.2 * full_l.sd()) << where;
    // ... and what it reports is that scatter.
    EXPECT_NEAR(reported_w, track_w.sd(), 0.25 * track_w.sd()) << where;
    EXPECT_NEAR(reported_l, track_l.sd(), 0.25 * track_l.sd()) << where;
    std::printf(
        "move %+.2f %+.2f: tracked left %+.4f ± %.4f (reported %.4f), width %+.4f ± %.4f "
        "(reported %.4f); full width %+.4f ± %.4f\n",
        move[0], move[1], track_l.mean(), track_l.sd(), reported_l, track_w.mean(), track_w.sd(),
        reported_w, full_w.mean(), full_w.sd());
  }
}

// Beyond the first order's reach (0.3 px) the template's shapes are evaluated again where the fit
// moved to: a move of 0.6–1 px is followed, its edges where the full fit on the same pixels puts
// them; a move too far to follow within max_relinearisations is refused, never a width elsewhere.
TEST(CylinderTrackTest, FollowsAMoveBeyondItsFirstOrderByEvaluatingItsShapesAgain) {
  std::mt19937 rng(23);
  const CylinderTemplate reference = ReferenceTemplate(&rng);
  const double moves[][2] = {{0.6, 0}, {-0.6, 0}, {1.0, 0}, {0, 0.6}, {-0.8, -0.5}};
  for (const auto& move : moves) {
    const double c = kCentre + move[0], r = kRadius + move[1];
    const auto s = Noisy(Profile(c, r), kNoise, &rng);
    CylinderTemplate t = reference;
    CylinderFit out;
    const auto refusal = TrackLitCylinder(&t, s, {}, &out);
    const std::string where = ::testing::PrintToString(std::vector<double>{move[0], move[1]});
    ASSERT_EQ(refusal, CylinderTrackRefusal::kNone)
        << where << ": " << CylinderTrackRefusalName(refusal);
    EXPECT_GE(t.relinearisations, 1) << where;
    const CylinderFit full =
        FitLitCylinder(s, reference.reference.left_px, reference.reference.right_px,
                       reference.reference.sigma_px, CylinderBackground::kOneLine);
    ASSERT_TRUE(full.converged);
    // One draw's edges scatter by ~0.03 px: 0.1 px is beyond 3 σ. The full fit on the same
    // pixels differs by the robust scale each takes and the last evaluation's first order (up to
    // 0.3 px from where it ends): up to 0.019 px over 1000 draws (a review's count), where a
    // template's first order alone is off by 0.05–0.1 px at these moves.
    EXPECT_NEAR(out.left_px, c - r, 0.1) << where;
    EXPECT_NEAR(out.right_px, c + r, 0.1) << where;
    EXPECT_NEAR(out.left_px, full.left_px, 0.025) << where;
    EXPECT_NEAR(out.right_px, full.right_px, 0.025) << where;
    // The template now holds the shapes where it moved to: the next frame there needs no more.
    CylinderFit again;
    const int before = t.relinearisations;
    ASSERT_EQ(TrackLitCylinder(&t, Noisy(Profile(c, r), kNoise, &rng), {}, &again, &out),
              CylinderTrackRefusal::kNone)
        << where;
    EXPECT_EQ(t.relinearisations, before) << where;
    EXPECT_NEAR(again.right_px - again.left_px, 2 * r, 0.1) << where;
  }
  // Far moves: 2 and 3 px followed to the right edges within two evaluations; 5 px too far to
  // follow, refused and the template left as it was.
  for (const double shift : {2.0, -3.0, 5.0}) {
    CylinderTemplate t = reference;
    CylinderFit out;
    const auto refusal =
        TrackLitCylinder(&t, Noisy(Profile(kCentre + shift, kRadius), kNoise, &rng), {}, &out);
    if (shift == 5.0) {
      EXPECT_NE(refusal, CylinderTrackRefusal::kNone) << shift;
      EXPECT_FALSE(out.converged) << shift;
      EXPECT_EQ(t.centre_px, reference.centre_px) << shift;
      EXPECT_EQ(t.relinearisations, 0) << shift;
      continue;
    }
    ASSERT_EQ(refusal, CylinderTrackRefusal::kNone)
        << shift << ": " << CylinderTrackRefusalName(refusal);
    EXPECT_NEAR(out.left_px, kCentre + shift - kRadius, 0.1) << shift;
    EXPECT_NEAR(out.right_px, kCentre + shift + kRadius, 0.1) << shift;
  }
  // No more shapes evaluated again than the options allow: refused as moved.
  CylinderTemplate t = reference;
  CylinderTrackOptions first_order_only;
  first_order_only.max_relinearisations = 0;
  CylinderFit out;
  EXPECT_EQ(TrackLitCylinder(&t, Noisy(Profile(kCentre + 0.6, kRadius), kNoise, &rng),
                             first_order_only, &out),
            CylinderTrackRefusal::kMoved);
  EXPECT_FALSE(out.converged);
}

// An object almost along the pixel grid (rows shifted by 0.02 px: Greeff's filament lies at
// 1.2°): each column's four pixels are one group, whose model both fits evaluate once, at the
// group's mean u, and each pixel's value from there by the model's slope. Over 60 draws the full
// fit's and the template's edges are unbiased (within 0.015 px: ±2.5 σ/√n at σ 0.045) and the
// template as scattered as the full fit on the same pixels. (The same draws on rows 0.27 px apart,
// no two pixels in a group: full width −0.014 ± 0.045, tracked −0.006 ± 0.043.)
TEST(CylinderTrackTest, PixelsGroupedByColumnAgreeWithTheTruth) {
  std::mt19937 rng(37);
  constexpr double kShear = 0.02;
  const auto clean_ref = Profile(kCentre, kRadius, 1.0, 1.0, kShear);
  // Noise-free, each pixel's value from its group's by the model's slope: residuals at the
  // silhouettes of a few thousandths of a grey level (taken at the group's value alone they are
  // ~1 level there, with the slope's sign turned ~2), and both scales as small.
  {
    std::vector<double> residuals;
    const CylinderFit clean =
        FitLitCylinder(clean_ref, kCentre - kRadius + 1, kCentre + kRadius - 1, 1.5,
                       CylinderBackground::kOneLine, &residuals);
    ASSERT_TRUE(clean.converged);
    ASSERT_EQ(residuals.size(), clean_ref.size());
    double worst = 0;
    for (size_t i = 0; i < clean_ref.size(); ++i) {
      const double u = clean_ref[i].u_px;
      if (std::abs(u - clean.left_px) < 3 || std::abs(u - clean.right_px) < 3)
        worst = std::max(worst, std::abs(residuals[i]));
    }
    EXPECT_LT(worst, 0.02);
    EXPECT_LT(clean.noise, 0.03);
    CylinderTemplate exact;
    ASSERT_TRUE(MakeCylinderTemplate(clean_ref, clean, &exact));
    EXPECT_LT(exact.noise, 0.03);
  }
  const auto ref = Noisy(clean_ref, kNoise, &rng);
  const CylinderFit reference = FitLitCylinder(ref, kCentre - kRadius + 1, kCentre + kRadius - 1,
                                               1.5, CylinderBackground::kOneLine);
  ASSERT_TRUE(reference.converged);
  CylinderTemplate t;
  ASSERT_TRUE(MakeCylinderTemplate(ref, reference, &t));
  // A group per column about the silhouettes (the last row is a pixel short), fewer inside.
  EXPECT_LE(t.groups.size(), (ref.size() + 3) / 4);
  const double c = kCentre + 0.15, r = kRadius - 0.1;
  const auto clean = Profile(c, r, 1.0, 1.0, kShear);
  Stats full_l, full_w, track_l, track_w;
  for (int i = 0; i < 60; ++i) {
    const auto s = Noisy(clean, kNoise, &rng);
    const CylinderFit full = FitLitCylinder(s, reference.left_px, reference.right_px,
                                            reference.sigma_px, CylinderBackground::kOneLine);
    ASSERT_TRUE(full.converged);
    CylinderTemplate each = t;
    CylinderFit tracked;
    ASSERT_EQ(TrackLitCylinder(&each, s, {}, &tracked), CylinderTrackRefusal::kNone) << i;
    full_l.Add(full.left_px - (c - r));
    full_w.Add(full.right_px - full.left_px - 2 * r);
    track_l.Add(tracked.left_px - (c - r));
    track_w.Add(tracked.right_px - tracked.left_px - 2 * r);
  }
  EXPECT_NEAR(full_l.mean(), 0, 0.015);
  EXPECT_NEAR(full_w.mean(), 0, 0.015);
  EXPECT_NEAR(track_l.mean(), 0, 0.015);
  EXPECT_NEAR(track_w.mean(), 0, 0.015);
  EXPECT_LT(track_w.sd(), 1.2 * full_w.sd());
  std::printf("grouped: full width %+.4f ± %.4f, tracked width %+.4f ± %.4f\n", full_w.mean(),
              full_w.sd(), track_w.mean(), track_w.sd());
}

// A template followed frame by frame while its object drifts (0.75 px a frame at the left
// silhouette, the object narrowing, over 9 px of its slab): its pixels are grouped again wherever
// its shapes are evaluated again (a silhouette read off the interior's wide groups came out
// 0.02 px narrow, and diverged in 19 of 30 sequences at 14 px), and it takes Newton's steps only
// within the first order's reach (beyond it, 5 of 30 sequences ran away). Every frame followed,
// the last one's width within 0.015 px of the truth over 20 sequences (±2.5 σ/√n at σ 0.03).
TEST(CylinderTrackTest, FollowsADriftAcrossItsSlab) {
  std::mt19937 rng(41);
  constexpr double kDriftNoise = 0.5;
  constexpr int kSequences = 20, kFrames = 12;
  const auto ref = Noisy(Profile(kCentre, kRadius), kDriftNoise, &rng);
  const CylinderFit reference = FitLitCylinder(ref, kCentre - kRadius + 1, kCentre + kRadius - 1,
                                               1.5, CylinderBackground::kOneLine);
  ASSERT_TRUE(reference.converged);
  CylinderTemplate start;
  ASSERT_TRUE(MakeCylinderTemplate(ref, reference, &start));
  // The left silhouette 0.75 px inward a frame, the right 0.05.
  std::vector<std::vector<EdgeSample>> clean;
  double c = kCentre, r = kRadius;
  for (int frame = 1; frame <= kFrames; ++frame) clean.push_back(Profile(c += 0.4, r -= 0.35));
  Stats last_w;
  for (int n = 0; n < kSequences; ++n) {
    CylinderTemplate t = start;
    CylinderFit fit = reference;
    for (int frame = 0; frame < kFrames; ++frame) {
      CylinderFit next;
      const auto refusal =
          TrackLitCylinder(&t, Noisy(clean[frame], kDriftNoise, &rng), {}, &next, &fit);
      ASSERT_EQ(refusal, CylinderTrackRefusal::kNone)
          << "sequence " << n << " frame " << frame << ": " << CylinderTrackRefusalName(refusal);
      fit = next;
    }
    last_w.Add(fit.right_px - fit.left_px - 2 * r);
  }
  EXPECT_NEAR(last_w.mean(), 0, 0.015);
  std::printf("drift: last width %+.4f ± %.4f\n", last_w.mean(), last_w.sd());
}

TEST(CylinderTrackTest, RefusesChangedShadingOrLightButFollowsSmallChanges) {
  std::mt19937 rng(29);
  CylinderTemplate t = ReferenceTemplate(&rng);
  CylinderFit out;
  // The Lambertian part 40 % stronger: a change of 0.4·96 = 38 levels, 24 % of a + k = 160.
  EXPECT_EQ(TrackLitCylinder(&t, Noisy(Profile(kCentre, kRadius, 1.4), kNoise, &rng), {}, &out),
            CylinderTrackRefusal::kShadingChanged);
  EXPECT_FALSE(out.converged);
  // The whole object 25 % brighter: 40 levels of 160.
  EXPECT_EQ(
      TrackLitCylinder(&t, Noisy(Profile(kCentre, kRadius, 1.0, 1.25), kNoise, &rng), {}, &out),
      CylinderTrackRefusal::kShadingChanged);
  // 5 % brighter is within the limit (8 levels): followed, the edges where they are.
  ASSERT_EQ(
      TrackLitCylinder(&t, Noisy(Profile(kCentre, kRadius, 1.0, 1.05), kNoise, &rng), {}, &out),
      CylinderTrackRefusal::kNone);
  EXPECT_NEAR(out.left_px, kCentre - kRadius, 0.1);  // ~4 σ of one draw
  EXPECT_NEAR(out.right_px, kCentre + kRadius, 0.1);
  EXPECT_NEAR(out.ambient + out.shading, 1.05 * kLevel, 3.0);
  // Three times the noise: refused as noisier.
  EXPECT_EQ(TrackLitCylinder(&t, Noisy(Profile(kCentre, kRadius), 3 * kNoise, &rng), {}, &out),
            CylinderTrackRefusal::kNoisier);
  // Other pixels (one sample fewer): refused.
  auto fewer = Noisy(Profile(kCentre, kRadius), kNoise, &rng);
  fewer.pop_back();
  EXPECT_EQ(TrackLitCylinder(&t, fewer, {}, &out), CylinderTrackRefusal::kOtherSamples);
}

TEST(CylinderTrackTest, NoTemplateOfAFitWithALineEachSide) {
  std::mt19937 rng(31);
  const auto s = Noisy(Profile(kCentre, kRadius), kNoise, &rng);
  const CylinderFit each_side = FitLitCylinder(s, kCentre - kRadius + 1, kCentre + kRadius - 1, 1.5,
                                               CylinderBackground::kEachSide);
  ASSERT_TRUE(each_side.converged);
  CylinderTemplate t;
  EXPECT_FALSE(MakeCylinderTemplate(s, each_side, &t));
}

}  // namespace
}  // namespace clogscope::vision
