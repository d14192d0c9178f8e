#include "apps/watch_outputs.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <httplib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <thread>

#include "common/csv.h"
#include "common/spawn.h"
#include "vision/io/source_name.h"
#include "vision/overlay/overlay.h"

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

struct WatchHttpServer::Impl {
  httplib::Server server;
  std::thread thread;
};

WatchHttpServer::WatchHttpServer(const std::string& host_port, const watch::WatchBoard* board,
                                 std::optional<calib::ScaleCalibration> conversion)
    : impl_(std::make_unique<Impl>()) {
  const size_t colon = host_port.rfind(':');
  int port = -1;
  if (colon != std::string::npos) {
    try {
      size_t used = 0;
      port = std::stoi(host_port.substr(colon + 1), &used);
      if (used != host_port.size() - colon - 1) port = -1;
    } catch (const std::exception&) {
      port = -1;
    }
  }
  if (colon == std::string::npos || colon == 0 || port < 0 || port > 65535)
    throw std::invalid_argument("--http '" + host_port +
                                "': expected HOST:PORT, e.g. 0.0.0.0:8090");
  const std::string host = host_port.substr(0, colon);
  httplib::Server& srv = impl_->server;
  srv.Get("/status", [board](const httplib::Request&, httplib::Response& res) {
    const watch::WatchSnapshot s = board->Read();
    res.set_content(watch::StatusJson(s.status, s.clog, s.counters, "status") + "\n",
                    "application/json");
  });
  srv.Get("/metrics", [board](const httplib::Request&, httplib::Response& res) {
    const watch::WatchSnapshot s = board->Read();
    res.set_content(watch::PrometheusText(s.status, s.clog, s.counters),
                    "text/plain; version=0.0.4; charset=utf-8");
  });
  srv.Get("/frame.jpg", [board, conversion](const httplib::Request&, httplib::Response& res) {
    const watch::WatchSnapshot s = board->Read();
    if (s.frame.empty()) {
      res.status = 503;
      res.set_content("no frame yet\n", "text/plain");
      return;
    }
    // Drawn on request: the measuring thread never pays for a picture nobody looks at.
    std::vector<uchar> jpeg;
    cv::imencode(
        ".jpg",
        vision::DrawOverlay(s.frame, s.measurement, conversion ? conversion->scale_um_per_px : 0.0,
                            conversion ? conversion->edge_bias_px : 0.0),
        jpeg, {cv::IMWRITE_JPEG_QUALITY, 85});
    res.set_content(reinterpret_cast<const char*>(jpeg.data()), jpeg.size(), "image/jpeg");
  });
  srv.Get("/", [](const httplib::Request&, httplib::Response& res) {
    res.set_content("clogscope watch: /status /metrics /frame.jpg\n", "text/plain");
  });
  port_ = port == 0 ? srv.bind_to_any_port(host) : (srv.bind_to_port(host, port) ? port : -1);
  if (port_ <= 0) {
    throw std::invalid_argument(fmt::format(
        "--http {}: cannot listen there (port in use, no permission, or unknown host)", host_port));
  }
  impl_->thread = std::thread([this] { impl_->server.listen_after_bind(); });
}

WatchHttpServer::~WatchHttpServer() {
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

}  // namespace clogscope::apps
