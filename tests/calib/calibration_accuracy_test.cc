// Calibration from rendered targets of known scale, end to end through the vision module: the
// accuracy targets of the calibration issue, and (label `slow`) σ_s against the spread of s.
#include <gtest/gtest.h>

#include <cmath>

#include "calib/pixel_scale.h"
#include "synthetic/synthetic.h"
#include "vision/scene/micrometer.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::calib {
namespace {

using synthetic::SceneParams;

constexpr double kScale = 3.0, kBias = 0.35;

SceneParams PinScene(double diameter_um, uint64_t seed, int width = 1280, int height = 720) {
  SceneParams p;
  p.target = synthetic::RenderTarget::kPin;
  p.width_px = width;
  p.height_px = height;
  p.tip_x_px = width / 2.0;
  p.tip_y_px = height / 2.0;
  p.strand_width_um = diameter_um;
  p.scale_um_per_px = kScale;
  p.edge_bias_px = kBias;
  p.tilt_deg = 2.5;
  p.seed = seed;
  p.SetSilhouette();
  return p;
}

ScaleCalibration CalibrateFromRenderedPins(uint64_t seed, int width = 1280, int height = 720) {
  vision::StrandMeasureOptions mo;
  mo.target = vision::MeasureTarget::kFilament;
  mo.band_start_px = 8;
  mo.band_height_px = 1e6;
  std::vector<PinObservation> pins;
  for (double d : {300.0, 350.0, 400.0, 450.0, 500.0}) {
    const cv::Mat img = synthetic::RenderFrame(
        PinScene(d, seed + static_cast<uint64_t>(d), width, height), 0, nullptr);
    const auto m = vision::MeasureStrand(img, mo);
    EXPECT_TRUE(m.valid()) << m.detail;
    pins.push_back({"pin", d, 0, m.width_px, m.width_sigma_px});
  }
  return FitPinScale(pins, {});
}

TEST(CalibrationAccuracyTest, FivePinsWithinFiveHundredthsOfAPercent) {
  const ScaleCalibration c = CalibrateFromRenderedPins(1);
  ASSERT_TRUE(c.usable) << c.message;
  EXPECT_LE(std::abs(c.scale_um_per_px / kScale - 1), 0.0005);
  EXPECT_NEAR(c.edge_bias_px, kBias, 0.05);
}

TEST(CalibrationAccuracyTest, MicrometerWithinTwoHundredthsOfAPercent) {
  SceneParams p;
  p.target = synthetic::RenderTarget::kMicrometer;
  p.pitch_um = 100;
  p.line_width_um = 8;
  p.tilt_deg = -3;
  p.scale_um_per_px = kScale;
  p.SetSilhouette();
  const cv::Mat img = synthetic::RenderFrame(p, 0, nullptr);
  const auto found = vision::FindMicrometerLines(img, {});
  ASSERT_TRUE(found.ok) << found.reason;
  ASSERT_GE(found.lines.size(), 30u);
  EXPECT_NEAR(found.angle_deg, -3, 0.05);
  std::vector<double> pos, sig;
  for (const auto& l : found.lines) {
    pos.push_back(l.position_px);
    sig.push_back(l.sigma_px);
  }
  const ScaleCalibration c = FitMicrometerScale(IndexLines(pos, sig), 100, {});
  ASSERT_TRUE(c.usable) << c.message;
  EXPECT_LE(std::abs(c.scale_um_per_px / kScale - 1), 0.0002);
}

// σ_s must describe the scatter of s over repeated noisy renders (within a factor 1.5).
TEST(CalibrationAccuracyTest, SigmaMatchesMonteCarloSpread) {
  const int n = 24;
  double s1 = 0, s2 = 0, sig = 0;
  for (int i = 0; i < n; ++i) {
    const ScaleCalibration c = CalibrateFromRenderedPins(1000 + 17 * i, 640, 360);
    ASSERT_TRUE(c.usable);
    s1 += c.scale_um_per_px;
    s2 += c.scale_um_per_px * c.scale_um_per_px;
    sig += c.scale_sigma_um_per_px;
  }
  const double sd = std::sqrt(std::max(0.0, s2 / n - (s1 / n) * (s1 / n)));
  const double ratio = (sig / n) / sd;
  RecordProperty("sigma_over_spread", std::to_string(ratio));
  EXPECT_GT(ratio, 1 / 1.5) << "mean sigma " << sig / n << " spread " << sd;
  EXPECT_LT(ratio, 1.5) << "mean sigma " << sig / n << " spread " << sd;
}

}  // namespace
}  // namespace clogscope::calib
