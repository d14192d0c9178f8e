// End-to-end tests of `clogscope predict`: the binary on the reference table, a fit, and bad inputs
// that must leave no output files behind.
#include "apps/predict_command.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "tests/apps/cli_test_util.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

using testing::RunCli;
using testing::RunResult;

fs::path FreshDir(const std::string& name) {
  return testing::FreshDir("clogscope_predict_" + name);
}

const char* kTable =
    "# clogscope diameter table\n"
    "step,temperature_c,n,mean_um,std_um,sem_um,ci95_um\n"
    "1,220,50,400.0,2,0.28,0.57\n2,210,50,396.9,2,0.28,0.57\n3,200,50,390.1,2,0.28,0.57\n"
    "4,190,50,381.3,2,0.28,0.57\n5,180,50,365.9,2,0.28,0.57\n6,170,50,345.4,2,0.28,0.57\n";

// A diameter table that carries the measured feedstock: the output says so and the CSV shows it.
TEST(PredictCommandTest, MeasuredFilamentDiameterIsUsedAndSaid) {
  const fs::path d = FreshDir("feedstock");
  WriteFileAtomically((d / "d.csv").string(),
                      "step,temperature_c,mean_um,filament_diameter_um\n1,220,400.0,1748\n"
                      "2,210,396.9,\n3,200,390.1,1761\n");
  const RunResult r = RunCli(
      "predict --diameters " + (d / "d.csv").string() + " --no-plots --out " + (d / "out").string(),
      d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("filament diameter: measured at 2 of 3 steps"), std::string::npos) << r.out;
  const CsvTable t = ParseCsv(ReadFile((d / "out/predictions.csv").string()), "predictions.csv");
  const int c = t.Column("filament_diameter_um");
  ASSERT_GE(c, 0);
  EXPECT_EQ(t.rows[0][c], "1748");
  EXPECT_EQ(t.rows[1][c], "");
}

