#pragma once

// Internal to the watch's JSON outputs (watch_report.cc, watch_history.cc).
#include <cmath>
#include <nlohmann/json.hpp>

#include "watch/watch_report.h"

namespace clogscope::watch {

// v to `digits` decimals (RoundDecimals); JSON has no NaN: a quantity not known is null.
inline nlohmann::json JsonNumber(double v, int digits) {
  return std::isfinite(v) ? nlohmann::json(RoundDecimals(v, digits)) : nlohmann::json();
}

}  // namespace clogscope::watch
