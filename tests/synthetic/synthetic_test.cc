#include "synthetic/synthetic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/scratch_dir.h"
#include "vision/io/frame_source.h"

namespace clogscope::synthetic {
namespace {

namespace fs = std::filesystem;

// The ground truth is right if the rendered strand holds exactly the truth's area: in any row away
// from the nozzle, the summed coverage (I - background)/(strand - background) equals the width
// along the row, w / cos(angle), and its centroid lies on the axis. 16-bit output without noise
// makes quantisation negligible (< 1e-5 px per row).
void ExpectRowsHoldTheTruth(SceneParams p) {
  p.noise_sigma = 0;
  p.bit_depth = 16;
  FrameTruth truth;
  const cv::Mat img = RenderFrame(p, 0, &truth);
  const double th = truth.angle_deg * M_PI / 180;
  for (int dy : {100, 200, 300}) {
    const int y = static_cast<int>(p.tip_y_px) + dy;
    double sum = 0, moment = 0;
    for (int x = 0; x < img.cols; ++x) {
      const double cov = (img.at<uint16_t>(y, x) / 257.0 - p.background_level) /
                         (p.strand_level - p.background_level);
      sum += cov;
      moment += cov * x;
    }
    const double expected_x = p.tip_x_px + (y - p.tip_y_px) * std::tan(th);
    EXPECT_NEAR(sum, truth.width_px / std::cos(th), 0.002)
        << "row " << y << " tilt " << truth.angle_deg << " blur " << p.blur_sigma_px;
    EXPECT_NEAR(moment / sum, expected_x, 0.002) << "row " << y;
  }
}

TEST(SyntheticTest, EdgesHoldTheTruthExactly) {
  for (double tilt : {0.0, 7.5, -20.0}) {
    for (double blur : {0.0, 1.5, 3.0}) {
      SceneParams p;
      p.tilt_deg = tilt;
      p.blur_sigma_px = blur;
      ExpectRowsHoldTheTruth(p);
    }
  }
  SceneParams odd;
  odd.strand_width_um = 347.3;
  odd.scale_um_per_px = 2.87;
  odd.tip_x_px = 611.37;
  ExpectRowsHoldTheTruth(odd);
}

// A noiseless 10 µm stage micrometer (2 µm lines, 40 µm short ticks) at 0.5 µm/px, 360 px tall,
// as a silhouette.
SceneParams NoiselessMicrometer(int width_px, double tip_x_px, double tip_y_px) {
  SceneParams p;
  p.target = RenderTarget::kMicrometer;
  p.width_px = width_px;
  p.height_px = 360;
  p.tip_x_px = tip_x_px;
  p.tip_y_px = tip_y_px;
  p.scale_um_per_px = 0.5;
  p.pitch_um = 10;
  p.line_width_um = 2;
  p.tick_length_um = 40;
  p.noise_sigma = 0;
  p.SetSilhouette();
  return p;
}

// A stage micrometer's ticks: each holds exactly its line's area at its lattice position, and the
// ticks are as long as asked (short 40 µm, every 5th 60 µm, every 10th 80 µm).
TEST(SyntheticTest, MicrometerTicksHoldTheLattice) {
  SceneParams p = NoiselessMicrometer(640, 320.3, 180);
  p.tilt_deg = 3;
  p.bit_depth = 16;
  const cv::Mat img = RenderFrame(p, 0, nullptr);
  const double th = p.tilt_deg * M_PI / 180, pitch = 20, w = 4, tick = 80;
  // Coverage summed across tick k on the row where the tick's centre line is at s (px below the
  // tip point, along the lines), and its centroid's offset from the lattice position on that row.
  auto across = [&](int k, double s, double* offset) {
    const int y =
        static_cast<int>(std::lround(p.tip_y_px - k * pitch * std::sin(th) + s * std::cos(th)));
    const double xc = p.tip_x_px + (k * pitch + (y - p.tip_y_px) * std::sin(th)) / std::cos(th);
    double sum = 0, moment = 0;
    for (int x = static_cast<int>(xc - 0.5 * pitch); x <= static_cast<int>(xc + 0.5 * pitch); ++x) {
      const double cov = (p.background_level - img.at<uint16_t>(y, x) / 257.0) /
                         (p.background_level - p.strand_level);
      sum += cov;
      moment += cov * x;
    }
    if (offset) *offset = sum > 0 ? moment / sum - xc : 0;
    return sum;
  };
  for (int k : {-10, 1, 5, 10}) {
    double offset = 0;
    EXPECT_NEAR(across(k, 0.5 * tick, &offset), w / std::cos(th), 0.002) << "tick " << k;
    EXPECT_NEAR(offset, 0, 0.002) << "tick " << k;
  }
  EXPECT_NEAR(across(1, -0.25 * tick, nullptr), 0, 0.001);  // above the short ticks
  EXPECT_NEAR(across(5, -0.25 * tick, nullptr), w / std::cos(th), 0.002);
  EXPECT_NEAR(across(5, -0.75 * tick, nullptr), 0, 0.001);  // above the medium ones
  EXPECT_NEAR(across(10, -0.75 * tick, nullptr), w / std::cos(th), 0.002);
  EXPECT_NEAR(across(10, 1.25 * tick, nullptr), 0, 0.001);  // below the common end
}

TEST(SyntheticTest, MicrometerNumeralsDustAndTwelveBitData) {
  SceneParams p = NoiselessMicrometer(480, 240, 220);
  const cv::Mat plain = RenderFrame(p, 0, nullptr);
  p.numerals = true;
  const cv::Mat numbered = RenderFrame(p, 0, nullptr);
  // Numerals half a short tick tall (40 px), a quarter tick (20 px) above the long ticks' tops
  // (80 px above the tip point), and nothing else changes.
  cv::Mat diff;
  cv::absdiff(plain, numbered, diff);
  const cv::Rect changed = cv::boundingRect(diff > 20);
  EXPECT_GT(changed.area(), 0);
  EXPECT_GE(changed.y, 220 - 140 - 4);
  EXPECT_LE(changed.y + changed.height, 220 - 100 + 4);
  p.dust_specks = 10;
  p.dust_fibres = 2;
  const cv::Mat dusty = RenderFrame(p, 0, nullptr);
  EXPECT_GT(cv::countNonZero(cv::abs(dusty - numbered) > 50), 50);
  EXPECT_EQ(cv::norm(dusty, RenderFrame(p, 0, nullptr), cv::NORM_INF), 0.0);  // same seed
  // 16-bit frames of 12-bit data: 0..4095, levels scaled to it.
  p.bit_depth = 16;
  p.data_bits = 12;
  const cv::Mat twelve = RenderFrame(p, 0, nullptr);
  double lo = 0, hi = 0;
  cv::minMaxLoc(twelve, &lo, &hi);
  EXPECT_NEAR(hi, 215 * 4095 / 255.0, 1);
  EXPECT_NEAR(lo, 55 * 4095 / 255.0, 40);
  std::string why;
  p.bit_depth = 8;
  EXPECT_FALSE(p.Validate(&why));
  EXPECT_NE(why.find("data_bits"), std::string::npos);
  p.bit_depth = 16;
  p.tick_length_um = 0;
  EXPECT_FALSE(p.Validate(&why));
  EXPECT_NE(why.find("numerals need tick_length_um"), std::string::npos);
  SceneParams strand;
  strand.dust_specks = 3;
  EXPECT_FALSE(strand.Validate(&why));
  EXPECT_NE(why.find("micrometer"), std::string::npos);
}

// A 320x240 scene with a 150 µm strand: fast to render.
SceneParams SmallScene() {
  SceneParams p;
  p.width_px = 320;
  p.height_px = 240;
  p.tip_x_px = 160;
  p.tip_y_px = 60;
  p.strand_width_um = 150;
  p.nozzle_tip_width_um = 400;
  return p;
}

TEST(SyntheticTest, SameSeedSameFrame) {
  SceneParams p = SmallScene();
  p.width_jitter_um = 2;
  p.sway_deg = 1;
  FrameTruth a, b, c;
  const cv::Mat i1 = RenderFrame(p, 3, &a), i2 = RenderFrame(p, 3, &b), i3 = RenderFrame(p, 4, &c);
  EXPECT_EQ(cv::norm(i1, i2, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(i1, i3, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.width_um, b.width_um);
  EXPECT_NE(a.width_um, c.width_um);
  EXPECT_EQ(FrameTruthFor(p, 4).width_um, c.width_um);
  // Jitter and sway have the requested spread.
  double s1 = 0, s2 = 0, a1 = 0, a2 = 0;
  const int n = 2000;
  for (int i = 0; i < n; ++i) {
    const FrameTruth t = FrameTruthFor(p, i);
    s1 += t.width_um - p.strand_width_um;
    s2 += std::pow(t.width_um - p.strand_width_um, 2);
    a1 += t.angle_deg;
    a2 += t.angle_deg * t.angle_deg;
  }
  EXPECT_NEAR(std::sqrt(s2 / n - std::pow(s1 / n, 2)), 2.0, 0.1);
  EXPECT_NEAR(std::sqrt(a2 / n - std::pow(a1 / n, 2)), 1.0, 0.05);
}

TEST(SyntheticTest, OutputKinds) {
  SceneParams p = SmallScene();
  EXPECT_EQ(RenderFrame(p, 0, nullptr).type(), CV_8UC1);
  p.colour = true;
  EXPECT_EQ(RenderFrame(p, 0, nullptr).type(), CV_8UC3);
  p.colour = false;
  p.bit_depth = 16;
  EXPECT_EQ(RenderFrame(p, 0, nullptr).type(), CV_16UC1);
}

TEST(SyntheticTest, ValidateNamesTheProblem) {
  std::string why;
  SceneParams p;
  EXPECT_TRUE(p.Validate(&why));
  p.scale_um_per_px = -1;
  EXPECT_FALSE(p.Validate(&why));
  EXPECT_NE(why.find("scale"), std::string::npos);
  p = SceneParams();
  p.nozzle_tip_width_um = 300;
  EXPECT_FALSE(p.Validate(&why));
  p = SceneParams();
  p.bit_depth = 12;
  EXPECT_FALSE(p.Validate(&why));
  EXPECT_THROW(RenderFrame(p, 0, nullptr), std::invalid_argument);
}

TEST(SyntheticTest, SequencesAsPngAviAndMp4WithTruth) {
  const testutil::ScratchDir scratch("clogscope_synthetic_seq");
  const fs::path& dir = scratch.path();
  SceneParams p = SmallScene();
  p.width_jitter_um = 1;
  for (const char* out : {"png", "v.avi", "v.mp4"}) {
    const std::string out_path = (dir / out).string();
    const std::string truth_path = out_path + ".json";
    const auto truth = RenderSequence(p, 6, 25.0, out_path, truth_path);
    ASSERT_EQ(truth.size(), 6u);
    std::ifstream in(truth_path);
    const auto j = nlohmann::json::parse(in);
    ASSERT_EQ(j["frames"].size(), 6u);
    EXPECT_DOUBLE_EQ(j["frames"][2]["width_um"].get<double>(), truth[2].width_um);
    EXPECT_DOUBLE_EQ(j["scene"]["scale_um_per_px"].get<double>(), 3.0);
    auto src = vision::FrameSource::Open(out_path);
    int n = 0;
    vision::InputFrame f;
    while (src->Next(&f)) {
      ASSERT_FALSE(f.image.empty()) << out;
      EXPECT_EQ(f.image.cols, 320);
      EXPECT_EQ(f.index, n);
      ++n;
    }
    EXPECT_EQ(n, 6) << out;
  }
  EXPECT_THROW(RenderSequence(p, 0, 25.0, (dir / "x").string(), ""), std::invalid_argument);
  p.bit_depth = 16;
  EXPECT_THROW(RenderSequence(p, 2, 25.0, (dir / "x.mp4").string(), ""), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::synthetic
