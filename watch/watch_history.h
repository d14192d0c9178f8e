#pragma once

// The recent past of a live watch for its web page (/history.json): one point per period of the
// watch's clock (the state at the end of that period), the last max_points of them, in a ring of
// bounded size.

#include <cmath>
#include <deque>
#include <limits>
#include <string>
#include <vector>

#include "watch/watch_state.h"

namespace clogscope::watch {

struct WatchHistoryOptions {
  double period_s = 1;   // one point per period of the watch's clock
  int max_points = 600;  // the oldest point goes when a new one would pass it (10 min at 1 s)
  bool Validate(std::string* why) const;
};

// The state at the end of one period (or the latest state, for the period under way). µm fields
// are NaN without a scale, diameter fields without a diameter, baseline fields before the
// baseline, as in WatchStatus.
struct HistoryPoint {
  double time_s = 0;  // the watch's clock (WatchStatus::time_s) at the state kept
  WatchLevel level = WatchLevel::kStarting;
  bool has_diameter = false;
  double diameter_px = NAN, diameter_ci95_px = NAN;  // mean over the rolling window, its 95 % CI
  double diameter_um = NAN, diameter_ci95_um = NAN;  // half-width
  double baseline_px = NAN, baseline_um = NAN;
  double drift_pct = NAN;  // the window's, from the baseline
  double valid_fraction = 0;
};

// Fed with every state published (WatchBoard does), in time order. Not thread-safe: its owner
// locks.
class WatchHistory {
 public:
  // Throws std::invalid_argument when the options do not validate.
  explicit WatchHistory(const WatchHistoryOptions& options = {});

  // The state at status.time_s: a new point when a period began since the last one, else it
  // replaces the point of the period under way. A state before the first frame (kStarting) is no
  // point.
  void Add(const WatchStatus& status);
  // The points whose time is at or after since_s, oldest first.
  std::vector<HistoryPoint> Points(double since_s = -std::numeric_limits<double>::infinity()) const;
  size_t size() const { return points_.size(); }
  const WatchHistoryOptions& options() const { return options_; }

 private:
  WatchHistoryOptions options_;
  std::deque<HistoryPoint> points_;
  long long last_period_ = 0;  // the period (time_s / period_s, floored) of the newest point
};

// The /history.json document (one line, no newline): the period, the bound, the unit the page
// plots in ("um" with a scale, else "px") and the points, each with its level's name and its CI
// as low and high bounds; what is not known is null.
std::string HistoryJson(const std::vector<HistoryPoint>& points, const WatchHistoryOptions& options,
                        bool has_scale);

}  // namespace clogscope::watch
