// End-to-end test of `clogscope run` on a small rendered experiment: calibration from pins in the
// manifest, sampled steps against the truth, the predictor, the summary; bad manifests; --resume.
#include <gtest/gtest.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
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

class RunCommandTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: the suite may run as parallel processes (one a case).
    dir_ = testing::FreshDir("clogscope_run_e2e");
    const std::string small = " --size 640x360 --tip-x-px 320 ";
    std::string pins = "image,diameter_um\n";
    for (int d : {300, 400, 500}) {
      ASSERT_EQ(RunCli("render --target pin --edge-bias-px 0.3 --strand-width-um " +
                           std::to_string(d) + small + "--tip-y-px 180 --out " +
                           (dir_ / ("pin" + std::to_string(d))).string(),
                       dir_)
                    .exit_code,
                0);
      pins += "pin" + std::to_string(d) + "/frame_000000.png," + std::to_string(d) + "\n";
    }
    WriteFileAtomically((dir_ / "pins.csv").string(), pins);
    const double diams[] = {400.0, 390.1, 365.9};
    std::string manifest =
        "name: small\nsamples: 12\nsettle_s: 0.4\ncalibrate:\n  pins: pins.csv\nextruder: "
        "direct-pla\nsteps:\n";
    for (int i = 0; i < 3; ++i) {
      const std::string v = "s" + std::to_string(i + 1) + ".mp4";
      ASSERT_EQ(
          RunCli("render --frames 50 --edge-bias-px 0.3 --width-jitter-um 1 --strand-width-um " +
                     std::to_string(diams[i]) + small + "--tip-y-px 100 --seed " +
                     std::to_string(i + 1) + " --out " + (dir_ / v).string(),
                 dir_)
              .exit_code,
          0);
      manifest += "  - {step: " + std::to_string(i + 1) +
                  ", temperature_c: " + std::to_string(220 - 10 * i) + ", video: " + v + "}\n";
    }
    WriteFileAtomically((dir_ / "exp.yaml").string(), manifest);
  }
  static fs::path dir_;
};
fs::path RunCommandTest::dir_;

TEST_F(RunCommandTest, WholePipeline) {
  const fs::path out = dir_ / "out";
  const RunResult r =
      RunCli("run " + (dir_ / "exp.yaml").string() + " --out " + out.string() + " --jobs 2", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* f :
       {"calibration.yaml", "frames.csv", "diameters.csv", "diameters.json", "summary.md",
        "summary.json", "predict/predictions.csv", "steps/step_0003.json"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
  }
  const CsvTable t = ParseCsv(ReadFile((out / "diameters.csv").string()), "diameters.csv");
  const double diams[] = {400.0, 390.1, 365.9};
  ASSERT_EQ(t.rows.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(t.rows[i][t.Column("status")], "ok");
    EXPECT_EQ(t.rows[i][t.Column("n")], "12");
    // Jitter 1 µm over 12 frames: the mean is within ~0.3 µm (1σ) of the rendered diameter.
    EXPECT_NEAR(std::stod(t.rows[i][t.Column("mean_um")]), diams[i], 1.2) << i;
    EXPECT_GT(std::stod(t.rows[i][t.Column("ci95_um")]), 0);
  }
  const std::string summary = ReadFile((out / "summary.md").string());
  EXPECT_NE(summary.find("Pixel scale (pins)"), std::string::npos);
  EXPECT_NE(summary.find("Predicted bar-mount vibration"), std::string::npos);
  // --resume: nothing re-measured, same table.
  const RunResult again =
      RunCli("run " + (dir_ / "exp.yaml").string() + " --out " + out.string() + " --resume", dir_);
  ASSERT_EQ(again.exit_code, 0) << again.err;
  EXPECT_NE(again.err.find("kept from the earlier run"), std::string::npos);
  const CsvTable t2 = ParseCsv(ReadFile((out / "diameters.csv").string()), "diameters.csv");
  EXPECT_EQ(t2.rows[1][t2.Column("mean_um")], t.rows[1][t.Column("mean_um")]);
}

TEST_F(RunCommandTest, BadManifestsAreOneLineErrors) {
  WriteFileAtomically((dir_ / "typo.yaml").string(), "name: x\nsampels: 5\nsteps: []\n");
  RunResult r =
      RunCli("run " + (dir_ / "typo.yaml").string() + " --out " + (dir_ / "o1").string(), dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("typo.yaml:2: unknown key 'sampels'"), std::string::npos) << r.err;
  r = RunCli("run " + (dir_ / "nope.yaml").string() + " --out " + (dir_ / "o2").string(), dir_);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nope.yaml"), std::string::npos) << r.err;
  // A band in µm without any pixel scale: refused as `measure` refuses it (one line from one
  // home), not measured at an assumed 3 µm/px.
  WriteFileAtomically(
      (dir_ / "band.yaml").string(),
      "samples: 5\nband_height_um: 90\nsteps:\n  - {step: 1, temperature_c: 220, video: s1.mp4}\n");
  r = RunCli("run " + (dir_ / "band.yaml").string() + " --out " + (dir_ / "o4").string(), dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  const std::string band_err = "a band in µm needs a pixel scale";
  EXPECT_NE(r.err.find("band.yaml: band_height_um: " + band_err), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "o4" / "frames.csv"));
  r = RunCli("measure " + (dir_ / "s1.mp4").string() + " --band-start-um 50", dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("--band-start-um: " + band_err), std::string::npos) << r.err;
  // One step's video is missing: the others complete, exit 2.
  WriteFileAtomically(
      (dir_ / "partial.yaml").string(),
      "samples: 5\nscale_um_per_px: 3\nsteps:\n  - {step: 1, temperature_c: 220, video: s1.mp4}\n"
      "  - {step: 2, temperature_c: 210, video: gone.mp4}\n");
  r = RunCli("run " + (dir_ / "partial.yaml").string() + " --out " + (dir_ / "o3").string(), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("gone.mp4"), std::string::npos) << r.err;
  const CsvTable t = ParseCsv(ReadFile((dir_ / "o3" / "diameters.csv").string()), "d");
  EXPECT_EQ(t.rows[0][t.Column("status")], "ok");
  EXPECT_EQ(t.rows[1][t.Column("status")], "failed");
}

// Whether signal `sig` is still pending for process `pid` (/proc: its SigPnd and ShdPnd masks).
bool SignalPending(pid_t pid, int sig) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("SigPnd:", 0) != 0 && line.rfind("ShdPnd:", 0) != 0) continue;
    if ((std::stoull(line.substr(7), nullptr, 16) >> (sig - 1)) & 1) return true;
  }
  return false;
}

