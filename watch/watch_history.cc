#include "watch/watch_history.h"

#include <fmt/format.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "watch/json_number.h"
#include "watch/watch_report.h"

namespace clogscope::watch {

bool WatchHistoryOptions::Validate(std::string* why) const {
  if (!(period_s >= 0.01 && period_s <= 3600))
    *why = fmt::format("history period {:g} s: must be in [0.01, 3600] s", period_s);
  else if (!(max_points >= 2 && max_points <= 100000))
    *why = fmt::format("history points {}: must be in [2, 100000]", max_points);
  else
    return true;
  return false;
}

WatchHistory::WatchHistory(const WatchHistoryOptions& options) : options_(options) {
  std::string why;
  if (!options_.Validate(&why)) throw std::invalid_argument(why);
}

void WatchHistory::Add(const WatchStatus& s) {
  if (s.level == WatchLevel::kStarting) return;  // nothing known yet
  HistoryPoint p;
  // To the millisecond, as served: a page asking for the points since a time it was told finds
  // the same points the server does.
  p.time_s = RoundDecimals(s.time_s, 3);
  p.level = s.level;
  p.has_diameter = s.has_diameter;
  if (s.has_diameter) {
    p.diameter_px = s.diameter_px;
    p.diameter_ci95_px = s.diameter_ci95_px;
    p.diameter_um = s.diameter_um;
    p.diameter_ci95_um = s.diameter_ci95_um;
  }
  if (s.baseline_ready) {
    p.baseline_px = s.baseline_px;
    p.baseline_um = s.baseline_um;
    if (s.has_diameter) p.drift_pct = s.drift_pct;
  }
  p.valid_fraction = s.valid_fraction;
  const auto period = static_cast<long long>(std::floor(p.time_s / options_.period_s));
  // The state watches its clock never step back; a period at or before the newest one's is the
  // same period still under way.
  if (!points_.empty() && period <= last_period_) {
    points_.back() = p;
    return;
  }
  if (static_cast<int>(points_.size()) >= options_.max_points) points_.pop_front();
  points_.push_back(p);
  last_period_ = period;
}

std::vector<HistoryPoint> WatchHistory::Points(double since_s) const {
  const auto first = std::find_if(points_.begin(), points_.end(),
                                  [&](const HistoryPoint& p) { return p.time_s >= since_s; });
  return {first, points_.end()};
}

std::string HistoryJson(const std::vector<HistoryPoint>& points, const WatchHistoryOptions& options,
                        bool has_scale) {
  nlohmann::json list = nlohmann::json::array();
  for (const HistoryPoint& p : points) {
    list.push_back({{"time_s", RoundDecimals(p.time_s, 3)},
                    {"level", WatchLevelName(p.level)},
                    {"diameter_px", JsonNumber(p.diameter_px, 4)},
                    {"ci95_low_px", JsonNumber(p.diameter_px - p.diameter_ci95_px, 4)},
                    {"ci95_high_px", JsonNumber(p.diameter_px + p.diameter_ci95_px, 4)},
                    {"diameter_um", JsonNumber(p.diameter_um, 3)},
                    {"ci95_low_um", JsonNumber(p.diameter_um - p.diameter_ci95_um, 3)},
                    {"ci95_high_um", JsonNumber(p.diameter_um + p.diameter_ci95_um, 3)},
                    {"baseline_px", JsonNumber(p.baseline_px, 4)},
                    {"baseline_um", JsonNumber(p.baseline_um, 3)},
                    {"drift_pct", JsonNumber(p.drift_pct, 4)},
                    {"valid_fraction", RoundDecimals(p.valid_fraction, 4)}});
  }
  const nlohmann::json j = {{"period_s", options.period_s},
                            {"max_points", options.max_points},
                            {"unit", has_scale ? "um" : "px"},
                            {"points", std::move(list)}};
  return j.dump();
}

}  // namespace clogscope::watch
