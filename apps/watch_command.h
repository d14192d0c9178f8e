#pragma once

// `clogscope watch`: a live camera or stream, diameter drift, clog index and alerts.

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "pipeline/measure_inputs.h"
#include "watch/live_watch.h"
#include "watch/mqtt_publisher.h"
#include "watch/printer_link.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunWatch(int argc, char** argv);

struct WatchCommandOptions {
  // The measurement as `measure` has it (scale or calibration, ROI, band, target, polarity…);
  // its inputs are not used.
  pipeline::MeasureInputsOptions measure;
  // Source, its timeouts, the rolling window and thresholds, report interval, duration. Its
  // strand, conversion and extruder are filled from the fields here.
  watch::LiveWatchOptions live;
  std::string extruder;                 // preset or YAML: attaches the clog index; empty: none
  std::vector<std::string> set;         // "name=value" overrides of the extruder
  std::optional<double> temperature_c;  // the nozzle's; default the extruder's reference
  std::string log_path;                 // JSON lines appended here; empty: standard output
  std::string http;                     // [HOST:]PORT for /status, /metrics, /frame.jpg
  std::string http_token_file;          // the bearer token the server asks for; empty: none
  std::string on_alert;                 // shell command run on every level change
  watch::MqttOptions mqtt;              // --mqtt, --mqtt-credentials-file; no url: none
  // --moonraker / --octoprint, --printer-api-key-file, --pause-level, --pause-holdoff-s,
  // --printer-poll-s, --webcam, --moonraker-notify-macro; no URL: none. With --moonraker and no
  // source, its webcam is watched.
  watch::PrinterLinkOptions printer;
};

struct WatchReport {
  watch::LiveWatchSummary summary;
  int http_port = 0;  // the bound port (the real one for --http HOST:0)
  std::vector<std::string> alert_failures;
};

// What a caller of WatchNozzle may follow (tests, a program embedding the watch), each called on
// the watch's thread when given.
struct WatchObservers {
  // Once the HTTP server listens (before the source opens): its port (0 without --http).
  std::function<void(int http_port)> on_started;
  // On every level change, after its JSON line and the alert command, once /status, /metrics and
  // /frame.jpg serve the new state; the watch waits for it, so they keep serving that state
  // meanwhile.
  std::function<void(const watch::WatchStatus&)> on_level_change;
  // What the printer link did (its state seen, a pause sent, a resume seen…), on the link's own
  // thread: the watch does not wait for it.
  std::function<void(const watch::PrinterEvent&)> on_printer;
};

// Watches a camera, stream, file or folder until *stop (or the file's end, or --duration-s),
// writing JSON lines, serving HTTP, running the alert command and pausing the printer. Throws
// std::invalid_argument (one line naming the option, file or source) when nothing can be watched:
// bad options, a source that cannot be opened or yields no frame (or, with --moonraker and no
// source, no webcam listed), a log that cannot be opened, a port in use.
WatchReport WatchNozzle(const WatchCommandOptions& options, std::atomic<bool>* stop,
                        const WatchObservers& observers = {});

}  // namespace clogscope::apps
