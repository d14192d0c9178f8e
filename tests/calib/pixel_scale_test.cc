#include "calib/pixel_scale.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace clogscope::calib {
namespace {

std::vector<PinObservation> ExactPins(double scale, double bias, double noise_px,
                                      std::mt19937* rng) {
  std::normal_distribution<double> n(0, noise_px);
  std::vector<PinObservation> pins;
  for (double d : {300.0, 350.0, 400.0, 450.0, 500.0}) {
    pins.push_back({"pin" + std::to_string(int(d)), d, 0,
                    d / scale + bias + (noise_px > 0 ? n(*rng) : 0.0), std::max(noise_px, 1e-4)});
  }
  return pins;
}

TEST(PixelScaleTest, PinsRecoverScaleAndBiasExactly) {
  std::mt19937 rng(1);
  const ScaleCalibration c = FitPinScale(ExactPins(2.87, 0.37, 0, &rng), {});
  ASSERT_TRUE(c.usable) << c.message;
  EXPECT_NEAR(c.scale_um_per_px, 2.87, 1e-9);
  EXPECT_NEAR(c.edge_bias_px, 0.37, 1e-8);
  EXPECT_NEAR(c.rms_residual_px, 0, 1e-8);
  EXPECT_EQ(c.targets, 5);
  EXPECT_EQ(c.outliers, 0);
  // The conversion undoes the bias and the scale.
  EXPECT_NEAR(c.ToMicrons(400 / 2.87 + 0.37), 400, 1e-6);
}

TEST(PixelScaleTest, OnePinHoldsBiasAtZeroAndSaysSo) {
  std::mt19937 rng(1);
  auto pins = ExactPins(3.0, 0.0, 0, &rng);
  pins.resize(1);
  const ScaleCalibration c = FitPinScale(pins, {});
  ASSERT_TRUE(c.usable);
  EXPECT_FALSE(c.edge_bias_fitted);
  EXPECT_DOUBLE_EQ(c.edge_bias_px, 0);
  EXPECT_NEAR(c.scale_um_per_px, 3.0, 1e-9);
  EXPECT_NE(c.message.find("one pin"), std::string::npos);
}

TEST(PixelScaleTest, BadPinRowIsAnOutlierAndDoesNotPullTheScale) {
  std::mt19937 rng(2);
  auto pins = ExactPins(3.0, 0.4, 0.003, &rng);
  for (double d : {325.0, 375.0, 425.0}) pins.push_back({"more", d, 0, d / 3.0 + 0.4, 0.003});
  pins[2].width_px += 0.5;  // a dirty pin
  const ScaleCalibration c = FitPinScale(pins, {});
  EXPECT_EQ(c.outliers, 1);
  EXPECT_TRUE(c.residuals[2].outlier);
  EXPECT_NEAR(c.scale_um_per_px, 3.0, 3.0 * 2e-4);  // the Huber loss caps the dirty pin's pull
}

TEST(PixelScaleTest, PinContractViolations) {
  std::mt19937 rng(1);
  EXPECT_THROW(FitPinScale({}, {}), std::invalid_argument);
  auto same = ExactPins(3, 0, 0, &rng);
  for (auto& p : same) p.diameter_um = 400;
  EXPECT_THROW(FitPinScale(same, {}), std::invalid_argument);
  auto zero = ExactPins(3, 0, 0, &rng);
  zero[1].diameter_um = 0;
  EXPECT_THROW(FitPinScale(zero, {}), std::invalid_argument);
}

TEST(PixelScaleTest, MicrometerRecoversScaleAndDistortion) {
  std::vector<LineObservation> lines;
  const double s = 3.1, d2 = 0.004;
  for (int k = 0; k < 35; ++k) {
    const double kk = k - 17.0;
    lines.push_back({0, k, 100.0 + kk * 100.0 / s + d2 * kk * kk, 0.002});
  }
  ScaleFitOptions o;
  // Unmodelled, the (even) distortion leaves the middle scale alone but shows in the residuals.
  EXPECT_GT(FitMicrometerScale(lines, 100, o).rms_residual_px, 0.1);
  o.fit_distortion = true;
  const ScaleCalibration c = FitMicrometerScale(lines, 100, o);
  ASSERT_TRUE(c.usable) << c.message;
  EXPECT_NEAR(c.scale_um_per_px, s, 1e-9);
  EXPECT_NEAR(c.distortion_px, d2, 1e-9);
}

TEST(PixelScaleTest, MicrometerSharesTheScaleAcrossImages) {
  std::vector<LineObservation> lines;
  for (int img = 0; img < 2; ++img) {
    for (int k = 0; k < 10; ++k)
      lines.push_back({img, k, -200.0 + 57.3 * img + (k - 4.5) * 100.0 / 3.0, 0.002});
  }
  const ScaleCalibration c = FitMicrometerScale(lines, 100, {});
  EXPECT_NEAR(c.scale_um_per_px, 3.0, 1e-9);
  EXPECT_NEAR(c.rms_residual_px, 0, 1e-8);
}

TEST(PixelScaleTest, IndexingLinesRefusesIrregularSpacing) {
  const auto idx = IndexLines({0, 33.3, 66.7, 133.3, 166.7}, {});  // one line missing: still fine
  ASSERT_EQ(idx.size(), 5u);
  EXPECT_EQ(idx[3].index, 4);
  EXPECT_THROW(IndexLines({0, 33.3, 50.0, 66.7, 100.0}, {}), std::invalid_argument);
  EXPECT_THROW(FitMicrometerScale({{0, 0, 0, 0.01}, {0, 1, 33, 0.01}}, 100, {}),
               std::invalid_argument);
  EXPECT_THROW(FitMicrometerScale({{0, 0, 0, 0.01}, {0, 1, 33, 0.01}, {0, 2, 66, 0.01}}, -5, {}),
               std::invalid_argument);
}

TEST(PixelScaleTest, MicronsSigmaCarriesTheScaleUncertainty) {
  ScaleCalibration c;
  c.scale_um_per_px = 3;
  c.scale_sigma_um_per_px = 0.003;
  c.edge_bias_px = 0.4;
  c.edge_bias_sigma_px = 0.01;
  const double w = 130.4, sw = 0.01;
  EXPECT_NEAR(c.MicronsSigma(w, sw),
              std::sqrt(std::pow(sw * 3, 2) + std::pow(130 * 0.003, 2) + std::pow(0.03, 2)), 1e-12);
}

}  // namespace
}  // namespace clogscope::calib
