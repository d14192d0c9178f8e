// Scenes from the adversarial renderer (synthetic/adversarial.h) built around one trouble each,
// measured with the default options and judged against the render's geometric truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "tests/synthetic/adversarial_test_util.h"
#include "vision/scene/scene.h"
#include "vision/scene/track.h"

namespace clogscope::synthetic {
namespace {

// Seed 3 of the plain class without what the class draws at random besides: a flat strand on a
// flat, untextured background, lossless.
AdversarialScene FlatPlainScene() {
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kPlain, 3);
  p.codec = Codec::kPng;
  p.shading_ambient = 1;
  p.background_texture = 0;
  p.background_slope = 0;
  return p;
}

TEST(AdversarialTest, RendererKeepsTheGeometricWidthOfAPlainStrand) {
  // The renderer's own honesty: a flat strand, no noise, lossless, measured within 0.05 px.
  AdversarialScene p = FlatPlainScene();
  p.noise_sigma = 0;
  p.blur_sigma_px = 1.2;
  AdversarialTruth t;
  const vision::StrandMeasurement m = RenderAndMeasure(p, &t);
  ASSERT_TRUE(m.valid()) << m.detail << " " << Describe(p);
  EXPECT_NEAR(m.width_px, t.width_px, 0.05) << Describe(p);
  EXPECT_NEAR(m.tip_y_px, t.tip_y_px, 1.5);
}

TEST(AdversarialTest, BacklitLensIsMeasuredAtItsOuterSilhouette) {
  // A transparent strand on a backlight: dark rims, a bright core of 15–50 % of the width. The
  // core, or one rim, is never the strand; the outer silhouette is.
  int valid = 0;
  for (uint64_t seed = 1; seed <= 6; ++seed) {
    const AdversarialScene p = RandomAdversarialScene(TroubleClass::kBacklitLens, seed);
    AdversarialTruth t;
    const vision::StrandMeasurement m = RenderAndMeasure(p, &t);
    if (!m.valid()) continue;
    ++valid;
    EXPECT_EQ(m.polarity, vision::Polarity::kDarkOnBright) << Describe(p);
    EXPECT_NEAR(m.width_px, t.width_px, WrongTolerancePx(t.width_px)) << Describe(p);
  }
  EXPECT_GE(valid, 5);
}

TEST(AdversarialTest, ALensCoreWithinReachOfABlurredRimIsFittedWithIt) {
  // A 40 px lens at a blur of 2.7 px whose core begins 11.5 px inside each silhouette (seed 620,
  // without its noise and texture): judged at the first guess of the blur (1.5 px), the windows
  // stopped short of the core instead of fitting it, and held 1.4 blurs of the rim: each edge
  // came out 0.09 px outward, 39.77 px against 39.59. Lenses whose core lies deeper (a smaller
  // acceptance) are the control.
  for (const double acceptance_rad : {0.12, 0.29, 0.33}) {
    AdversarialScene p = RandomAdversarialScene(TroubleClass::kBacklitLens, 620);
    p.noise_sigma = 0;
    p.background_texture = 0;
    p.lens_acceptance_rad = acceptance_rad;
    AdversarialTruth t;
    const vision::StrandMeasurement m = RenderAndMeasure(p, &t);
    ASSERT_TRUE(m.valid()) << m.detail << " " << Describe(p);
    EXPECT_NEAR(m.width_px, t.width_px, 0.05) << Describe(p);
  }
}

TEST(AdversarialTest, ALensCoreAcrossTheMiddleIsFittedWithItsRim) {
  // Narrow lenses at a large blur (seeds 6003 and 6707 without their noise, texture and codec):
  // a 35 px lens at a blur of 3.0 px and a 32 px one at 2.9 px, their cores 10 px inside each
  // silhouette and reaching past the middle. Once the blur was fitted the windows stopped short of
  // the core with one blur of the rim in them (the core, its far side within reach, was taken for
  // a narrow stripe, whose model fails), and the widths came out 0.28 and 0.35 px wide here (in
  // the matrix, with noise, 0.22-0.45 px wide and valid at sigma 0.03-0.08: four frames
  // confidently wrong). Fitted with the core's near step, the window stopping at the middle: within
  // 0.05 px.
  for (const uint64_t seed : {6003, 6707}) {
    AdversarialScene p = RandomAdversarialScene(TroubleClass::kBacklitLens, seed);
    p.noise_sigma = 0;
    p.background_texture = 0;
    p.codec = Codec::kPng;
    AdversarialTruth t;
    const vision::StrandMeasurement m = RenderAndMeasure(p, &t);
    ASSERT_TRUE(m.valid()) << m.detail << " " << Describe(p);
    EXPECT_NEAR(m.width_px, t.width_px, 0.05) << Describe(p);
  }
}

TEST(AdversarialTest, ACoreTooNarrowToFitIsLeftAsItWas) {
  // Where a core's near step cannot be fitted at the middle, the windows stay short of it: a
  // 34 px lens whose 8 px core lies 13 px inside at a blur of 2.4 px (4 px of it within reach of
  // the middle: no caliper found both edges with it), and a dark 27 px strand whose 3 px stripe,
  // blurred to 6.5 px, lies by the middle (no plateau to fit). Both were valid and right, and
  // became `occluded` when their cores were fitted.
  ExpectMatrixFramesValidAndRight(RandomAdversarialScene(TroubleClass::kBacklitLens, 7103));
  ExpectMatrixFramesValidAndRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 4012));
}

