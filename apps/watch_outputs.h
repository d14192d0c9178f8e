#pragma once

#include <optional>
#include <string>
#include <vector>

#include "watch/live_watch.h"
#include "watch/mqtt_publisher.h"

namespace clogscope::apps {

// The watch's JSON lines: to standard output, or appended to a file. Each line goes out in one
// write(2) on a file opened for appending, so a crash leaves every complete line intact.
class LineLog {
 public:
  // Empty path: standard output. Throws std::invalid_argument naming --log when it cannot open.
  explicit LineLog(const std::string& path);
  ~LineLog();
  void Write(const std::string& line);

 private:
  int fd_ = 1;
  bool own_ = false;
};

// The MQTT publisher's lines, from its own threads: nothing of the watch's stack is captured.
watch::MqttPublisher::Log MqttLog();

// The log's last line of a watch: how it ended, its frames, levels and latency. `prefix` names the
// camera in a farm ("NAME: "), or is empty.
void LogWatchEnded(const std::string& prefix, const watch::LiveWatchSummary& s);

// --on-alert: runs `sh -c COMMAND` on every level change without waiting for it, the state in
// CLOGSCOPE_* environment variables (LEVEL, PREVIOUS_LEVEL, TIME_S, REASON, DIAMETER_UM,
// DRIFT_PCT, DRIFT_CI95_PCT, BASELINE_UM, BACK_PRESSURE_RATIO, VIBRATION_INCREASE_PCT, SOURCE
// with a URL's password hidden, STATUS_JSON; in a farm, PRINTER: the camera's name).
class AlertCommand {
 public:
  explicit AlertCommand(std::string command, std::string printer = "")
      : command_(std::move(command)), printer_(std::move(printer)) {}
  ~AlertCommand();  // waits (up to 10 s) for the commands still running
  // Starts the command; false with *why when it could not be started.
  bool Run(const watch::WatchStatus& status, const std::optional<watch::ClogIndex>& clog,
           const std::string& source, const std::string& status_json, std::string* why);
  // Collects finished commands; returns lines about those that failed.
  std::vector<std::string> Reap(bool wait = false);

 private:
  std::string command_;
  std::string printer_;
  std::vector<int> running_;  // pids
};

}  // namespace clogscope::apps
