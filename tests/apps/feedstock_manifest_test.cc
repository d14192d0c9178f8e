// A manifest whose steps film the feedstock too (the feedstock issue, item 4): the diameter table
// gains the filament's diameter and the slip per step, --resume keeps them, the predictor uses the
// measured diameter; bad feedstock blocks are one-line errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using testing::RunCli;
using testing::RunResult;

// Two strand steps (3 µm/px) and, for each, a feedstock video at 20 µm/px whose drive gear's
// surface runs at 5 mm/s: the filament 1750 µm at 4.5 mm/s (10 % slip), then 1760 µm at 4.0 mm/s
// (20 %).
class FeedstockManifestTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: the suite may run as parallel processes (one a case).
    dir_ = testing::FreshDir("clogscope_feedstock_manifest");
    const double widths[] = {400, 390}, filaments[] = {1750, 1760}, feeds[] = {4.5, 4.0};
    for (int i = 0; i < 2; ++i) {
      const std::string n = std::to_string(i + 1);
      ASSERT_EQ(RunCli("render --out " + (dir_ / ("s" + n + ".avi")).string() +
                           " --frames 30 --size 640x360 --tip-x-px 320 --tip-y-px 100 "
                           "--strand-width-um " +
                           std::to_string(widths[i]) + " --seed " + n,
                       dir_)
                    .exit_code,
                0);
      ASSERT_EQ(
          RunCli("render --out " + (dir_ / ("f" + n + ".avi")).string() +
                     " --no-nozzle --scale-um-per-px 20 --size 640x480 --tip-x-px 320 "
                     "--tip-y-px 0 --fps 30 --frames 30 --surface-texture 8 --strand-width-um " +
                     std::to_string(filaments[i]) + " --feed-speed-mm-s " +
                     std::to_string(feeds[i]) +
                     " --drive-gear 176,240,100 --gear-surface-speed-mm-s 5 --seed " + n,
                 dir_)
              .exit_code,
          0);
    }
  }
  static void Write(const std::string& name, const std::string& feedstock_block) {
    WriteFileAtomically((dir_ / name).string(),
                        "name: feed\nsamples: 8\nscale_um_per_px: 3\nextruder: direct-pla\n" +
                            feedstock_block +
                            "steps:\n"
                            "  - {step: 1, temperature_c: 220, video: s1.avi, feedstock_video: "
                            "f1.avi}\n"
                            "  - {step: 2, temperature_c: 210, video: s2.avi, feedstock_video: "
                            "f2.avi}\n");
  }
  static fs::path dir_;
};
fs::path FeedstockManifestTest::dir_;

const std::string kBlock =
    "feedstock:\n  scale_um_per_px: 20\n  gear_roi: 70,134,213,213\n  gear_radius_mm: 2\n";

TEST_F(FeedstockManifestTest, DiameterTableGainsTheFilamentAndTheSlip) {
  Write("exp.yaml", kBlock);
  const std::string out = (dir_ / "out").string();
  const std::string manifest = (dir_ / "exp.yaml").string();
  RunResult r = RunCli("run " + manifest + " --out " + out, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (bool resumed : {false, true}) {
    const CsvTable t =
        ParseCsv(ReadFile((fs::path(out) / "diameters.csv").string()), "diameters.csv");
    const int c_d = t.Column("filament_diameter_um"), c_ci = t.Column("filament_diameter_ci95_um"),
              c_slip = t.Column("slip_pct"), c_slip_ci = t.Column("slip_ci95_pct"),
              c_st = t.Column("feedstock_status");
    ASSERT_GE(c_d, 0);
    ASSERT_EQ(t.rows.size(), 2u);
    const double filaments[] = {1750, 1760}, slips[] = {10, 20};
    for (int i = 0; i < 2; ++i) {
      const auto& row = t.rows[i];
      EXPECT_EQ(row[c_st], "ok") << resumed;
      // The renders' widths are exact: the mean within 0.5 µm (0.025 px), inside its CI + 0.2 µm.
      const double d = std::stod(row[c_d]), ci = std::stod(row[c_ci]);
      EXPECT_NEAR(d, filaments[i], 0.5);
      EXPECT_LE(std::abs(d - filaments[i]), ci + 0.2);
      EXPECT_NEAR(std::stod(row[c_slip]), slips[i], 0.5);
      EXPECT_GT(std::stod(row[c_slip_ci]), 0);
    }
    if (resumed) break;
    r = RunCli("run " + manifest + " --resume --out " + out, dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // The prediction used the measured filament diameters, and said so.
  const std::string predict = ReadFile((fs::path(out) / "predict" / "predictions.csv").string());
  EXPECT_NE(predict.find("1749."), std::string::npos) << predict;
  EXPECT_NE(r.out.find("step 2 feedstock: filament 17"), std::string::npos) << r.out;
}

TEST_F(FeedstockManifestTest, AMissingFeedstockVideoFailsOnlyTheFeedstock) {
  WriteFileAtomically(
      (dir_ / "missing.yaml").string(),
      "name: m\nsamples: 8\nscale_um_per_px: 3\nsteps:\n"
      "  - {step: 1, temperature_c: 220, video: s1.avi, feedstock_video: nope.avi}\n");
  const std::string out = (dir_ / "out_missing").string();
  const RunResult r =
      RunCli("measure --manifest " + (dir_ / "missing.yaml").string() + " --out " + out, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t =
      ParseCsv(ReadFile((fs::path(out) / "diameters.csv").string()), "diameters.csv");
  EXPECT_EQ(t.rows[0][t.Column("status")], "ok");
  EXPECT_EQ(t.rows[0][t.Column("feedstock_status")], "failed");
  EXPECT_NE(t.rows[0][t.Column("feedstock_detail")].find("nope.avi"), std::string::npos);
  EXPECT_EQ(t.rows[0][t.Column("filament_diameter_um")], "");
}

TEST_F(FeedstockManifestTest, BadFeedstockBlocksAreOneLineErrors) {
  const std::pair<std::string, std::string> cases[] = {
      {"feedstock:\n  gear_roi: 70,134,213,213\n  scale_um_per_px: 20\n", "gear_radius_mm"},
      {"feedstock:\n  gear_radius_mm: 2\n  speed: yes\n", "unknown key 'speed'"},
      {"feedstock:\n  scale_um_per_px: -1\n", "must be positive"},
      {"feedstock:\n  roi: 1,2,3\n", "roi"},
      {"feedstock:\n  scale_um_per_px: 20\n  gear_roi: 70,134,213,213\n  gear_radius_mm: 2\n"
       "  gear_centre: 176\n",
       "feedstock: gear_centre '176': expected x,y"},
  };
  int k = 0;
  for (const auto& [block, expected] : cases) {
    const std::string name = "bad" + std::to_string(++k) + ".yaml";
    Write(name, block);
    const RunResult r = RunCli(
        "measure --manifest " + (dir_ / name).string() + " --out " + (dir_ / ("o" + name)).string(),
        dir_);
    EXPECT_EQ(r.exit_code, 1) << block;
    EXPECT_NE(r.err.find(expected), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

}  // namespace
}  // namespace clogscope::apps