TEST(AdversarialTest, ClippedStrandThroughH264IsSaturatedNotMeasured) {
  // A strand (seeds 7, 11) or its background (14, 116, 119) clipped before x264, read as
  // `measure` reads it (the luma as stored): the clip sits at 233-235, by the limited range's
  // white, with the codec's ringing on both sides of it (in a key frame, 296 pixels at 235 and
  // 180 above), where a check for a clip at 255 does not look. Such frames were measured valid
  // 0.7-1.7 px off at σ 0.04-0.15: the clipped side's step is cut short. (Read in BGR, as
  // OpenCV's reader gave them, the ringing above clipped into one spike at 255.)
  for (uint64_t seed : {3, 7, 11, 14, 116, 119}) {
    AdversarialScene p = RandomAdversarialScene(TroubleClass::kSaturated, seed);
    p.codec = Codec::kH264;
    AdversarialTruth t;
    ClipFacts clip;
    const cv::Mat f = RenderAdversarial(p, 1, Scratch().string(), &t, &clip)[0];
    EXPECT_EQ(clip.luma_range, vision::LumaRange::kLimited);
    const vision::StrandMeasurement m = MeasureAdversarialFrame(f, p, clip);
    EXPECT_FALSE(m.valid() && std::abs(m.width_px - t.width_px) > WrongTolerancePx(t.width_px))
        << m.width_px << " px, truth " << t.width_px << ": " << Describe(p);
    if (!m.valid()) {
      EXPECT_EQ(m.status, vision::FrameStatus::kSaturated) << m.detail;
    }
  }
}

TEST(AdversarialTest, ABacklightClippedThroughH264AtALowRateIsSaturatedNotMeasured) {
  // Dark strands on a backlight above white (347, 330), through x264 as the matrix's four-frame
  // clips: the clipped plateau in the band's slab came out at 235 with its ringing mostly inside
  // it (seed 1316: 488 at 235, a mean of 115 a bin in the four below), or split over 235 and 236
  // (seed 1318: 374 and 334). Neither was taken for a clip, and every frame was measured valid
  // 0.71-0.80 px narrow at sigma 0.06-0.07: the clipped side's step cut short.
  for (const uint64_t seed : {1316, 1318}) {
    AdversarialTruth t;
    for (const vision::StrandMeasurement& m :
         MeasuredMatrixFrames(RandomAdversarialScene(TroubleClass::kSaturated, seed), &t)) {
      EXPECT_EQ(m.status, vision::FrameStatus::kSaturated)
          << "seed " << seed << ": " << m.width_px << " px, truth " << t.width_px;
    }
  }
}

