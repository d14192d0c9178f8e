#pragma once

// Runs the built clogscope binary in tests: exit status, standard output and error.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/atomic_file.h"
#include "synthetic/synthetic.h"
#include "tests/scratch_dir.h"

namespace clogscope::apps::testing {

struct RunResult {
  int exit_code;
  std::string out, err;
};

// `args` after the binary name; output is captured in files in `dir`.
inline RunResult RunCli(const std::string& args, const std::filesystem::path& dir) {
  const std::string o = (dir / "stdout.txt").string(), e = (dir / "stderr.txt").string();
  const int status =
      std::system((std::string(CLOGSCOPE_BINARY) + " " + args + " >" + o + " 2>" + e).c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadFile(o), ReadFile(e)};
}

// An empty folder of the test's own under the system's temporary directory.
inline std::filesystem::path FreshDir(const std::string& name) { return testutil::FreshDir(name); }

// A watch's camera in the tests: 640×360, the nozzle's tip at (320, 80), the strand's width
// jittering by 2 µm from frame to frame; widths and events are the test's.
inline synthetic::SceneParams WatchCameraScene(uint64_t seed) {
  synthetic::SceneParams s;
  s.width_px = 640;
  s.height_px = 360;
  s.tip_x_px = 320;
  s.tip_y_px = 80;
  s.width_jitter_um = 2.0;
  s.seed = seed;
  return s;
}

}  // namespace clogscope::apps::testing
