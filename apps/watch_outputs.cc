#include "apps/watch_outputs.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <stdexcept>
#include <thread>

#include "common/csv.h"
#include "common/spawn.h"
#include "vision/io/source_name.h"

extern char** environ;

namespace clogscope::apps {

LineLog::LineLog(const std::string& path) {
  if (path.empty() || path == "-") return;
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::invalid_argument(
        fmt::format("--log {}: cannot open ({})", path, std::strerror(errno)));
  own_ = true;
}

LineLog::~LineLog() {
  if (own_) ::close(fd_);
}

void LineLog::Write(const std::string& line) {
  const std::string out = line + "\n";
  size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::write(fd_, out.data() + done, out.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return;  // a full disk or a closed pipe must not stop the watch
    done += static_cast<size_t>(n);
  }
}

bool AlertCommand::Run(const watch::WatchStatus& s, const std::optional<watch::ClogIndex>& clog,
                       const std::string& source, const std::string& status_json,
                       std::string* why) {
  Reap();
  std::vector<std::string> env;
  for (char** e = environ; *e; ++e)
    if (std::strncmp(*e, "CLOGSCOPE_", 10) != 0) env.emplace_back(*e);
  const auto add = [&](const char* name, const std::string& value) {
    env.push_back(std::string("CLOGSCOPE_") + name + "=" + value);
  };
  add("LEVEL", watch::WatchLevelName(s.level));
  add("PREVIOUS_LEVEL", watch::WatchLevelName(s.previous_level));
  add("TIME_S", CsvNumber(s.time_s, 3));
  add("REASON", s.reason);
  add("DIAMETER_UM", s.has_diameter ? CsvNumber(s.diameter_um, 3) : "");
  add("DRIFT_PCT", s.has_recent ? CsvNumber(s.recent_drift_pct, 3) : "");
  add("DRIFT_CI95_PCT", s.has_recent ? CsvNumber(s.recent_drift_ci95_pct, 3) : "");
  add("BASELINE_UM", s.baseline_ready ? CsvNumber(s.baseline_um, 3) : "");
  add("BACK_PRESSURE_RATIO", clog ? CsvNumber(clog->back_pressure_ratio, 5) : "");
  add("VIBRATION_INCREASE_PCT", clog ? CsvNumber(clog->vibration_increase_pct, 3) : "");
  add("SOURCE", vision::RedactCredentials(source));  // a child may log it: no password
  if (!printer_.empty()) add("PRINTER", printer_);
  add("STATUS_JSON", status_json);
  SpawnOptions run;
  run.argv = {"/bin/sh", "-c", command_};
  run.env = std::move(env);
  std::string spawn_why;
  const pid_t pid = Spawn(run, &spawn_why);
  if (pid < 0) {
    *why = "--on-alert: " + spawn_why;
    return false;
  }
  running_.push_back(pid);
  return true;
}

std::vector<std::string> AlertCommand::Reap(bool wait) {
  std::vector<std::string> failures;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!running_.empty()) {
    for (auto it = running_.begin(); it != running_.end();) {
      int status = 0;
      const pid_t r = waitpid(*it, &status, WNOHANG);
      if (r == 0) {
        ++it;
        continue;
      }
      if (const std::string problem = r == *it ? ExitProblem(status) : ""; !problem.empty())
        failures.push_back("--on-alert command " + problem);
      it = running_.erase(it);
    }
    if (!wait || running_.empty() || std::chrono::steady_clock::now() > deadline) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return failures;
}

AlertCommand::~AlertCommand() { Reap(/*wait=*/true); }

watch::MqttPublisher::Log MqttLog() {
  return {[](const std::string& m) { spdlog::info("{}", m); },
          [](const std::string& m) { spdlog::warn("{}", m); }};
}

void LogWatchEnded(const std::string& prefix, const watch::LiveWatchSummary& s) {
  spdlog::info(
      "{}watch ended ({}): {} frames, {} valid, {} skipped, {} reconnect(s), {} level change(s), "
      "final level {}; latency median {:.1f} ms, p95 {:.1f} ms",
      prefix, s.ended_because.empty() ? "not started" : s.ended_because, s.frames, s.valid_frames,
      s.skipped_frames, s.reconnects, s.level_changes, watch::WatchLevelName(s.final_level),
      s.latency_median_ms, s.latency_p95_ms);
}

}  // namespace clogscope::apps