TEST(AdversarialTest, ALightClippedBesideAnEdgeIsNotTakenAtItsClip) {
  // Clipped pixels in an edge's window, too few in its transition to make the frame `saturated`:
  // a lamp's spot behind one edge of a dark 116.8 px strand through H.264, its background clipped
  // at the luma's white from 3.5 px out (background spot 4400), and a stripe clipped at white
  // 8 px inside a dark 89.7 px strand, fitted with the edge, through JPEG (specular stripe 4033).
  // Fitted at their values, the clip cut the steps short: 4400's four frames came out 0.66 px
  // narrow at sigma 0.08-0.19, 4033's first 0.55 px wide at sigma 0.125. Censored, the spot's
  // edge has its blur (1.96 px, from 1.81; 2.0 rendered), and its transitions hold 9 % clipped
  // pixels; 4033's stripe, smeared by JPEG below its clip, still pulls its edge, but the
  // censored fit runs beyond the clip, and the calipers share that excess as residual structure
  // (0.31 px).
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kBackgroundSpot, 4400));
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 4033));
}

TEST(AdversarialTest, OneEdgeSlidingAlongTheBandCarriesItsDoubt) {
  // A lit 81 px strand through H.264, a lamp's spot (+100, sigma 8 px) 12 px outside its left
  // edge by the band's lower end (background spot 10205): the spot lifted the left background to
  // the rim's level and the left edge slid 1.7 px in over the band while the right held, the
  // band's middle turning 3° off the pair's axis. Its width trend was taken for a swell's: four
  // frames 0.87-0.94 px narrow at sigma 0.09-0.11, valid.
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kBackgroundSpot, 10205));
}

TEST(AdversarialTest, ALitStrandWhoseShadingNoiseHidesCarriesTheCylindersDoubt) {
  // A bright 205 px strand lit almost flat (ambient 0.75, the lamp 1° off the camera's axis),
  // noise 9.9, through H.264 (plain 10289): its √d shading pulls a plain step 0.4 px in a side.
  // Too noisy to decide on shading, both sides were taken as plain, and the shaded fits' own
  // outward shift, the doubt, came to 0.1-0.2 px: frames 1.0-1.1 px narrow at sigma 0.23-0.29,
  // valid. The cylinders put the sides 0.15-0.5 px out, and no frame is valid. (Their σ then
  // covers their error to 3.0σ, not within it: the codec and the background's texture add to
  // the shading's pull.)
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kPlain, 10289);
  AdversarialTruth t;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t);
  for (size_t i = 0; i < measured.size(); ++i) {
    if (measured[i].valid()) ExpectWidthRight(measured[i], t, i, p);
  }
}

TEST(AdversarialTest, AHighlightAtTheRimOfAFlatStrandCarriesItsDoubt) {
  // Bright flat strands with a brighter stripe 2.8 px inside one edge, closer than the blur lets
  // it show as an edge of its own: the edge's fitted step took the stripe in and moved inward,
  // 0.43-0.51 px at sigma 0.07-0.12 (seed 201, 81 px, blur 2.1), 2.0 px at 0.11 (seed 506, 79 px,
  // blur 1.8, the stripe brighter above the strand than the strand above the background).
  for (const uint64_t seed : {201, 506})
    ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, seed));
}

TEST(AdversarialTest, AStripeWithinOneEdgesBlurCarriesItsDoubt) {
  // A dark 123 px strand whose near-white stripe lies by its edge, through JPEG: the edge's step
  // took the stripe in, 1.5 times as blurred as the other edge, and the width came out 0.7-0.8 px
  // wide at sigma 0.11, valid. (A shaded strand's stripe, seed 214, blurs its edge as much but
  // in noise that leaves the blurs' medians in doubt: still 1.4 px narrow in one frame of four.)
  ExpectMatrixFramesRefusedOrRight(RandomAdversarialScene(TroubleClass::kSpecularStripe, 202));
}

