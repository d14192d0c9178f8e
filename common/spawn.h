#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <vector>

namespace clogscope {

// The full path of the executable `name` on $PATH (a name holding '/' is checked as it is), or
// empty. No shell is involved.
std::string FindOnPath(const std::string& name);

struct SpawnOptions {
  std::vector<std::string> argv;                // argv[0]: a path, or a name looked up on $PATH
  std::optional<std::vector<std::string>> env;  // "NAME=value" entries; unset: this process's
  std::string stdout_path, stderr_path;         // created or truncated; empty: inherited
};

// Starts a program without a shell (posix_spawnp): no argument, path or variable is interpreted.
// Returns its pid, or -1 with the reason in *why.
pid_t Spawn(const SpawnOptions& options, std::string* why);

// How a child that waitpid() reported as `status` ended: empty when it exited with 0, else "exited
// with N" or "killed by signal N".
std::string ExitProblem(int status);

// Waits for `pid`; true when it exited with 0, else false with ExitProblem in *why.
bool WaitForExit(pid_t pid, std::string* why);

}  // namespace clogscope