// Starts clogscope with `args`, waits for its first finished step (the progress line "[1/" on
// its standard error: a readiness signal, no clock), then sends `signals` SIGINTs, each once the
// one before has been taken, and returns how it ended: its exit status, or −N when signal N
// killed it. Its standard error is appended to `log`.
int RunAndInterrupt(const std::string& args, int signals, const std::string& log) {
  int fds[2];
  if (pipe(fds) != 0) return -1000;
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], STDERR_FILENO);
    close(fds[0]);
    close(fds[1]);
    const std::string cmd = "exec " + std::string(CLOGSCOPE_BINARY) + " " + args + " >/dev/null";
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  std::string err;
  char buf[4096];
  ssize_t n;
  int sent = 0;
  while ((n = read(fds[0], buf, sizeof buf)) > 0) {  // to the end: a full pipe would block it
    err.append(buf, static_cast<size_t>(n));
    if (sent > 0 || err.find("[1/") == std::string::npos) continue;
    for (; sent < signals; ++sent) {
      while (sent > 0 && SignalPending(pid, SIGINT)) sched_yield();
      kill(pid, SIGINT);
    }
  }
  close(fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  std::ofstream(log, std::ios::app) << err;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

// Ctrl-C stops after the running step with status 130 and a summary that says so; a second Ctrl-C
// stops at once, still with the exit status 130 (death by SIGINT would read −2 here, not 130).
TEST_F(RunCommandTest, InterruptedRunsExit130) {
  // Twenty steps (the three videos again and again), one at a time: long enough to interrupt.
  std::string manifest = "name: long\nsamples: 12\nsettle_s: 0.4\nsteps:\n";
  for (int i = 0; i < 20; ++i) {
    manifest += "  - {step: " + std::to_string(i + 1) +
                ", temperature_c: " + std::to_string(220 - i) + ", video: s" +
                std::to_string(i % 3 + 1) + ".mp4}\n";
  }
  WriteFileAtomically((dir_ / "long.yaml").string(), manifest);
  const std::string args =
      "run " + (dir_ / "long.yaml").string() + " --scale-um-per-px 3 --jobs 1 --out ";
  const fs::path once = dir_ / "int_once", twice = dir_ / "int_twice";
  const std::string log = (dir_ / "interrupt.log").string();
  WriteFileAtomically(log, "");
  EXPECT_EQ(RunAndInterrupt(args + once.string(), 1, log), 130) << ReadFile(log);
  // Stopped after the running step: the finished ones are kept, the summary says so.
  const auto j = nlohmann::json::parse(ReadFile((once / "summary.json").string()));
  EXPECT_TRUE(j["cancelled"].get<bool>());
  EXPECT_LT(j["steps"].size(), 20u);
  EXPECT_NE(ReadFile(log).find("interrupted"), std::string::npos);
  EXPECT_EQ(RunAndInterrupt(args + twice.string(), 2, log), 130) << ReadFile(log);
}

}  // namespace
}  // namespace clogscope::apps
