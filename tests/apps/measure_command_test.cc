// End-to-end tests of `clogscope render` and `clogscope measure`: the binary on a small rendered
// video, its exit codes and one-line errors, and the typed MeasureInputs() behind it.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

using testing::RunCli;
using testing::RunResult;

fs::path FreshDir(const std::string& name) { return testing::FreshDir("clogscope_cli_" + name); }

const std::string kSmall = "--size 640x360 --tip-x-px 320 --tip-y-px 100 ";

TEST(MeasureCommandTest, VideoEndToEndAgainstTruth) {
  const fs::path d = FreshDir("e2e");
  ASSERT_EQ(RunCli("render --out " + (d / "v.mp4").string() + " --frames 30 --width-jitter-um 3 " +
                       kSmall + "--tilt-deg 4",
                   d)
                .exit_code,
            0);
  const RunResult r =
      RunCli("measure " + (d / "v.mp4").string() + " --scale-um-per-px 3 --out-frames " +
                 (d / "frames.csv").string() + " --overlay " + (d / "ov").string(),
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "frames.csv").string()), "frames.csv");
  for (const auto& col : FrameCsvColumns()) EXPECT_GE(t.Column(col), 0) << col;
  std::ifstream in(d / "v.truth.json");
  const auto truth = nlohmann::json::parse(in);
  ASSERT_EQ(t.rows.size(), 30u);
  for (const auto& row : t.rows) {
    ASSERT_EQ(row[t.Column("valid")], "1") << row[t.Column("detail")];
    const int frame = std::stoi(row[t.Column("frame")]);
    const double w_um = std::stod(row[t.Column("width_um")]);
    const double truth_um = truth["frames"][frame]["width_um"].get<double>();
    EXPECT_NEAR(w_um, truth_um, 0.15 * 3.0) << "frame " << frame;
    EXPECT_NEAR(std::stod(row[t.Column("width_px")]) * 3.0, w_um, 0.002);
    EXPECT_NEAR(std::stod(row[t.Column("time_s")]), frame / 25.0, 1e-3);
  }
  // Overlays: every 25th video frame by default.
  EXPECT_TRUE(fs::exists(d / "ov" / "v.mp4_000000.png"));
  EXPECT_TRUE(fs::exists(d / "ov" / "v.mp4_000025.png"));
  // Provenance in the header comments.
  const std::string text = ReadFile((d / "frames.csv").string());
  EXPECT_EQ(text.rfind("# clogscope ", 0), 0u);
  EXPECT_NE(text.find("# command "), std::string::npos);
}

TEST(MeasureCommandTest, BadInputsGiveOneLineErrorsAndExitCodes) {
  const fs::path d = FreshDir("bad");
  const std::string out = " --out-frames " + (d / "f.csv").string();
  RunResult r = RunCli("measure " + (d / "nope.mp4").string() + out, d);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nope.mp4: no such file or directory"), std::string::npos) << r.err;

  r = RunCli("measure x.png --scale-um-per-px -3" + out, d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--scale-um-per-px"), std::string::npos) << r.err;

  r = RunCli("measure x.png --roi 1,2,3" + out, d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--roi"), std::string::npos) << r.err;

  r = RunCli("measure x.png --band-start-um 50" + out, d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("--scale-um-per-px"), std::string::npos) << r.err;

  // A frame without a strand: measured, reported in its row, exit 1 as nothing could be measured.
  ASSERT_EQ(RunCli("render --out " + (d / "frames").string() +
                       " --size 640x360 --tip-x-px 320 --tip-y-px=-500",
                   d)
                .exit_code,
            0);
  r = RunCli("measure " + (d / "frames").string() + out, d);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "f.csv").string()), "f.csv");
  ASSERT_EQ(t.rows.size(), 1u);
  EXPECT_EQ(t.rows[0][t.Column("reason")], "no_tip");

  // One good input and one missing: the good one is measured, exit 2.
  ASSERT_EQ(RunCli("render --out " + (d / "good").string() + " " + kSmall, d).exit_code, 0);
  r = RunCli("measure " + (d / "good").string() + " " + (d / "missing").string() + out, d);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("missing: no such file"), std::string::npos);

  // An input whose frames are smaller than the ROI is reported and skipped; the good one is
  // measured and the table written (once the whole run ended with no table at all).
  ASSERT_EQ(RunCli("render --out " + (d / "tiny").string() +
                       " --size 160x120 --tip-x-px 80 --tip-y-px 30 --strand-width-um 60",
                   d)
                .exit_code,
            0);
  r = RunCli("measure " + (d / "good").string() + " " + (d / "tiny").string() +
                 " --roi 100,50,440,300" + out,
             d);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("tiny"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("outside"), std::string::npos) << r.err;
  const CsvTable both = ParseCsv(ReadFile((d / "f.csv").string()), "f.csv");
  ASSERT_EQ(both.rows.size(), 1u);
  EXPECT_EQ(both.rows[0][both.Column("valid")], "1");

  r = RunCli("frobnicate", d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("unknown command"), std::string::npos);
}

TEST(MeasureCommandTest, BandOptionsResolveFromMicronsOrPixels) {
  MeasureCommandOptions o;
  o.inputs = {"x"};
  o.ResolveBand();
  EXPECT_NEAR(o.strand.band_start_px, 50.0 / 3.0, 1e-12);
  EXPECT_NEAR(o.strand.band_height_px, 50.0, 1e-12);
  o.scale_um_per_px = 2.5;
  o.ResolveBand();
  EXPECT_NEAR(o.strand.band_start_px, 20.0, 1e-12);
  EXPECT_NEAR(o.strand.band_height_px, 60.0, 1e-12);
  o.band_height_px = 30;
  o.ResolveBand();
  EXPECT_NEAR(o.strand.band_height_px, 30.0, 1e-12);
  o.band_height_um = 100;
  EXPECT_THROW(o.ResolveBand(), std::invalid_argument);
}

TEST(MeasureCommandTest, TypedFunctionWritesAtomicallyAndSummarises) {
  const fs::path d = FreshDir("typed");
  RenderCommandOptions r;
  r.scene.width_px = 640;
  r.scene.height_px = 360;
  r.scene.tip_x_px = 320;
  r.scene.tip_y_px = 100;
  r.frames = 3;
  r.out = (d / "png").string();
  RenderToFiles(r);
  MeasureCommandOptions o;
  o.inputs = {r.out, (d / "nothing-here").string()};
  o.out_frames = (d / "frames.csv").string();
  const MeasureSummary s = MeasureInputs(o);
  EXPECT_EQ(s.inputs_ok, 1);
  EXPECT_EQ(s.inputs_failed, 1);
  EXPECT_EQ(s.frames, 3);
  EXPECT_EQ(s.valid_frames, 3);
  EXPECT_TRUE(fs::exists(o.out_frames));
  EXPECT_FALSE(fs::exists(o.out_frames + ".partial"));
  // Without a scale the µm columns stay empty.
  const CsvTable t = ParseCsv(ReadFile(o.out_frames), "frames.csv");
  EXPECT_EQ(t.rows[0][t.Column("width_um")], "");
}

}  // namespace
}  // namespace clogscope::apps
