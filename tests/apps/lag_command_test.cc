// End-to-end tests of `clogscope lag`: a rendered video whose strand follows a known lag, measured
// and fitted by the binary; simulations; and inputs that must fail with one line and no output.
#include <fmt/format.h>
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

const char* kProfile = "time_s,flow_mm3_s\n0,5\n1.0,10\n2.5,6\n4.0,11\n5.5,5\n";

// 25 frames/s video, 2 µm of per-frame width jitter on top of the lagged width: K within 5 %, and
// the truth within 4σ of the fit.
TEST(LagCommandTest, KFittedFromARenderedVideo) {
  const fs::path d = testing::FreshDir("clogscope_lag_video");
  WriteFileAtomically((d / "profile.csv").string(), kProfile);
  for (double k : {0.1, 0.5}) {
    const std::string tag = k < 0.2 ? "fast" : "slow";
    const std::string video = (d / (tag + ".avi")).string();
    RunResult r =
        RunCli(fmt::format("render --out {} --frames 175 --fps 25 --size 640x480 "
                           "--tip-x-px 320 --tip-y-px 120 --width-jitter-um 2 "
                           "--lag-commanded {} --lag-k-s {} --lag-um-per-mm3-s 40 --seed 4",
                           video, (d / "profile.csv").string(), k),
               d);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto truth = nlohmann::json::parse(ReadFile((d / (tag + ".truth.json")).string()));
    EXPECT_DOUBLE_EQ(truth["lag"]["k_s"].get<double>(), k);
    const std::string frames = (d / (tag + ".csv")).string();
    r = RunCli(fmt::format("measure {} --scale-um-per-px 3 --out-frames {}", video, frames), d);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const std::string out = (d / tag).string();
    r = RunCli(fmt::format("lag --frames {} --commanded {} --out {} --no-plots", frames,
                           (d / "profile.csv").string(), out),
               d);
    ASSERT_EQ(r.exit_code, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("linear advance to set"), std::string::npos) << r.out;
    const auto fit = nlohmann::json::parse(ReadFile(out + "/lag.json"));
    const double k_fit = fit["k_s"], sigma = fit["k_sigma_s"];
    std::printf("K %.2f s: fitted %.5f ± %.5f s, RMS %.3f µm\n", k, k_fit, sigma,
                fit["rms_um"].get<double>());
    EXPECT_NEAR(k_fit, k, 0.05 * k);
    EXPECT_LT(std::abs(k_fit - k), 4 * sigma);
    EXPECT_NEAR(fit["gain_um_per_mm3_s"].get<double>(), 40, 0.5);
    EXPECT_EQ(fit["frames_total"], 175);
    EXPECT_TRUE(fs::exists(out + "/lag_fit.csv"));
  }
}

// With K_LA = K the simulated outlet is the command; without, it lags.
TEST(LagCommandTest, SimulationWithLinearAdvanceFollowsTheCommand) {
  const fs::path d = testing::FreshDir("clogscope_lag_sim");
  WriteFileAtomically((d / "profile.csv").string(), kProfile);
  RunResult r =
      RunCli("lag --commanded " + (d / "profile.csv").string() +
                 " --k-s 0.2 --k-la-s 0.2 --dt-s 0.01 --no-plots --out " + (d / "sim").string(),
             d);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const CsvTable t = ParseCsv(ReadFile((d / "sim/outlet.csv").string()), "outlet.csv");
  const int c_cmd = t.Column("commanded_flow_mm3_s"), c_out = t.Column("outlet_flow_mm3_s"),
            c_la = t.Column("outlet_flow_linear_advance_mm3_s");
  ASSERT_GE(c_la, 0);
  double worst_la = 0, worst_plain = 0;
  for (const auto& row : t.rows) {
    const double cmd = std::stod(row[c_cmd]);
    worst_la = std::max(worst_la, std::abs(std::stod(row[c_la]) - cmd));
    worst_plain = std::max(worst_plain, std::abs(std::stod(row[c_out]) - cmd));
  }
  EXPECT_LT(worst_la, 1e-4);  // the file's 5 decimals
  EXPECT_GT(worst_plain, 1.0);
}

TEST(LagCommandTest, BadInputsFailWithOneLineAndNoOutput) {
  const fs::path d = testing::FreshDir("clogscope_lag_bad");
  WriteFileAtomically((d / "profile.csv").string(), kProfile);
  WriteFileAtomically((d / "late.csv").string(), "time_s,flow_mm3_s\n100,5\n101,10\n");
  WriteFileAtomically((d / "flat.csv").string(), "time_s,flow_mm3_s\n0,5\n3,5\n");
  std::string frames = "source,frame,time_s,valid,width_px\n";
  for (int i = 0; i < 50; ++i)
    frames += fmt::format("v.avi,{},{},1,{}\n", i, i * 0.04, 100 + i % 3);
  WriteFileAtomically((d / "frames.csv").string(), frames);
  const std::string f = (d / "frames.csv").string(), out = (d / "out").string();
  struct Case {
    std::string args, expect;
  };
  const Case cases[] = {
      {"--frames " + f + " --commanded " + (d / "late.csv").string(), "does not overlap"},
      {"--frames " + f + " --commanded " + (d / "flat.csv").string(), "does not change"},
      {"--commanded " + (d / "profile.csv").string(), "either --frames"},
      {"--frames " + f + " --commanded " + (d / "missing.csv").string(), "missing.csv"},
      {"--commanded " + (d / "profile.csv").string() + " --k-s 0", "--k-s"},
      {"--commanded " + f + " --k-s 0.1", "time_s column and one of flow_mm3_s"},
      {"--frames " + f + " --commanded " + (d / "profile.csv").string() +
           " --max-offset-s 2147483648",
       "--max-offset-s 2.14748e+09: must be in [0, 60] s"},
      {"--frames " + f + " --commanded " + (d / "profile.csv").string() + " --max-offset-s 1e5",
       "--max-offset-s 100000: must be in [0, 60] s"},
  };
  for (const auto& c : cases) {
    const RunResult r = RunCli("lag " + c.args + " --out " + out, d);
    EXPECT_EQ(r.exit_code, 1) << c.args;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << c.args << "\n" << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

}  // namespace
}  // namespace clogscope::apps