TEST(AdversarialTest, AStripeByTheRimOfAStrandShadedOnBothSidesCarriesItsDoubt) {
  // A lit 40 px strand shaded on both sides, a faint stripe (17 levels) 3.6 px inside one rim:
  // the two merge within the blur (2.3 px) and that edge came out 0.75 px inward, 1.18 times as
  // blurred as the other, valid at sigma 0.06 even without noise or texture. (Through the
  // matrix's JPEG at q45 with texture, two frames of four are still 0.8-0.9 px narrow at sigma
  // 0.08: the blurs' noise hides the excess. docs/accuracy.md.)
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 2715);
  p.light_deg = 0;  // as drawn: lit from the camera's side
  p.codec = Codec::kPng;
  p.noise_sigma = 0.5;
  p.background_texture = 0;
  ExpectMatrixFramesRefusedOrRight(p);
}

TEST(AdversarialTest, AStripeInsideALitStrandLeavesItsCylindersInDoubt) {
  // A bright 90.6 px strand lit from one side, through H.264, a brighter stripe (clipped at the
  // luma's white) 2 px inside one rim: refitted as lit cylinders, whose smooth interior the stripe
  // breaks, the other edge came 0.85 px inside the per-edge fit's, within the blur (2.8 px), and
  // the width 1.5 px narrow, valid at sigma 0.12-0.15 in three frames of four.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 4063);
  AdversarialTruth t;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t);
  for (size_t i = 0; i < measured.size(); ++i) {
    const vision::StrandMeasurement& m = measured[i];
    if (!m.gave_width()) continue;
    const double error_px = std::abs(m.width_px - t.width_px);
    if (m.valid()) {
      EXPECT_LE(error_px, WrongTolerancePx(t.width_px)) << "frame " << i;
    }
    EXPECT_LE(error_px, kCoveredSigmas * m.width_sigma_px)
        << "frame " << i << ": " << m.width_px << " ± " << m.width_sigma_px << " px, truth "
        << t.width_px << " " << Describe(p);
  }
}

TEST(AdversarialTest, AStrandLitFromOneSideIsMeasuredToItsDarkRim) {
  // A lit 95 px strand, its Lambertian part 0.6 of its light, under a lamp 25° off to either
  // side: its far rim is at the ambient level out to the terminator, 4.4 px inside. Without that
  // strip in the lit cylinder's model its silhouette came out 0.3 px outward.
  AdversarialScene p = FlatPlainScene();
  p.background_level = 40;
  p.strand_level = 200;
  p.shading_ambient = 0.4;
  p.noise_sigma = 2;
  for (const double light_deg : {25.0, -25.0}) {
    p.light_deg = light_deg;
    AdversarialTruth t;
    for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
      ASSERT_TRUE(m.valid()) << m.detail << ": " << Describe(p);
      EXPECT_NEAR(m.width_px, t.width_px, 0.1) << Describe(p);
    }
  }
}

