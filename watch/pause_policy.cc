#include "watch/pause_policy.h"

#include <cmath>

namespace clogscope::watch {

const char* PrintStateName(PrintState state) {
  switch (state) {
    case PrintState::kUnknown:
      return "unknown";
    case PrintState::kPrinting:
      return "printing";
    case PrintState::kPaused:
      return "paused";
    case PrintState::kIdle:
      return "idle";
  }
  return "unknown";
}

bool ParsePauseLevel(const std::string& name, WatchLevel* level) {
  if (name == "warn")
    *level = WatchLevel::kWarn;
  else if (name == "clog")
    *level = WatchLevel::kClog;
  else
    return false;
  return true;
}

bool PausePolicyOptions::Validate(std::string* why) const {
  if (pause_level != WatchLevel::kWarn && pause_level != WatchLevel::kClog)
    *why = "--pause-level: warn or clog";
  else if (!(std::isfinite(holdoff_s) && holdoff_s >= 0))
    *why = "--pause-holdoff-s must be a number of seconds >= 0";
  else if (!(std::isfinite(retry_s) && retry_s > 0))
    *why = "the pause retry interval must be > 0 s";
  else
    return true;
  return false;
}

PausePolicy::PausePolicy(const PausePolicyOptions& options) : options_(options) {}

bool PausePolicy::Reaches(WatchLevel level) const {
  // Only the drift levels: not_extruding and no_view are what a paused printer (or a covered
  // camera) looks like, and a pause would not help them.
  if (options_.pause_level == WatchLevel::kWarn)
    return level == WatchLevel::kWarn || level == WatchLevel::kClog;
  return level == WatchLevel::kClog;
}

bool PausePolicy::OnPrinterState(double time_s, PrintState state) {
  bool resumed = false;
  if (state == PrintState::kPaused) {
    seen_paused_ = true;
  } else if (state == PrintState::kPrinting && seen_paused_) {
    // Someone resumed: the clog may still show for a while, and they have seen it.
    resumed = true;
    seen_paused_ = false;
    episode_paused_ = false;
    retry_after_s_.reset();
    holdoff_until_s_ = time_s + options_.holdoff_s;
  } else if (state == PrintState::kIdle) {
    // The job ended: a new one starts armed, without a hold-off, a retry or a pause already made.
    seen_paused_ = false;
    episode_paused_ = false;
    retry_after_s_.reset();
    holdoff_until_s_.reset();
  }
  // kUnknown (no answer) keeps seen_paused_: an outage in between is no resume by itself.
  state_ = state;
  return resumed;
}

bool PausePolicy::OnLevel(double time_s, WatchLevel level) {
  if (!Reaches(level)) {
    episode_paused_ = false;  // the episode is over: the next one may pause again
    retry_after_s_.reset();
    return false;
  }
  if (!armed() || episode_paused_ || in_flight_) return false;
  if (holdoff_until_s_ && time_s < *holdoff_until_s_) return false;
  if (retry_after_s_ && time_s < *retry_after_s_) return false;
  episode_paused_ = true;
  in_flight_ = true;
  ++pauses_requested_;
  return true;
}

void PausePolicy::OnPauseResult(double time_s, bool ok) {
  in_flight_ = false;
  if (ok) return;
  // Not sent (the printer away, refused): the episode may try again, not at every report.
  episode_paused_ = false;
  retry_after_s_ = time_s + options_.retry_s;
}

}  // namespace clogscope::watch
