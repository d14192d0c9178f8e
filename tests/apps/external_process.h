#pragma once

// External programs in the watch's tests, started without a shell (posix_spawn): one fed on its
// standard input through a pipe, and a server whose log is read through a pipe as it writes it.
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <vector>

extern char** environ;

namespace clogscope::apps::testing {

// A free port on 127.0.0.1 (bound to port 0, told, closed: another program may take it meanwhile).
inline int FreeLoopbackPort() {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a));
  socklen_t len = sizeof(a);
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  close(fd);
  return ntohs(a.sin_port);
}

// `argv` started with its standard input the read end of a pipe and its standard output and error
// the write end of another (SIGPIPE at its default in the child); its standard error to the file
// `error_path` instead when one is named (a program whose output is a document, not a log).
// Returns the pid, or -1; *input and *output are this side's ends (close-on-exec), -1 when not
// wanted.
inline pid_t SpawnWithPipes(const std::vector<std::string>& argv, int* input, int* output,
                            const std::string& error_path = "") {
  int in[2] = {-1, -1}, out[2] = {-1, -1};
  if ((input && pipe2(in, O_CLOEXEC) != 0) || pipe2(out, O_CLOEXEC) != 0) return -1;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (input)
    posix_spawn_file_actions_adddup2(&actions, in[0], 0);
  else
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, out[1], 1);
  if (error_path.empty())
    posix_spawn_file_actions_adddup2(&actions, out[1], 2);
  else
    posix_spawn_file_actions_addopen(&actions, 2, error_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                     0644);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGPIPE);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  if (posix_spawnp(&pid, args[0], &actions, &attr, args.data(), environ) != 0) pid = -1;
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (input) close(in[0]);
  close(out[1]);
  if (pid < 0) {
    if (input) close(in[1]);
    close(out[0]);
    return -1;
  }
  if (input) *input = in[1];
  *output = out[0];
  return pid;
}

struct ProgramResult {
  int exit_code = -1;  // -1: not started, or killed by a signal
  std::string output;  // standard output and error, interleaved as written (error: see below)
};

// Runs `argv` with `input` on its standard input and waits for it; what it writes is read while
// the input is written (poll on both pipes), so neither side can block the other. Its standard
// error goes to `error_path` when one is named, else into the output.
inline ProgramResult RunWithInput(const std::vector<std::string>& argv, const std::string& input,
                                  const std::string& error_path = "") {
  ProgramResult r;
  int in = -1, out = -1;
  const pid_t pid = SpawnWithPipes(argv, &in, &out, error_path);
  if (pid < 0) return r;
  fcntl(in, F_SETFL, O_NONBLOCK);
  // A child that exits before reading all its input must not kill this process with SIGPIPE.
  const auto old_pipe = signal(SIGPIPE, SIG_IGN);
  const auto close_input = [&] {
    close(in);
    in = -1;
  };
  size_t written = 0;
  if (input.empty()) close_input();
  char buf[4096];
  while (out >= 0) {
    pollfd p[2] = {{out, POLLIN, 0}, {in, POLLOUT, 0}};
    if (poll(p, in >= 0 ? 2 : 1, -1) < 0) continue;
    if (in >= 0 && p[1].revents) {
      const ssize_t n = write(in, input.data() + written, input.size() - written);
      if (n > 0) written += static_cast<size_t>(n);
      if (n < 0 || written == input.size()) close_input();
    }
    if (p[0].revents) {
      const ssize_t n = read(out, buf, sizeof buf);
      if (n > 0) {
        r.output.append(buf, static_cast<size_t>(n));
      } else {
        close(out);
        out = -1;
      }
    }
  }
  if (in >= 0) close(in);
  signal(SIGPIPE, old_pipe);
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  return r;
}

// A server started with its output on a pipe, read as it comes; stopped with SIGTERM at the end.
class ServerProcess {
 public:
  ServerProcess() = default;
  explicit ServerProcess(const std::vector<std::string>& argv) {
    pid_ = SpawnWithPipes(argv, nullptr, &out_);
  }
  ~ServerProcess() { Stop(); }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  bool started() const { return pid_ > 0; }
  const std::string& log() const { return log_; }

  // Reads what the server writes until `text` is in it (true), it closes its output (it ended), or
  // `deadline` passes: woken by its output, not by a clock.
  bool WaitForLog(const std::string& text, std::chrono::steady_clock::time_point deadline) {
    while (log_.find(text) == std::string::npos) {
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                            deadline - std::chrono::steady_clock::now())
                            .count();
      if (out_ < 0 || left <= 0) return false;
      ReadFor(static_cast<int>(left));
    }
    return true;
  }
  // What it wrote since, waiting up to timeout_ms for it: keeps its pipe from filling, and paces
  // a caller that polls the server.
  void ReadFor(int timeout_ms) {
    if (out_ < 0) return;
    pollfd p{out_, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return;
    char buf[4096];
    const ssize_t n = read(out_, buf, sizeof buf);
    if (n <= 0) {
      close(out_);
      out_ = -1;
    } else {
      log_.append(buf, static_cast<size_t>(n));
    }
  }
  // SIGTERM, and SIGKILL if it has not ended within 30 s (its output closed at its end).
  void Stop() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
      while (out_ >= 0 && std::chrono::steady_clock::now() < deadline) ReadFor(1000);
      if (out_ >= 0) kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
    }
    if (out_ >= 0) close(out_);
    out_ = -1;
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  std::string log_;
};

}  // namespace clogscope::apps::testing
