// The Cramér–Rao bound on an adversarial scene's width (synthetic/adversarial_bound.h), against the
// closed form for blurred steps and against the scatter of the production measurement on rendered
// frames (no unbiased measurement that reads each edge from its transition scatters less).
#include "synthetic/adversarial_bound.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "synthetic/adversarial_matrix.h"
#include "synthetic/adversarial_optics.h"
#include "tests/scratch_dir.h"

namespace clogscope::synthetic {
namespace {

// A flat, untilted strand on a plain background through a lossless codec.
AdversarialScene FlatStrand(double width_px, double blur_px, double noise) {
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kPlain, 7);
  p.width_px = 640;
  p.height_px = 480;
  p.tip_x_px = 320;
  p.tip_y_px = 120;
  p.scale_um_per_px = 5.0;
  p.width_um = width_px * p.scale_um_per_px;
  p.tilt_deg = 0;
  p.codec = Codec::kPng;
  p.shading_ambient = 1;
  p.background_texture = 0;
  p.background_slope = 0;
  p.spot_level = 0;
  p.background_level = 180;
  p.strand_level = 60;
  p.nozzle_level = 120;
  p.blur_sigma_px = blur_px;
  p.noise_sigma = noise;
  return p;
}

TEST(AdversarialBoundTest, AWideStrandsBoundIsTheClosedFormOfTwoBlurredSteps) {
  // Far from each other, each edge's place is learnt from its transition alone, the levels from
  // the plateaus: per px of band, Σ (C·k(u))² / v = C² / (2√π σ v) with σ² = blur² + 1/12 (the
  // pixel's box, as a Gaussian), so σ_w² = 2 · 2√π σ v / (L C²). The noise's variance v is the
  // shot noise's at the transition's middle level; the bound lies a few % above the closed form
  // (the blur and the levels are unknowns too, the variance changes across the transition).
  const AdversarialScene p = FlatStrand(120.0, 1.5, 6.0);
  const double c = p.background_level - p.strand_level;
  const double sigma = std::sqrt(1.5 * 1.5 + 1.0 / 12.0);
  const double length_px = kBandLengthUm / p.scale_um_per_px;
  const double v =
      NoiseVariance(p.noise_sigma, 0.5 * (p.background_level + p.strand_level)) + 1.0 / 12.0;
  const double closed = std::sqrt(2 * 2 * std::sqrt(M_PI) * sigma * v / (length_px * c * c));
  const double bound = WidthBoundSigmaPx(p, 120.0);
  EXPECT_GT(bound, 0.98 * closed);  // 1.044 when written
  EXPECT_LT(bound, 1.10 * closed);
  // And it scales with the noise and the band's length as a σ must.
  AdversarialScene q = p;
  q.noise_sigma = 2 * p.noise_sigma;
  EXPECT_NEAR(WidthBoundSigmaPx(q, 120.0) / bound, 2.0, 0.02);
  q = p;
  q.scale_um_per_px = 4 * p.scale_um_per_px;  // a quarter of the band's px
  EXPECT_NEAR(WidthBoundSigmaPx(q, 120.0) / bound, 2.0, 0.02);
}

TEST(AdversarialBoundTest, TheMeasurementScattersNoLessThanTheBound) {
  // 40 frames of one scene, independent noise, measured as the matrix measures them: the widths'
  // scatter is at least the bound (less the scatter's own uncertainty over 40 frames, ~11 %), and
  // an efficient measurement comes within a small factor of it.
  static const testutil::ScratchDir dir("clogscope_adversarial_bound_test");
  for (const double blur : {1.0, 2.5}) {
    const AdversarialScene p = FlatStrand(60.0, blur, 10.0);
    AdversarialTruth truth;
    const std::vector<cv::Mat> frames = RenderAdversarial(p, 40, dir.path().string(), &truth);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (const cv::Mat& f : frames) {
      const vision::StrandMeasurement m = MeasureAdversarialFrame(f, p);
      if (!m.gave_width()) continue;
      sum += m.width_px;
      sum2 += m.width_px * m.width_px;
      ++n;
    }
    ASSERT_GE(n, 30) << "blur " << blur;
    const double sd = std::sqrt((sum2 - sum * sum / n) / (n - 1));
    const double bound = WidthBoundSigmaPx(p, truth.width_px);
    EXPECT_GT(sd, 0.75 * bound) << "blur " << blur << ": sd " << sd << " px, bound " << bound;
    EXPECT_LT(sd, 3.0 * bound) << "blur " << blur << ": sd " << sd << " px, bound " << bound;
  }
}

TEST(AdversarialBoundTest, NothingToMeasureHasNoBound) {
  AdversarialScene p = FlatStrand(60.0, 1.5, 5.0);
  p.strand_level = p.background_level;  // the strand's light is the background's
  EXPECT_TRUE(std::isinf(WidthBoundSigmaPx(p, 60.0)));
  p = FlatStrand(60.0, 1.5, 5.0);
  p.strand = false;
  EXPECT_TRUE(std::isinf(WidthBoundSigmaPx(p, 60.0)));
}

}  // namespace
}  // namespace clogscope::synthetic
