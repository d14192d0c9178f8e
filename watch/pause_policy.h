#pragma once

// When `watch --moonraker` / `--octoprint` pauses the print: a plain state machine fed with the
// watch's levels and the printer's state, each with the watch's time (the frames' clock, which the
// caller passes: no clock inside).

#include <optional>
#include <string>

#include "watch/watch_state.h"

namespace clogscope::watch {

// The printer's job as its API reports it.
enum class PrintState {
  kUnknown,   // not asked yet, or the last question went unanswered
  kPrinting,  // Klipper's print_stats "printing", OctoPrint's "Printing…"
  kPaused,    // "paused" (OctoPrint's "Pausing" too)
  kIdle,      // anything else: standby, complete, cancelled, error, Operational, Offline…
};
const char* PrintStateName(PrintState state);

struct PausePolicyOptions {
  // The level that pauses (--pause-level): kClog, or kWarn (warn and clog both pause).
  WatchLevel pause_level = WatchLevel::kClog;
  // After a resume, no pause for this long (--pause-holdoff-s): the strand needs a few seconds
  // back at its width before the drift clears, and whoever resumed has looked.
  double holdoff_s = 60;
  // A pause request that failed is tried again after this (the watch's seconds).
  double retry_s = 5;
  bool Validate(std::string* why) const;  // names --pause-level, --pause-holdoff-s
};

// "warn" or "clog" into *level; false for any other name.
bool ParsePauseLevel(const std::string& name, WatchLevel* level);

// Pauses once per episode (the level at or past pause_level, from reaching it until it falls
// back), only while the printer reports printing (armed), never within holdoff_s after a resume
// (paused, then printing again), and again after the hold-off if the level still holds. A failed
// request is retried after retry_s within the same episode.
class PausePolicy {
 public:
  explicit PausePolicy(const PausePolicyOptions& options);

  // The printer's state as last asked, at time_s. Returns true when it tells a resume (paused,
  // then printing): the hold-off runs from time_s.
  bool OnPrinterState(double time_s, PrintState state);
  // The watch's level at time_s. Returns true when the print is to be paused now (the caller
  // sends the request and tells its outcome through OnPauseResult).
  bool OnLevel(double time_s, WatchLevel level);
  void OnPauseResult(double time_s, bool ok);

  bool armed() const { return state_ == PrintState::kPrinting; }
  PrintState state() const { return state_; }
  // Until when no pause is sent after the last resume (nullopt: none seen).
  std::optional<double> holdoff_until_s() const { return holdoff_until_s_; }
  int pauses_requested() const { return pauses_requested_; }

 private:
  bool Reaches(WatchLevel level) const;

  PausePolicyOptions options_;
  PrintState state_ = PrintState::kUnknown;
  bool seen_paused_ = false;     // paused since the printer last printed
  bool episode_paused_ = false;  // a pause was asked (or sent) in this episode
  bool in_flight_ = false;       // a request is out, its outcome not told yet
  std::optional<double> holdoff_until_s_, retry_after_s_;
  int pauses_requested_ = 0;
};

}  // namespace clogscope::watch
