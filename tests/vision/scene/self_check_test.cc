// The self-checks on drawn profiles: vertical objects whose levels across x are given, blurred as
// a lens does, against the geometry they were drawn with.
#include "vision/scene/self_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

namespace clogscope::vision {
namespace {

constexpr int kWidthPx = 400, kHeightPx = 160;
constexpr double kCentreX = 200, kBlurPx = 2.0, kMinStep = 15.3;  // 0.06 of 255

// A frame of vertical bands: `background` everywhere, then each (from, to, level) in u = x − 200
// painted over it in turn, blurred by kBlurPx.
cv::Mat DrawBands(double background,
                  const std::vector<std::pair<std::pair<double, double>, double>>& bands) {
  cv::Mat f(kHeightPx, kWidthPx, CV_32F, cv::Scalar(background));
  for (int x = 0; x < kWidthPx; ++x) {
    const double u = x + 0.5 - kCentreX;
    for (const auto& [span, level] : bands)
      if (u >= span.first && u < span.second) f.col(x).setTo(level);
  }
  cv::GaussianBlur(f, f, cv::Size(), kBlurPx);
  cv::Mat out;
  f.convertTo(out, CV_8U);
  return out;
}

// The check on an object between u = left_u and right_u, over rows 20-140.
SelfCheck Check(const cv::Mat& frame, bool object_dark, double left_u = -5, double right_u = 5) {
  const GreyImage img{frame, false};
  const AxisFrame axis{kCentreX, 0, 0, 1};
  return CheckNotOnAWiderObject(img, axis, 20, 140, left_u, right_u, 0, kBlurPx, kMinStep,
                                object_dark);
}

TEST(CheckNotOnAWiderObjectTest, AStripeOnALitStrandLiesOnAWiderObject) {
  // A lit 86 px strand (75 on a background of 20) and its 10 px stripe (210), measured as the
  // object.
  const cv::Mat f = DrawBands(20, {{{-43, 43}, 75}, {{-5, 5}, 210}});
  const SelfCheck check = Check(f, false);
  EXPECT_FALSE(check.passed);
  EXPECT_NE(check.why.find("wider object"), std::string::npos) << check.why;
  // The same stripe with the strand gone: a bright strand on a dark background.
  EXPECT_TRUE(Check(DrawBands(20, {{{-5, 5}, 210}}), false).passed);
}

TEST(CheckNotOnAWiderObjectTest, ABrightStrandBetweenTwoLikeItIsNotOnOne) {
  // Two neighbours of one level, 23 px wide and 15 px from it on both sides: outward from the
  // strand the level steps up to theirs, as from a stripe to its strand's body, but the dark
  // background comes back beyond them.
  const cv::Mat f = DrawBands(20, {{{-43, -20}, 75}, {{20, 43}, 75}, {{-5, 5}, 210}});
  EXPECT_TRUE(Check(f, false).passed) << Check(f, false).why;
}

TEST(CheckNotOnAWiderObjectTest, ADarkStrandOnABacklightRingedByDarkIsNotJudged) {
  // A dark strand on a bright 86 px field (a backlight's disc, a microscope's vignette) with dark
  // beyond: judged as a bright object it would lie on a wider one; as a dark one it does not.
  const cv::Mat f = DrawBands(20, {{{-43, 43}, 200}, {{-5, 5}, 40}});
  EXPECT_TRUE(Check(f, true).passed) << Check(f, true).why;
  EXPECT_FALSE(Check(f, false).passed);
}

TEST(CheckNotOnAWiderObjectTest, AStripeByADarkStrandsRimLiesAtTheSideOfAWiderObject) {
  // A dark strand (64 on a background of 107) from u = -8 to 87, its bright 10 px stripe (180) 3 px
  // inside its left rim, which the blur hides: outside the stripe's left edge lies the
  // background, outside its right edge the strand's body, stepping on to the background 82 px out.
  const cv::Mat f = DrawBands(107, {{{-8, 87}, 64}, {{-5, 5}, 180}});
  const SelfCheck check = Check(f, false);
  EXPECT_FALSE(check.passed);
  EXPECT_NE(check.why.find("side of a wider object"), std::string::npos) << check.why;
  // Without the strand's body: the stripe alone, a bright strand on the background.
  EXPECT_TRUE(Check(DrawBands(107, {{{-5, 5}, 180}}), false).passed);
}

TEST(CheckNotOnAWiderObjectTest, ADarkBlobBesideABrightStrandIsNoBodyAroundAStripe) {
  // A bright 40 px strand (125 on a background of 27) and, against its right edge, a dark blob
  // (1) 25 px wide: outward the level steps up to the background's, which lies just outside the
  // left edge too, but a stripe's body would reach at least as far again as the stripe is wide.
  const SelfCheck check = Check(DrawBands(27, {{{20, 45}, 1}, {{-20, 20}, 125}}), false, -20, 20);
  EXPECT_TRUE(check.passed) << check.why;
  // The same blob reaching 50 px out is the strand's body around a stripe at its rim.
  EXPECT_FALSE(Check(DrawBands(27, {{{20, 70}, 1}, {{-20, 20}, 125}}), false, -20, 20).passed);
}

TEST(CheckNotOnAWiderObjectTest, AWideObjectBesideTheStrandIsNotOneItLiesOn) {
  // A bright strand on a dark background (20), and 25 px beside it a wide object of 75 running
  // to the frame's side: outward from the strand the level steps up to the object's, but the
  // other side's outside is the background, not the object's level.
  const cv::Mat f = DrawBands(20, {{{30, 200}, 75}, {{-5, 5}, 210}});
  EXPECT_TRUE(Check(f, false).passed) << Check(f, false).why;
}

TEST(CheckNotOnAWiderObjectTest, ASlowFallIsNoEdge) {
  // A bright strand whose surroundings fall from 60 to 20 over 60 px on both sides (a lamp's wide
  // glow, a vignette): no edge steps to the farther level.
  cv::Mat f(kHeightPx, kWidthPx, CV_32F);
  for (int x = 0; x < kWidthPx; ++x) {
    const double d = std::abs(x + 0.5 - kCentreX);
    f.col(x).setTo(d < 5 ? 210 : std::max(20.0, 60.0 - 40.0 * (d - 10) / 60.0));
  }
  cv::GaussianBlur(f, f, cv::Size(), kBlurPx);
  cv::Mat frame;
  f.convertTo(frame, CV_8U);
  EXPECT_TRUE(Check(frame, false).passed) << Check(frame, false).why;
}

// CheckInsideIsOneObject on an object drawn between u = -100 and +100, over rows 20-140.
SelfCheck CheckInside(const cv::Mat& frame) {
  const GreyImage img{frame, false};
  const AxisFrame axis{kCentreX, 0, 0, 1};
  return CheckInsideIsOneObject(img, axis, 20, 140, -100, 100, 0, kBlurPx, kMinStep);
}

TEST(CheckInsideIsOneObjectTest, TheBackgroundOverHalfTheWidthIsBetweenTwoObjects) {
  // A bright 80 px strand and a 10 px hair of its level 110 px beside it, paired across both: the
  // background between them is 55 % of the pair's width.
  const cv::Mat f = DrawBands(20, {{{-100, -20}, 120}, {{90, 100}, 120}});
  const SelfCheck check = CheckInside(f);
  EXPECT_FALSE(check.passed);
  EXPECT_NE(check.why.find("two objects"), std::string::npos) << check.why;
}

TEST(CheckInsideIsOneObjectTest, AHairThinnerThanTheInsetBesideTheStrandIsNotOneObject) {
  // A dark 110 px strand and a 4 px hair 86 px beside it, paired across both: the hair lies
  // inside the 8 px the read keeps from the edge, so the read starts on the background between
  // them (43 % of the width), then the strand (stringer 3690: 121 px of 323).
  const cv::Mat f = DrawBands(200, {{{-100, -96}, 60}, {{-10, 100}, 60}});
  const SelfCheck check = CheckInside(f);
  EXPECT_FALSE(check.passed);
  EXPECT_NE(check.why.find("just inside its left edge"), std::string::npos) << check.why;
  // The same from the right; and the strand alone, or a hair half as far, passes.
  EXPECT_FALSE(CheckInside(DrawBands(200, {{{96, 100}, 60}, {{-100, 10}, 60}})).passed);
  EXPECT_TRUE(CheckInside(DrawBands(200, {{{-100, 100}, 60}})).passed);
  EXPECT_TRUE(CheckInside(DrawBands(200, {{{-100, -96}, 60}, {{-80, 100}, 60}})).passed);
}

TEST(CheckInsideIsOneObjectTest, ALenssCoreOverHalfItsWidthIsNotAGap) {
  // A dark backlit lens (60 on a field of 200) whose bright core, at the field's level, covers
  // 55 % of its width in its middle: rims alike on both sides, one object (lens 9114's core
  // covered 51 %).
  const cv::Mat f = DrawBands(200, {{{-100, 100}, 60}, {{-55, 55}, 200}});
  EXPECT_TRUE(CheckInside(f).passed) << CheckInside(f).why;
}

TEST(CheckInsideIsOneObjectTest, AStripeAtTheBackgroundsLevelIsNotAGap) {
  // A bright 200 px strand with a stripe at the background's level over 30 % of its width, in its
  // middle: the body on both sides, one object.
  const cv::Mat f = DrawBands(20, {{{-100, 100}, 120}, {{-30, 30}, 20}});
  EXPECT_TRUE(CheckInside(f).passed) << CheckInside(f).why;
}

}  // namespace
}  // namespace clogscope::vision