TEST(AdversarialTest, LightSlopingAcrossAFlatStrandIsNoStepBesideAnEdge) {
  // Lit from one side, a flat strand's level falls across it: its two edges read different
  // levels inside it with nothing beside either. The level's trend across the strand's middle
  // accounts for that (without it these were imprecise at sigma 0.25-0.8 px, all within 0.1 px).
  AdversarialScene p = FlatPlainScene();
  p.noise_sigma = 2;
  p.tilt_deg = 0;
  p.blur_sigma_px = 1.5;
  AdversarialTruth t;
  const cv::Mat frame = RenderAdversarial(p, 1, Scratch().string(), &t)[0];
  for (const double fall : {0.15, 0.3}) {
    // The strand's excess over the background scaled from 1 at its left edge to 1 − fall at its
    // right.
    cv::Mat lit = frame.clone();
    const double left = p.tip_x_px - 0.5 * t.width_px;
    for (int y = 0; y < lit.rows; ++y) {
      for (int x = 0; x < lit.cols; ++x) {
        const double across = std::clamp((x - left) / t.width_px, 0.0, 1.0);
        const double v =
            p.background_level + (frame.at<uchar>(y, x) - p.background_level) * (1 - fall * across);
        lit.at<uchar>(y, x) = cv::saturate_cast<uchar>(v);
      }
    }
    const vision::StrandMeasurement m = MeasureAdversarialFrame(lit, p);
    ASSERT_TRUE(m.valid()) << "fall " << fall << ": " << m.detail << " " << Describe(p);
    EXPECT_LE(std::abs(m.width_px - t.width_px), WrongTolerancePx(t.width_px)) << fall;
  }
}

TEST(AdversarialTest, ACompressedColourFrameIsMeasuredInLuma) {
  // A Bayer camera's frames through JPEG q49 (4:2:0; matrix seed 102 of the unseen set): the
  // strand is found in red, its strongest channel, where the half-resolution chroma blurs the
  // edges to 2.2 px against luma's 1.8. Measured in red, frames 2 and 3 came out 0.30–0.34 px
  // narrow at σ 0.09, valid. Luma, the codec's full-resolution channel, holds; where its textured
  // ground's slope by the edges makes it too doubtful to be valid, red, whose edges are blurrier,
  // carries that doubt too. So no width is confidently wrong, and every one given is within 3σ
  // of the truth at a σ that says something (at most three times what a valid width may carry).
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kBayer, 102);
  ASSERT_EQ(p.codec, Codec::kJpeg);
  AdversarialTruth t;
  int given = 0;
  for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
    if (!m.gave_width()) continue;
    ++given;
    const double error_px = std::abs(m.width_px - t.width_px);
    const std::string what = std::string(vision::FrameStatusName(m.status)) + " " +
                             std::to_string(m.width_px) + " ± " + std::to_string(m.width_sigma_px) +
                             " px: " + Describe(p);
    if (m.valid()) {
      EXPECT_LE(error_px, WrongTolerancePx(t.width_px)) << what;
    }
    EXPECT_LE(error_px, 3 * m.width_sigma_px) << what;
    EXPECT_LE(m.width_sigma_px, 3 * vision::MaxValidSigmaPx({}, m.width_px)) << what;
  }
  EXPECT_GE(given, 3) << Describe(p);
}

TEST(AdversarialTest, AColourChannelThatCarriesLumasDoubtIsNotFollowedAlone) {
  // A Bayer camera through H.264 (matrix seed 109): in frames 1 and 2 the strand's channel is
  // valid where luma is only imprecise, and carries luma's doubt about the scene, which only
  // both channels measured together give. A tracker, which follows one channel, finds each such
  // frame afresh (and the frames after it); its widths are within the tolerance of the truth.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kBayer, 109);
  AdversarialTruth t;
  ClipFacts clip;
  const std::vector<cv::Mat> frames = RenderAdversarial(p, 4, Scratch().string(), &t, &clip);
  const vision::StrandMeasureOptions o = AdversarialMeasureOptions(p, clip);
  vision::StrandTracker tracker(o);
  int carried = 0;
  for (size_t i = 0; i < frames.size(); ++i) {
    vision::SceneResult scene;
    vision::FindAndMeasure(frames[i], o, &scene);
    carried += scene.channel_doubts_luma;
    const vision::StrandMeasurement m = tracker.Measure(frames[i]);
    if (m.valid()) {
      EXPECT_LE(std::abs(m.width_px - t.width_px), WrongTolerancePx(t.width_px))
          << "frame " << i << ": " << m.width_px << " ± " << m.width_sigma_px << " px";
    }
  }
  ASSERT_GE(carried, 1) << Describe(p);
  EXPECT_EQ(tracker.tracked_frames(), 0) << Describe(p);
}

