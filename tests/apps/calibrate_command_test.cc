// End-to-end tests of `clogscope calibrate` and `measure --calib` on rendered targets, and the
// bad inputs of the calibration issue: each a one-line error and no calibration file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "calib/calibration_file.h"
#include "common/atomic_file.h"
#include "common/csv.h"
#include "tests/apps/cli_test_util.h"
#include "vision/io/video_io.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

using testing::RunCli;
using testing::RunResult;

const std::string kSmall = " --size 640x360 --tip-x-px 320 --tip-y-px 180 ";

// Renders pins of the given diameters (bias 0.3 px, 3 µm/px) and their CSV in `dir`.
void RenderPins(const fs::path& dir, const std::vector<int>& diameters,
                const std::string& extra_csv_rows = "") {
  std::string csv = "image,diameter_um,tolerance_um\n";
  for (int d : diameters) {
    const std::string name = "pin" + std::to_string(d);
    ASSERT_EQ(RunCli("render --target pin --strand-width-um " + std::to_string(d) +
                         " --edge-bias-px 0.3 --silhouette" + kSmall + "--seed " +
                         std::to_string(d) + " --out " + (dir / name).string(),
                     dir)
                  .exit_code,
              0);
    csv += name + "/frame_000000.png," + std::to_string(d) + ",0.5\n";
  }
  WriteFileAtomically((dir / "pins.csv").string(), csv + extra_csv_rows);
}

TEST(CalibrateCommandTest, PinsThenMeasureWithCalib) {
  const fs::path d = testing::FreshDir("clogscope_calib_e2e");
  RenderPins(d, {300, 400, 500});
  RunResult r = RunCli(
      "calibrate --pins " + (d / "pins.csv").string() + " --out " + (d / "cal.yaml").string(), d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("outliers 0 of 3"), std::string::npos) << r.out;
  const calib::ScaleCalibration cal = calib::ReadCalibrationFile((d / "cal.yaml").string());
  EXPECT_NEAR(cal.scale_um_per_px, 3.0, 3.0 * 5e-4);
  EXPECT_NEAR(cal.edge_bias_px, 0.3, 0.05);
  EXPECT_GT(cal.scale_sigma_um_per_px, 0);
  EXPECT_TRUE(fs::exists(d / "cal_residuals.png"));
  // A strand seen through the same optics: µm from the calibration, bias removed.
  ASSERT_EQ(RunCli("render --strand-width-um 381.3 --edge-bias-px 0.3 --size 640x360 --tip-x-px "
                   "320 --tip-y-px 100 --out " +
                       (d / "strand").string(),
                   d)
                .exit_code,
            0);
  r = RunCli("measure " + (d / "strand").string() + " --calib " + (d / "cal.yaml").string() +
                 " --out-frames " + (d / "f.csv").string(),
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "f.csv").string()), "f.csv");
  EXPECT_NEAR(std::stod(t.rows[0][t.Column("width_um")]), 381.3, 0.3);
  EXPECT_GT(std::stod(t.rows[0][t.Column("width_sigma_um")]), 0);
}

