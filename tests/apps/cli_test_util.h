#pragma once

// Runs the built clogscope binary in tests: exit status, standard output and error.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "common/atomic_file.h"
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

}  // namespace clogscope::apps::testing
