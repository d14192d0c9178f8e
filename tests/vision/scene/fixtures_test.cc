// Measures the committed fixture frames (testdata/README.md says how they were rendered) against
// their committed truth: guards the detector against changes in the renderer or the measurement.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "vision/io/frame_source.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {
namespace {

namespace fs = std::filesystem;
const fs::path kData = CLOGSCOPE_TESTDATA_DIR;

// Each frame within frame_tol_px of its truth, and the mean error within mean_tol_px.
void CheckAgainstTruth(const std::string& input, const std::string& truth_file, double mean_tol_px,
                       double frame_tol_px, double tol_deg) {
  std::ifstream in(kData / truth_file);
  ASSERT_TRUE(in) << truth_file;
  const auto truth = nlohmann::json::parse(in);
  const double scale = truth["scene"]["scale_um_per_px"].get<double>();
  StrandMeasureOptions opt;
  opt.band_start_px = 50.0 / scale;
  opt.band_height_px = 150.0 / scale;
  auto src = FrameSource::Open((kData / input).string());
  InputFrame f;
  int n = 0;
  double sum = 0;
  while (src->Next(&f)) {
    const StrandMeasurement m = MeasureStrand(f.image, opt);
    const auto& t = truth["frames"][f.index];
    ASSERT_TRUE(m.valid()) << input << " frame " << f.index << ": " << m.detail;
    const double e = m.width_px - t["width_px"].get<double>();
    EXPECT_LE(std::abs(e), frame_tol_px) << input << " frame " << f.index;
    EXPECT_NEAR(m.angle_deg, t["angle_deg"].get<double>(), tol_deg)
        << input << " frame " << f.index;
    sum += e;
    ++n;
  }
  EXPECT_EQ(n, static_cast<int>(truth["frames"].size()));
  EXPECT_LE(std::abs(sum / n), mean_tol_px) << input;
}

TEST(FixturesTest, BrightTilted) {
  CheckAgainstTruth("frames/bright_tilt5.png", "frames/bright_tilt5.json", 0.05, 0.05, 0.1);
}
TEST(FixturesTest, SilhouetteHighlightGradient) {
  CheckAgainstTruth("frames/silhouette_tilt-12.png", "frames/silhouette_tilt-12.json", 0.1, 0.1,
                    0.2);
}
TEST(FixturesTest, ColourWithBed) {
  CheckAgainstTruth("frames/colour_bed.png", "frames/colour_bed.json", 0.1, 0.1, 0.2);
}
TEST(FixturesTest, H264WithJitterAndSway) {
  // The bound for H.264 is on the mean error (0.15 px). A moving strand's compression
  // artefacts differ frame to frame (std ~0.08 px here), so single frames get a 5-sigma bound, and
  // the 50 px band's edge slope moves by up to ~0.3°.
  CheckAgainstTruth("video/jitter_sway.mp4", "video/jitter_sway.truth.json", 0.15, 0.4, 0.5);
}

}  // namespace
}  // namespace clogscope::vision