TEST(CalibrateCommandTest, MicrometerEndToEnd) {
  const fs::path d = testing::FreshDir("clogscope_calib_micro");
  ASSERT_EQ(RunCli("render --target micrometer --pitch-um 100 --tilt-deg 4 --silhouette --out " +
                       (d / "m").string(),
                   d)
                .exit_code,
            0);
  const RunResult r = RunCli("calibrate --micrometer " + (d / "m" / "frame_000000.png").string() +
                                 " --pitch-um 100 --out " + (d / "cal.yaml").string(),
                             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NEAR(calib::ReadCalibrationFile((d / "cal.yaml").string()).scale_um_per_px, 3.0,
              3.0 * 2e-4);
}

// A 10 µm stage micrometer as in issue 22 (ticks of three lengths, numerals, dust), 8 bit and 16
// bit of 12-bit data: calibrated, the marks that are no lines left out and counted in the report.
TEST(CalibrateCommandTest, StageMicrometerWithNumeralsAndDust) {
  const fs::path d = testing::FreshDir("clogscope_calib_stage");
  const std::string stage =
      "render --target micrometer --scale-um-per-px 0.5 --line-width-um 2 "
      "--tick-length-um 80 --numerals --dust 25 --fibres 3 --tip-y-px 380 --tilt-deg -2.5 "
      "--silhouette --seed 11 ";
  for (const std::string depth : {"8", "16"}) {
    const fs::path out = d / ("stage" + depth);
    ASSERT_EQ(RunCli(stage + "--pitch-um 10 --bit-depth " + depth +
                         (depth == "16" ? " --data-bits 12" : "") + " --out " + out.string(),
                     d)
                  .exit_code,
              0);
    const fs::path cal = d / ("cal" + depth + ".yaml");
    const RunResult r = RunCli("calibrate --micrometer " + (out / "frame_000000.png").string() +
                                   " --pitch-um 10 --out " + cal.string(),
                               d);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NEAR(calib::ReadCalibrationFile(cal.string()).scale_um_per_px, 0.5, 0.5 * 2e-4);
    // The note names the image and says how many marks were left out (only when some were).
    EXPECT_NE(r.out.find("frame_000000.png: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find(" marks left out: "), std::string::npos) << r.out;
  }
  // Two micrometers of 10 and 12 µm pitch side by side: refused in one line naming the file.
  ASSERT_EQ(RunCli(stage + "--pitch-um 12 --out " + (d / "stage12").string(), d).exit_code, 0);
  std::string why;
  const cv::Mat a = vision::ReadImage((d / "stage8" / "frame_000000.png").string(), &why);
  const cv::Mat b = vision::ReadImage((d / "stage12" / "frame_000000.png").string(), &why);
  ASSERT_FALSE(a.empty() || b.empty()) << why;
  cv::Mat mixed = a.clone();
  b.colRange(640, 1280).copyTo(mixed.colRange(640, 1280));
  const std::string mixed_path = (d / "mixed.png").string();
  vision::WriteImageAtomically(mixed_path, mixed);
  const RunResult r = RunCli(
      "calibrate --micrometer " + mixed_path + " --pitch-um 10 --out " + (d / "m.yaml").string(),
      d);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find(mixed_path + ": "), std::string::npos) << r.err;
  EXPECT_TRUE(r.err.find("not evenly spaced") != std::string::npos ||
              r.err.find("two lattices fit") != std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(d / "m.yaml"));
}

TEST(CalibrateCommandTest, BadInputsWriteNoCalibration) {
  const fs::path d = testing::FreshDir("clogscope_calib_bad");
  RenderPins(d, {300, 400});
  const std::string good_rows =
      "pin300/frame_000000.png,300,0.5\npin400/frame_000000.png,400,0.5\n";
  WriteFileAtomically(
      (d / "same.csv").string(),
      "image,diameter_um\npin300/frame_000000.png,400\npin400/frame_000000.png,400\n");
  WriteFileAtomically((d / "nodiam.csv").string(), "image,diameter_um\npin300/frame_000000.png,\n");
  WriteFileAtomically((d / "missing.csv").string(),
                      "image,diameter_um\n" + good_rows.substr(0, 0) + "nothere.png,300\n");
  WriteFileAtomically((d / "empty.csv").string(), "image,diameter_um\n");
  ASSERT_EQ(RunCli("render --target pin --strand-width-um 300 --silhouette --size 640x360 "
                   "--tip-x-px 10 --tip-y-px 180 --out " +
                       (d / "cut").string(),
                   d)
                .exit_code,
            0);
  WriteFileAtomically((d / "notfound.csv").string(),
                      "image,diameter_um\ncut/frame_000000.png,300\npin400/frame_000000.png,400\n");
  ASSERT_EQ(RunCli("render --target micrometer --pitch-um 600 --silhouette --size 640x360 --out " +
                       (d / "sparse").string(),
                   d)
                .exit_code,
            0);
  ASSERT_EQ(RunCli("render --target micrometer --pitch-um 100 --silhouette --size 640x360 --out " +
                       (d / "m").string(),
                   d)
                .exit_code,
            0);
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"--pins " + (d / "same.csv").string(), "same diameter"},
      {"--pins " + (d / "nodiam.csv").string(), "nodiam.csv:2: diameter_um is missing"},
      {"--pins " + (d / "missing.csv").string(), "nothere.png: no such file"},
      {"--pins " + (d / "empty.csv").string(), "no pins listed"},
      {"--pins " + (d / "notfound.csv").string(), "pin not found"},
      {"--micrometer " + (d / "sparse" / "frame_000000.png").string() + " --pitch-um 600",
       "need at least 3"},
      {"--micrometer " + (d / "m" / "frame_000000.png").string() +
           " --pitch-um 10 --expect-scale-um-per-px 3",
       "does not fit the line spacing"},
      {"--micrometer " + (d / "m" / "frame_000000.png").string(), "--pitch-um must be positive"},
      {"--pins " + (d / "pins.csv").string() + " --micrometer x.png --pitch-um 100",
       "either --pins"},
      // Numbers no quantity can have (these once overflowed the fit into a crash).
      {"--micrometer " + (d / "m" / "frame_000000.png").string() + " --pitch-um inf",
       "--pitch-um inf: not a finite number"},
      {"--micrometer " + (d / "m" / "frame_000000.png").string() + " --pitch-um 1e309",
       "--pitch-um 1e309: not a finite number"},
      {"--micrometer " + (d / "m" / "frame_000000.png").string() + " --pitch-um 4.9e-324",
       "--pitch-um 4.9e-324: not a finite number"},
      {"--micrometer " + (d / "m" / "frame_000000.png").string() + " --pitch-um 1e308",
       "must be between 1 and 10000"},
  };
  for (const auto& c : cases) {
    const fs::path out = d / "cal.yaml";
    fs::remove(out);
    const RunResult r = RunCli("calibrate " + c.args + " --out " + out.string(), d);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
    EXPECT_FALSE(fs::exists(out.string() + ".partial")) << c.args;
  }
}