TEST(AdversarialTest, ALitCylinderThatTradedItsBlurForAStripeIsNotTrusted) {
  // A shaded lit strand with a stripe near one edge, through H.264 (matrix seed 8): the lit
  // cylinders put the far silhouette 6 px inside the per-edge fits' (their blur 4.9 px against
  // 3.6), and every frame came out 8 px narrow at σ 0.08, valid. Now refused, with a σ of at
  // least half a px.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 8);
  AdversarialTruth t;
  for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
    EXPECT_FALSE(m.valid()) << m.width_px << " ± " << m.width_sigma_px << " px, truth "
                            << t.width_px << ": " << Describe(p);
    if (m.status == vision::FrameStatus::kImprecise) {
      EXPECT_GT(m.width_sigma_px, 0.5) << Describe(p);
    }
  }
}

// The scene's four matrix frames each give a width within 3σ of the truth, and within the
// matrix's tolerance where valid.
void ExpectMatrixFramesWithinTheirSigma(const AdversarialScene& p) {
  AdversarialTruth t;
  ClipFacts clip;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t, &clip);
  if (p.codec == Codec::kH264) {
    ASSERT_TRUE(clip.encoder.found);
  }
  for (const vision::StrandMeasurement& m : measured) {
    ASSERT_TRUE(m.gave_width()) << m.detail << ": " << Describe(p);
    EXPECT_LE(std::abs(m.width_px - t.width_px), 3 * m.width_sigma_px)
        << m.width_px << " ± " << m.width_sigma_px << " px (codec " << m.codec_sigma_px
        << "), truth " << t.width_px << ": " << Describe(p);
    if (m.valid()) {
      EXPECT_LE(std::abs(m.width_px - t.width_px), WrongTolerancePx(t.width_px)) << Describe(p);
    }
  }
}

TEST(AdversarialTest, AWidthX264MovedCarriesTheCodecsDoubt) {
  // A lit strand through x264 at its defaults (matrix seed 109 of the unseen set, bend below the
  // band, with a third of its noise): x264's adaptive quantisation moved its edges so that every
  // frame came out 0.32-0.34 px narrow, valid at σ 0.085. A second pass through x264 moves it by
  // 0.15-0.38 px: that doubt makes the frames imprecise, not confidently wrong. (Of the luma as
  // stored, x264's own output, a second pass moved it 0.03-0.05 px: it goes in stretched.)
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kBend, 109);
  p.noise_sigma *= 0.3;
  ASSERT_EQ(p.codec, Codec::kH264);
  ExpectMatrixFramesWithinTheirSigma(p);
}

TEST(AdversarialTest, AColourCamerasFlatStrandIsNotTakenForALitOne) {
  // A flat dark strand (119 on 201) through a Bayer mosaic, bilinear demosaicing and H.264, blur
  // 0.7, with a third of its noise (matrix seed 21): the demosaiced luma's edge, whose shape
  // changes with the mosaic's phase along the tilted edge, looked shaded on its left side, and
  // the shaded step put it 0.2-0.5 px outward: three frames valid at σ 0.10-0.13, one of them
  // 3.6σ off. Shading is taken only where most calipers show it, beyond what a step through a
  // symmetric PSF of any peakedness describes.
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kBayer, 21);
  p.noise_sigma *= 0.3;
  ASSERT_EQ(p.codec, Codec::kH264);
  ExpectMatrixFramesWithinTheirSigma(p);
}

TEST(AdversarialTest, AWidthX264LeftInPlaceStaysValid) {
  // A plain strand through x264 (matrix seed 3), measured within 0.03 px in every frame: a
  // second pass moves it by hardly more than its noise, and the frames stay valid and right.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kPlain, 3);
  ASSERT_EQ(p.codec, Codec::kH264);
  ExpectMatrixFramesValidAndRight(p);
}

