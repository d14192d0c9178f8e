#include "vision/synthetic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "vision/frame_source.h"

namespace clogscope::vision {
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
  const fs::path dir = fs::temp_directory_path() / "clogscope_synthetic_seq";
  fs::remove_all(dir);
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
    auto src = FrameSource::Open(out_path);
    int n = 0;
    InputFrame f;
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
}  // namespace clogscope::vision
