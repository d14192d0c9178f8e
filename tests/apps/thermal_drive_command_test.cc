// End-to-end tests of `clogscope thermal` and `clogscope drive`: the study's numbers through the
// binary, files written, and bad inputs.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;
using testing::RunCli;
using testing::RunResult;

const char* kTable =
    "step,temperature_c,mean_um,slip_pct\n1,220,400.0,\n2,210,396.9,0.9\n3,200,390.1,\n"
    "4,190,381.3,\n5,180,365.9,\n6,170,345.4,\n";

TEST(ThermalCommandTest, AssessesVelocitiesAndWritesCriticalLengths) {
  const fs::path d = testing::FreshDir("clogscope_thermal");
  WriteFileAtomically((d / "d.csv").string(), kTable);
  const RunResult r = RunCli(
      "thermal --material abs --fan-velocity-m-s 0.112 --fan-velocity-m-s 0.02 --t4-c 75 "
      "--diameters " +
          (d / "d.csv").string() + " --filament-modulus-pa 5e7 --out " + (d / "out").string(),
      d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("abs at 0.112 m/s: T4 68.9 °C — safe"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("EXTRAPOLATED"), std::string::npos) << r.out;  // 0.02 m/s
  const auto j = nlohmann::json::parse(ReadFile((d / "out/thermal.json").string()));
  ASSERT_EQ(j["assessments"].size(), 3u);
  EXPECT_EQ(j["assessments"][0]["risk"], "safe");
  EXPECT_EQ(j["assessments"][1]["risk"], "clog_risk");
  EXPECT_EQ(j["assessments"][1]["extrapolated"], true);
  EXPECT_EQ(j["assessments"][2]["risk"], "marginal");
  EXPECT_NEAR(j["assessments"][2]["t4_c"].get<double>(), 75, 1e-12);
  EXPECT_EQ(j["softening"]["melt_viscosity_pa_s"], 350);  // the study's ABS value
  const CsvTable t = ParseCsv(ReadFile((d / "out/softening.csv").string()), "softening.csv");
  ASSERT_EQ(t.rows.size(), 6u);
  EXPECT_FALSE(j["provenance"]["command_line"].get<std::string>().empty());
}

TEST(ThermalCommandTest, BadInputsFailWithOneLine) {
  const fs::path d = testing::FreshDir("clogscope_thermal_bad");
  WriteFileAtomically((d / "d.csv").string(), kTable);
  const std::pair<std::string, std::string> cases[] = {
      {"--material petg --fan-velocity-m-s 0.3", "expected pla or abs"},
      {"--material pla", "give --fan-velocity-m-s"},
      {"--material pla --t4-c 120", "no fan velocity gives it"},
      {"--material pla --fan-velocity-m-s -1", "--fan-velocity-m-s"},
      {"--material pla --diameters " + (d / "d.csv").string(), "--filament-modulus-pa"},
  };
  for (const auto& [args, expect] : cases) {
    const RunResult r = RunCli("thermal " + args, d);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(expect), std::string::npos) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

TEST(DriveCommandTest, OperatingPointAndStepsWithMeasuredSlip) {
  const fs::path d = testing::FreshDir("clogscope_drive");
  WriteFileAtomically((d / "d.csv").string(), kTable);
  RunResult r = RunCli("drive --roller 3 --pinch-force-n 80 --feed-force-n 20", d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("6.700 ± 0.200 %"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("DISAGREES"), std::string::npos) << r.out;  // #3's printed F_p,min
  r = RunCli("drive --roller hobb-goblin --pinch-force-n 90 --friction-n 1.5 --diameters " +
                 (d / "d.csv").string() + " --out " + (d / "out").string(),
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "out/drive.csv").string()), "drive.csv");
  ASSERT_EQ(t.rows.size(), 6u);
  const int c_ff = t.Column("feed_force_n"), c_bp = t.Column("f_bp_n"),
            c_slip = t.Column("slip_pct"), c_meas = t.Column("measured_slip_pct");
  for (const auto& row : t.rows) {
    const double ff = std::stod(row[c_ff]);
    EXPECT_NEAR(ff, std::stod(row[c_bp]) + 1.5, 2e-4);
    EXPECT_NEAR(std::stod(row[c_slip]), (96.0 / 8100 + 0.32) * ff, 1e-3);
  }
  EXPECT_EQ(t.rows[1][c_meas], "0.9000");
  EXPECT_EQ(t.rows[0][c_meas], "");
  const auto j = nlohmann::json::parse(ReadFile((d / "out/drive.json").string()));
  EXPECT_EQ(j["roller"]["min_pinch_force_agrees"], false);
  EXPECT_EQ(j["velocity_form_extrapolated"], false);
}

TEST(DriveCommandTest, BadInputsFailWithOneLine) {
  const fs::path d = testing::FreshDir("clogscope_drive_bad");
  const std::pair<std::string, std::string> cases[] = {
      {"--roller mk8 --pinch-force-n 80 --feed-force-n 20", "7-straight-knurl"},
      {"--roller 3 --pinch-force-n 0 --feed-force-n 20", "pinch force 0 N: must be positive"},
      {"--roller 3 --pinch-force-n -4 --feed-force-n 20", "pinch force -4 N"},
      {"--roller 3 --feed-force-n 20", "--pinch-force-n is required"},
      {"--roller 3 --pinch-force-n 80", "either --feed-force-n"},
  };
  for (const auto& [args, expect] : cases) {
    const RunResult r = RunCli("drive " + args, d);
    EXPECT_EQ(r.exit_code, 1) << args;
    EXPECT_NE(r.err.find(expect), std::string::npos) << args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  }
}

}  // namespace
}  // namespace clogscope::apps