TEST(AdversarialTest, AStripeCloseInsideADarkStrandIsFittedWithTheEdge) {
  // A dark 62 px strand (42 on 146) with a stripe 88 levels brighter whose near edge lies 3.4 px
  // inside its right silhouette, blur 1.1, through H.264: a window stopping short of the stripe
  // held too little of the edge, and no caliper fitted both edges (`occluded`). The window now
  // reaches onto the stripe and the edge is fitted with the stripe's step: every frame gives a
  // width (valid in the matrix but one, `imprecise` by the codec's doubt, 0.10 px).
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 114);
  ExpectMatrixFramesWithinTheirSigma(p);
}

TEST(AdversarialTest, ANarrowStripeInsideADarkStrandIsFittedWithBothItsSides) {
  // A dark 33 px strand (134 on 182, blur 2.2, noise 3) with a stripe 60 levels brighter, 6 px
  // wide, its near side 7.4 px inside the left silhouette (matrix seed 7 with the stripe below
  // the clip and less noise): the profile's noise was read off its differences, which inside so
  // narrow an object all cross the stripe's sides, so the stripe was not seen as an inner edge and
  // the window ran onto it: without noise the width came out a px narrow at a σ of 0.15 px (7σ
  // off). The stripe is now found, its far side too, and fitted as a box of the edge's blur: the
  // widths are right within their σ (0.10–0.27 px: mostly `imprecise` still).
  AdversarialScene p = RandomAdversarialScene(TroubleClass::kSpecularStripe, 7);
  p.stripe_gain = 60;
  p.noise_sigma = 3;
  AdversarialTruth t;
  for (const vision::StrandMeasurement& m : MeasuredMatrixFrames(p, &t)) {
    ASSERT_TRUE(m.gave_width()) << m.detail << ": " << Describe(p);
    EXPECT_LE(std::abs(m.width_px - t.width_px), 3 * m.width_sigma_px)
        << m.width_px << " ± " << m.width_sigma_px << " px, truth " << t.width_px;
    EXPECT_LE(std::abs(m.width_px - t.width_px), WrongTolerancePx(t.width_px));
  }
}

TEST(AdversarialTest, ANoisyStraightStrandIsNotTakenForADiscOrBend) {
  // A straight 60 px strand, noise 11 grey levels on a contrast of 68, blur 2.2: its calipers'
  // widths scatter by about half a px, and a quadratic through 7 of them bent by a px or two over
  // the band, which once refused frames 0 and 2 as "the edges curve (a disc or bend)". A bend
  // counts only beyond 3σ of the widths' own scatter: every frame gives a width, which its σ
  // covers (valid or imprecise; the noise leaves 0.2-0.5 px) within 3σ; frame 3 within 4σ: its
  // six calipers of eight (one more was lost when the tip was read 0.01 px higher, and with it
  // the two-slope doubt) all but one lie below the truth, 0.59 px at σ 0.17.
  const AdversarialScene p = RandomAdversarialScene(TroubleClass::kPlain, 22);
  AdversarialTruth t;
  const std::vector<vision::StrandMeasurement> measured = MeasuredMatrixFrames(p, &t);
  for (size_t i = 0; i < measured.size(); ++i) {
    const vision::StrandMeasurement& m = measured[i];
    ASSERT_TRUE(vision::GivesWidth(m.status))
        << "frame " << i << ": " << vision::FrameStatusName(m.status) << " " << m.detail;
    EXPECT_LE(std::abs(m.width_px - t.width_px), (i == 3 ? 4.0 : 3.0) * m.width_sigma_px)
        << "frame " << i << ": " << m.width_px << " ± " << m.width_sigma_px << " px, truth "
        << t.width_px;
  }
}

}  // namespace
}  // namespace clogscope::synthetic