TEST(CalibrateCommandTest, MeasureRefusesBadCalibrationFiles) {
  const fs::path d = testing::FreshDir("clogscope_calib_refuse");
  WriteFileAtomically((d / "garbage.yaml").string(), "this: [is: not");
  WriteFileAtomically((d / "v9.yaml").string(),
                      "%YAML:1.0\n---\nclogscope_calibration_version: 9\nscale_um_per_px: 3\n");
  WriteFileAtomically(
      (d / "neg.yaml").string(),
      "%YAML:1.0\n---\nclogscope_calibration_version: 1\nusable: 1\nscale_um_per_px: -3\n"
      "scale_sigma_um_per_px: 0\nedge_bias_px: 0\n");
  // Nested 50,000 deep (once a stack overflow), a NUL byte, an emptied key, an infinite scale.
  WriteFileAtomically((d / "deep.yaml").string(), std::string(50000, '['));
  std::string maps;
  for (int i = 0; i < 50000; ++i) maps += "{a: ";
  WriteFileAtomically((d / "deepmap.yaml").string(), maps);
  WriteFileAtomically((d / "nul.yaml").string(),
                      std::string("clogscope_calibration_version: 1\n\0usable: 1\n", 45));
  WriteFileAtomically((d / "emptied.yaml").string(),
                      "clogscope_calibration_version: 1\nusable: 1\nscale_um_per_px:\n");
  WriteFileAtomically((d / "inf.yaml").string(),
                      "clogscope_calibration_version: 1\nusable: 1\nscale_um_per_px: .inf\n");
  for (const auto& [file, expect] : std::vector<std::pair<std::string, std::string>>{
           {"garbage.yaml", "garbage.yaml"},
           {"v9.yaml", "version 9"},
           {"neg.yaml", "must be positive"},
           {"absent.yaml", "absent.yaml"},
           {"deep.yaml", "deep.yaml: not a calibration file"},
           {"deepmap.yaml", "deepmap.yaml: not a calibration file"},
           {"nul.yaml", "nul.yaml"},
           {"emptied.yaml", "emptied.yaml: scale_um_per_px: missing"},
           {"inf.yaml", "is not a number"}}) {
    const RunResult r = RunCli(
        "measure x.png --calib " + (d / file).string() + " --out-frames " + (d / "f.csv").string(),
        d);
    EXPECT_NE(r.exit_code, 0) << file;
    EXPECT_NE(r.err.find(expect), std::string::npos) << file << "\n" << r.err;
  }
}

}  // namespace
}  // namespace clogscope::apps
