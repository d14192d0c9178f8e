#include "apps/inspect_command.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "pipeline/band.h"
#include "synthetic/synthetic.h"
#include "tests/apps/cli_test_util.h"
#include "vision/io/video_io.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

std::string Render(const fs::path& dir, const std::string& name, const synthetic::SceneParams& p) {
  const std::string path = (dir / name).string();
  vision::WriteImageAtomically(path, synthetic::RenderFrame(p, 0, nullptr));
  return path;
}

// --out names a PNG: a name without the extension (or with another) is refused, not written as
// a PNG under a name nothing will open it by.
TEST(InspectCommandTest, OutMustBeAPngName) {
  InspectCommandOptions o;
  // An input that exists: the input's own check (common/path_check.h) comes after --out's.
  const fs::path d = testing::FreshDir("clogscope_inspect_out");
  o.input = (d / "frame.png").string();
  std::ofstream(o.input) << "x";
  for (const std::string name : {"inspect", "dir/inspect.jpg", "x.png.partial"}) {
    o.out_png = name;
    std::string why;
    EXPECT_FALSE(o.Validate(&why)) << name;
    EXPECT_NE(why.find("--out " + name + ": "), std::string::npos) << why;
    EXPECT_NE(why.find(".png"), std::string::npos) << why;
  }
  for (const std::string name : {"inspect.png", "dir/Inspect.PNG"}) {
    o.out_png = name;
    std::string why;
    EXPECT_TRUE(o.Validate(&why)) << name << ": " << why;
  }
}

TEST(InspectCommandTest, ExplainsTheFrameAndSuggestsOptions) {
  const fs::path d = testing::FreshDir("clogscope_inspect");
  synthetic::SceneParams p;
  p.nozzle_level = 30;  // darker than the background
  p.clutter_discs = 2;
  InspectCommandOptions o;
  o.input = Render(d, "strand.png", p);
  o.out_png = (d / "inspect.png").string();
  const InspectReport r = InspectInput(o);
  ASSERT_TRUE(r.measurement.valid()) << r.text;
  EXPECT_EQ(r.target, vision::MeasureTarget::kStrand);
  EXPECT_NE(r.text.find("chosen"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("--target strand"), std::string::npos) << r.text;
  EXPECT_NE(r.text.find("polarity: bright"), std::string::npos) << r.text;
  // The suggested ROI holds the tip and the band.
  EXPECT_TRUE(r.suggested_roi.contains(cv::Point(640, 245))) << r.text;
  EXPECT_TRUE(r.suggested_roi.contains(cv::Point(640, 300))) << r.text;
  std::string why;
  const cv::Mat png = vision::ReadImage(o.out_png, &why);
  EXPECT_EQ(png.cols, 1280) << why;

  // No tip in view: the filament target is suggested.
  p = synthetic::SceneParams();
  p.nozzle = false;
  o.input = Render(d, "filament.png", p);
  const InspectReport f = InspectInput(o);
  EXPECT_EQ(f.target, vision::MeasureTarget::kFilament) << f.text;
  EXPECT_TRUE(f.measurement.valid()) << f.text;
  EXPECT_NE(f.text.find("target: filament"), std::string::npos);
  // Asked for a filament, it measures what measure would: the whole stretch.
  InspectCommandOptions asked = o;
  asked.strand.target = vision::MeasureTarget::kFilament;
  asked.target_given = true;
  const InspectReport fa = InspectInput(asked);
  ASSERT_TRUE(fa.measurement.valid()) << fa.text;
  vision::StrandMeasureOptions mo;
  mo.target = vision::MeasureTarget::kFilament;
  pipeline::ApplyBandPx({}, std::nullopt, &mo);  // measure's band without a scale (pipeline/band.h)
  const vision::StrandMeasurement direct =
      vision::MeasureStrand(vision::ReadImage(o.input, &why), mo);
  EXPECT_EQ(fa.measurement.calipers_total, direct.calipers_total);
  EXPECT_DOUBLE_EQ(fa.measurement.width_px, direct.width_px);
  EXPECT_GT(fa.measurement.calipers_total, 100);  // 720 px of stretch, not the strand's 50 px band

  // Nothing to see: the reason, and no ROI.
  p.strand = false;
  o.input = Render(d, "empty.png", p);
  const InspectReport e = InspectInput(o);
  EXPECT_EQ(e.measurement.status, vision::FrameStatus::kNoStrand);  // the README's no_strand
  EXPECT_TRUE(e.suggested_roi.empty());
  EXPECT_NE(e.text.find("no_strand"), std::string::npos) << e.text;

  o.frame = 3;  // an image has one frame
  EXPECT_THROW(InspectInput(o), std::invalid_argument);
}

}  // namespace
}  // namespace clogscope::apps
