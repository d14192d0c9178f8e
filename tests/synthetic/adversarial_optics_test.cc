#include "synthetic/adversarial_optics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace clogscope::synthetic {
namespace {

// A hi-res layer with what the renderer's have: hard edges (a tilted bar), smooth shading and
// sample noise, in grey levels.
cv::Mat Layer(int rows, int cols) {
  cv::Mat m(rows, cols, CV_32F);
  cv::randu(m, 0, 40);
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x) {
      const double u = x - 0.45 * cols + 0.3 * y;
      if (std::abs(u) < 0.12 * cols) m.at<float>(y, x) += 200 - 0.2 * std::abs(u);
    }
  return m;
}

double MaxAbsDiff(const cv::Mat& a, const cv::Mat& b) {
  EXPECT_EQ(a.size(), b.size());
  return cv::norm(a, b, cv::NORM_INF);
}

// The reference: OpenCV blurring every sample, then averaging each F × F block.
cv::Mat Reference(const cv::Mat& hires, int F, double sigma) {
  cv::Mat blurred, out;
  cv::GaussianBlur(hires, blurred, cv::Size(), sigma);
  cv::resize(blurred, out, cv::Size(hires.cols / F, hires.rows / F), 0, 0, cv::INTER_AREA);
  return out;
}

TEST(BlurAndBinTest, SameAsOpenCvsBlurThenAreaResize) {
  const cv::Mat hires = Layer(3 * 60, 3 * 80);
  // Narrow to wide blurs: the widest reaches past the layer's edges (reflected border).
  for (const double sigma : {1.5, 4.0, 9.0, 21.0}) {
    const cv::Mat ours = BlurAndBin(hires, 3, sigma);
    EXPECT_LT(MaxAbsDiff(ours, Reference(hires, 3, sigma)), 1e-3) << "sigma " << sigma;
  }
  // Another oversampling, and an image smaller than the kernel along one axis.
  const cv::Mat thin = Layer(2 * 20, 2 * 90);
  EXPECT_LT(MaxAbsDiff(BlurAndBin(thin, 2, 12.0), Reference(thin, 2, 12.0)), 1e-3);
}

TEST(BlurAndBinTest, BlurGrowingDownTheFrameBlendsTheTwoBlursRowByRow) {
  const int F = 3;
  const cv::Mat hires = Layer(F * 70, F * 50);
  std::vector<float> w(hires.rows);
  for (int y = 0; y < hires.rows; ++y) w[y] = std::clamp((y - 40.0f) / 120.0f, 0.0f, 1.0f);
  cv::Mat a, b;
  cv::GaussianBlur(hires, a, cv::Size(), 3.0);
  cv::GaussianBlur(hires, b, cv::Size(), 11.0);
  for (int y = 0; y < hires.rows; ++y) {
    cv::Mat row = a.row(y);
    cv::addWeighted(row, 1 - w[y], b.row(y), w[y], 0, row);
  }
  cv::Mat reference;
  cv::resize(a, reference, cv::Size(hires.cols / F, hires.rows / F), 0, 0, cv::INTER_AREA);
  EXPECT_LT(MaxAbsDiff(BlurAndBin(hires, F, 3.0, 11.0, w), reference), 1e-3);
}

}  // namespace
}  // namespace clogscope::synthetic
