#pragma once

// `watch --moonraker URL` / `--octoprint URL`: the printer's job state polled and the print paused
// on a clog (PausePolicy), on a thread of its own; the measuring thread only hands the latest
// level over. With Moonraker, the webcam to watch when no source is given.

#include <functional>
#include <memory>
#include <string>

#include "watch/pause_policy.h"
#include "watch/printer_api.h"

namespace clogscope::watch {

struct PrinterLinkOptions {
  std::string moonraker_url;  // --moonraker http://HOST:7125; empty: none
  std::string octoprint_url;  // --octoprint http://HOST; empty: none
  std::string api_key_file;   // --printer-api-key-file; empty: no key sent
  std::string webcam;         // --webcam NAME: Moonraker's webcam to watch (default: first enabled)
  // --moonraker-notify-macro NAME: a Klipper macro run after a pause ("NAME LEVEL=clog
  // TIME_S=15.2 DRIFT_PCT=-5.3"), which calls Moonraker's notifier (docs/watch.md).
  std::string notify_macro;
  PausePolicyOptions pause;
  double poll_interval_s = 1;    // --printer-poll-s: the job's state asked this often
  double request_timeout_s = 3;  // each request whole
  bool enabled() const { return !moonraker_url.empty() || !octoprint_url.empty(); }
  // Checks the URLs, reads the key file and the rest: false with one line naming the option.
  bool Validate(std::string* why) const;
  // Validate that hands back the URL as used and the key read, so that what is used is what was
  // checked.
  bool Resolve(std::string* base_url, std::string* api_key, std::string* why) const;
};

// What the link did, for a caller that follows it (tests, logs). `time_s` is the watch's time of
// the latest level handed over (0 before the first).
struct PrinterEvent {
  enum class Kind {
    kState,        // the job's state changed (state)
    kResumed,      // paused, then printing: the hold-off runs from time_s
    kPauseSent,    // the printer took the pause request
    kPauseFailed,  // it did not (error, detail)
    kNotified,     // the notify macro ran (or failed: error)
  };
  Kind kind = Kind::kState;
  double time_s = 0;
  PrintState state = PrintState::kUnknown;
  PrinterError error = PrinterError::kNone;
  std::string detail;
};
const char* PrinterEventName(PrinterEvent::Kind kind);

class PrinterLink {
 public:
  struct Log {
    std::function<void(const std::string&)> info, warning;  // called on any thread
  };
  // Asks the job's state once (blocking, at most request_timeout_s: before the watch starts), then
  // polls it on its own thread. Throws std::invalid_argument (one line naming the option) when the
  // options do not validate. `on_event` is called on the link's thread.
  PrinterLink(const PrinterLinkOptions& options, Log log,
              std::function<void(const PrinterEvent&)> on_event = {});
  // Handles the last level handed over, then ends the thread: waits for a request under way (at
  // most about 2 × request_timeout_s).
  ~PrinterLink();
  PrinterLink(const PrinterLink&) = delete;
  PrinterLink& operator=(const PrinterLink&) = delete;

  // Moonraker's webcam (--webcam, or the first enabled) as a source to open: its stream_url made
  // whole (ResolveWebcamUrl). Throws std::invalid_argument naming --moonraker when it cannot be
  // had (OctoPrint: never asked; the source is required there).
  std::string WebcamSource();

  // The watch's state after each of its updates (LiveWatchEvents::on_state): its level at its
  // time_s, the clock the hold-off and retries are on. Never waits for the network; the latest one
  // wins.
  void Update(const WatchStatus& status);

  const char* api_name() const;  // "Moonraker" or "OctoPrint"
  const std::string& base_url() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace clogscope::watch