TEST(PredictCommandTest, ReferenceTableAndFitEndToEnd) {
  const fs::path d = FreshDir("e2e");
  WriteFileAtomically((d / "d.csv").string(), kTable);
  WriteFileAtomically(
      (d / "accel.csv").string(),
      "temperature_c,amplitude_m_s2\n220,0.6479\n210,0.6554\n200,0.6848\n190,0.7414\n"
      "180,0.8769\n170,1.1128\n");
  RunResult r = RunCli("predict --extruder direct-pla --diameters " + (d / "d.csv").string() +
                           " --out " + (d / "out").string(),
                       d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t =
      ParseCsv(ReadFile((d / "out" / "predictions.csv").string()), "predictions.csv");
  for (const char* col :
       {"step", "temperature_c", "diameter_um", "dp1_pa", "dp2_pa", "dp3_pa", "dp_total_pa",
        "f_bp_n", "f_feed_n", "load_n", "relative_amplitude", "amplitude_increase_pct",
        "amplitude_m_s2", "natural_frequency_hz", "current_ma", "buckling_ratio"}) {
    EXPECT_GE(t.Column(col), 0) << col;
  }
  ASSERT_EQ(t.rows.size(), 6u);
  EXPECT_NEAR(std::stod(t.rows[5][t.Column("relative_amplitude")]), 1.8590, 5e-5);
  EXPECT_NEAR(std::stod(t.rows[0][t.Column("f_bp_n")]), 1.2622, 5e-5);
  EXPECT_TRUE(fs::exists(d / "out" / "predictions.json"));

  r = RunCli("predict --diameters " + (d / "d.csv").string() + " --fit " +
                 (d / "accel.csv").string() + " --fit-params activation_temperature_k,gain --out " +
                 (d / "fit").string(),
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("RMS 2.4"), std::string::npos) << r.out;
  // The fitted parameter file is accepted by --extruder and reproduces the fitted amplitudes.
  std::ifstream in(d / "fit" / "predictions.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(j["fit"]["usable"].get<bool>());
  r = RunCli("predict --extruder " + (d / "fit" / "fitted_params.yaml").string() + " --diameters " +
                 (d / "d.csv").string() + " --out " + (d / "again").string() + " --no-plots",
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable again = ParseCsv(ReadFile((d / "again" / "predictions.csv").string()), "again");
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(std::stod(again.rows[i][again.Column("amplitude_m_s2")]),
                j["steps"][i]["amplitude_m_s2"].get<double>(), 1e-6);
  }
}

TEST(PredictCommandTest, BadInputsLeaveNoOutputs) {
  const fs::path d = FreshDir("bad");
  WriteFileAtomically((d / "d.csv").string(), kTable);
  WriteFileAtomically((d / "nocol.csv").string(), "step,temperature_c\n1,220\n");
  WriteFileAtomically((d / "neg.csv").string(),
                      "step,temperature_c,mean_um\n1,220,400\n2,210,-3\n");
  WriteFileAtomically((d / "huge.csv").string(), "step,temperature_c,mean_um\n1,220,2400\n");
  WriteFileAtomically((d / "cold.csv").string(), "step,temperature_c,mean_um\n1,-300,400\n");
  WriteFileAtomically((d / "two.csv").string(), "step,amplitude_m_s2\n1,0.65\n2,0.66\n");
  WriteFileAtomically((d / "bad.yaml").string(),
                      "preset: direct-pla\nflow_index: 0.6\nnozle_angle_deg: 90\n");
  const std::string table = " --diameters " + (d / "d.csv").string();
  struct Case {
    std::string args, expect;
  } cases[] = {
      {"predict --diameters " + (d / "nocol.csv").string(), "mean_um"},
      {"predict --diameters " + (d / "neg.csv").string(), "step 2 (line 3)"},
      {"predict --diameters " + (d / "huge.csv").string(), "entry bore"},
      {"predict --diameters " + (d / "cold.csv").string(), "absolute zero"},
      {"predict" + table + " --set flow_indx=0.5", "unknown parameter 'flow_indx'"},
      {"predict" + table + " --set flow_index", "expected name=value"},
      {"predict" + table + " --extruder " + (d / "bad.yaml").string(), "bad.yaml:3"},
      {"predict" + table + " --extruder hotend-3000", "not a preset"},
      {"predict" + table + " --fit " + (d / "two.csv").string() +
           " --fit-params activation_temperature_k,gain",
       "more than 2 measured values"},
      {"predict" + table + " --fit " + (d / "two.csv").string() + " --fit-params gain,nonsense",
       "unknown parameter 'nonsense'"},
  };
  for (const auto& c : cases) {
    const fs::path out = d / "out";
    fs::remove_all(out);
    const RunResult r = RunCli(c.args + " --out " + out.string(), d);
    EXPECT_NE(r.exit_code, 0) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(out / "predictions.csv")) << c.args;
  }
}

TEST(PredictCommandTest, UnusableFitWritesNothing) {
  const fs::path d = FreshDir("unusable");
  WriteFileAtomically((d / "d.csv").string(), kTable);
  WriteFileAtomically(
      (d / "a.csv").string(),
      "step,amplitude_m_s2\n1,0.6479\n2,0.6554\n3,0.6848\n4,0.7414\n5,0.8769\n6,1.1128\n");
  PredictCommandOptions o;
  o.diameters = (d / "d.csv").string();
  o.fit_measured = (d / "a.csv").string();
  o.fit_params = {"gain", "motor_torque_nm", "drive_roller_radius_m"};  // only T/R matters: flat
  o.out_dir = (d / "out").string();
  const model::PredictionRun r = ComputePrediction(o);
  ASSERT_TRUE(r.fit.has_value());
  EXPECT_FALSE(r.fit->usable);
  const RunResult cli =
      RunCli("predict --diameters " + o.diameters + " --fit " + o.fit_measured +
                 " --fit-params gain,motor_torque_nm,drive_roller_radius_m --out " + o.out_dir,
             d);
  EXPECT_EQ(cli.exit_code, 1);
  EXPECT_NE(cli.err.find("nothing written"), std::string::npos) << cli.err;
  EXPECT_FALSE(fs::exists(d / "out" / "predictions.csv"));
}

}  // namespace
}  // namespace clogscope::apps
