#pragma once

// `clogscope watch --config cameras.yaml`: many cameras in one process, each with its own reader,
// state, log, alert command and printer link; one HTTP server and one MQTT connection for them
// all, labelled per printer.

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "apps/watch_command.h"
#include "apps/watch_config.h"

namespace clogscope::apps {

struct WatchFarmReport {
  std::vector<std::string> names;    // the cameras, in the file's order
  std::vector<WatchReport> cameras;  // each one's, in the same order
  // A camera that could not start or ended on an error, "NAME: why"; the others went on.
  std::vector<std::string> errors;
  int http_port = 0;  // the bound port (0 without http)
};

// What a caller may follow (tests, a program embedding the farm).
struct WatchFarmObservers {
  // Once the HTTP server listens and MQTT is connecting, before any source opens: its port.
  std::function<void(int http_port)> on_started;
  // A camera's level change, on that camera's thread, once the server serves it (it waits).
  std::function<void(const std::string& printer, const watch::WatchStatus&)> on_level_change;
  // Once every camera has ended, before the server and MQTT stop: they serve the last states.
  std::function<void(int http_port)> on_finished;
};

// Watches every camera of `options` until *stop (Ctrl-C), or until each has ended (its file's
// end, duration_s). A camera's failure ends that camera only: its error is reported and the
// others go on; a stream or device that cannot be opened at the start is tried again with
// back-off. Throws std::invalid_argument (one line) when the options do not validate or a camera's
// options are refused (a calibration file missing, a log that cannot be opened…), before any
// camera starts.
WatchFarmReport WatchFarm(const WatchFarmOptions& options, std::atomic<bool>* stop,
                          const WatchFarmObservers& observers = {});

}  // namespace clogscope::apps
