#include "common/spawn.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <utility>

extern char** environ;

namespace clogscope {

std::string FindOnPath(const std::string& name) {
  if (name.empty()) return "";
  if (name.find('/') != std::string::npos) return ::access(name.c_str(), X_OK) == 0 ? name : "";
  const char* path = std::getenv("PATH");
  const std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  size_t begin = 0;
  while (begin <= dirs.size()) {
    size_t end = dirs.find(':', begin);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = end > begin ? dirs.substr(begin, end - begin) : ".";
    const std::string candidate = dir + "/" + name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    begin = end + 1;
  }
  return "";
}

pid_t Spawn(const SpawnOptions& o, std::string* why) {
  if (o.argv.empty()) {
    *why = "no program to start";
    return -1;
  }
  std::vector<std::string> args = o.argv, env = o.env.value_or(std::vector<std::string>{});
  std::vector<char*> argv, envp;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  for (std::string& e : env) envp.push_back(e.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  for (const auto& [fd, path] :
       {std::pair{STDOUT_FILENO, &o.stdout_path}, std::pair{STDERR_FILENO, &o.stderr_path}}) {
    if (!path->empty())
      posix_spawn_file_actions_addopen(&actions, fd, path->c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                       0644);
  }
  pid_t pid = -1;
  const int err = posix_spawnp(&pid, args[0].c_str(), &actions, nullptr, argv.data(),
                               o.env ? envp.data() : environ);
  posix_spawn_file_actions_destroy(&actions);
  if (err != 0) {
    *why = fmt::format("cannot start {} ({})", args[0], std::strerror(err));
    return -1;
  }
  return pid;
}

std::string ExitProblem(int status) {
  if (WIFEXITED(status))
    return WEXITSTATUS(status) == 0 ? "" : fmt::format("exited with {}", WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return fmt::format("killed by signal {}", WTERMSIG(status));
  return "ended oddly";
}

bool WaitForExit(pid_t pid, std::string* why) {
  int status = 0;
  pid_t r;
  do {
    r = ::waitpid(pid, &status, 0);
  } while (r < 0 && errno == EINTR);
  if (r != pid) {
    *why = fmt::format("cannot wait for process {} ({})", pid, std::strerror(errno));
    return false;
  }
  *why = ExitProblem(status);
  return why->empty();
}

}  // namespace clogscope
