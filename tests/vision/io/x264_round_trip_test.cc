#include "vision/io/x264_round_trip.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "tests/vision/x264_test_settings.h"

namespace clogscope::vision {
namespace {

// A dark bar on a bright field, with noise: what a strand's frame holds.
cv::Mat NoisyBar() {
  cv::Mat img(96, 128, CV_8U, cv::Scalar(190));
  img.colRange(50, 80).setTo(30);
  cv::Mat noise(img.size(), CV_16S);
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::NORMAL, 0, 4);
  cv::Mat out;
  img.convertTo(out, CV_16S);
  out += noise;
  out.convertTo(out, CV_8U);
  return out;
}

double MeanAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  return cv::norm(a, b, cv::NORM_L1) / a.total() / a.channels();
}

TEST(X264RoundTripTest, LosslessX264GivesTheImageBackToTheBit) {
  // x264 at CRF 0 is lossless: whatever comes back different was the round trip's own doing.
  const cv::Mat img = NoisyBar();
  const cv::Mat back = X264RoundTrip(X264AtCrf(0)).Apply(img);
  ASSERT_EQ(back.type(), CV_8U);
  ASSERT_EQ(back.size(), img.size());
  EXPECT_EQ(cv::norm(img, back, cv::NORM_INF), 0);
}

TEST(X264RoundTripTest, TheStreamsRateFactorIsTheOneUsed) {
  // Coarser quantisation loses more: the noise of a CRF 40 pass is not that of CRF 10. (A setting
  // the encoder ignored would give the same image at both.)
  const cv::Mat img = NoisyBar();
  const double fine = MeanAbsDiff(img, X264RoundTrip(X264AtCrf(10)).Apply(img));
  const double coarse = MeanAbsDiff(img, X264RoundTrip(X264AtCrf(40)).Apply(img));
  EXPECT_LT(fine, 1.5);    // grey levels: CRF 10 keeps 4-level noise nearly as it was
  EXPECT_GT(coarse, 2.0);  // CRF 40 smooths most of it away
}

TEST(X264RoundTripTest, ColourComesBackInItsOwnColours) {
  // Flat 32-px patches survive 4:2:0 and BT.601 within a few levels at a fine rate factor.
  cv::Mat img(64, 96, CV_8UC3);
  const cv::Vec3b colours[] = {{20, 120, 230},  {200, 60, 40}, {90, 200, 90},
                               {240, 240, 240}, {10, 10, 10},  {128, 30, 180}};
  for (int i = 0; i < 6; ++i)
    img(cv::Rect(32 * (i % 3), 32 * (i / 3), 32, 32)).setTo(cv::Scalar(colours[i]));
  const cv::Mat back = X264RoundTrip(X264AtCrf(10)).Apply(img);
  ASSERT_EQ(back.type(), CV_8UC3);
  for (int i = 0; i < 6; ++i) {
    const cv::Scalar mean = cv::mean(back(cv::Rect(32 * (i % 3) + 8, 32 * (i / 3) + 8, 16, 16)));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], colours[i][c], 4.0) << "patch " << i;
  }
}

TEST(X264RoundTripTest, RefusesWhat420CannotHold) {
  X264RoundTrip rt(X264AtCrf(23));
  EXPECT_THROW(rt.Apply(cv::Mat(31, 32, CV_8U, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(rt.Apply(cv::Mat(32, 32, CV_16U, cv::Scalar(0))), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::vision
