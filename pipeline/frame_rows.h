#pragma once

#include <spdlog/spdlog.h>

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "calib/pixel_scale.h"
#include "pipeline/speed_summary.h"
#include "vision/motion/feed_speed.h"
#include "vision/motion/gear_speed.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

// One measured frame of `measure` in inputs mode: the width, and with --speed the feed and gear
// speeds.
struct FrameRow {
  std::string source;
  int64_t frame = 0;  // the input frame's index
  double time_s = -1;
  vision::StrandMeasurement m;
  vision::FeedSpeedSample speed;
  vision::GearSpeedSample gear;
};

// "<video file name>_<frame>.png" or "<image stem>.png"; a suffix keeps names of this run unique.
std::string OverlayName(const FrameRow& r, bool from_video, std::set<std::string>* used);

// "; width 139.570 ± 0.104 px per frame (mean ± 0.012 px, 95 %)[ = … µm]", from the valid
// rows after the steps' own outlier rejection, the mean's interval as a step's
// (RobustWidthStats: the model's doubt, frames that repeat); empty without valid rows.
std::string WidthSummary(const std::vector<FrameRow>& rows,
                         const std::optional<calib::ScaleCalibration>& conv);

// For a filament whose edges are rough (knurl or gear marks) over part of its stretch on some
// valid frames: a sentence saying so and where the straight part measured lies; else empty.
std::string StraightPartSummary(const std::vector<FrameRow>& rows);

// The feed-speed columns of one row (FeedSpeedCsvColumns): mm/s, its σ (the shift's, scaled up to
// the rows' scatter by the summary, and the scale's), the reason when empty, the baseline in
// frames, whether the summary used the row and why not.
std::vector<std::string> SpeedFields(const vision::FeedSpeedSample& v,
                                     const FeedSpeedSummary& summary, size_t row,
                                     const calib::ScaleCalibration& conv);

// The row's gear surface speed and slip (vision::GearAndSlipOf).
using vision::GearAndSlip;
GearAndSlip GearAndSlipOf(const FrameRow& r, const calib::ScaleCalibration& conv, double radius_mm);

// "; gear 2.00 ± 0.01 mm/s …; slip 10.0 ± 0.5 % per frame pair (mean ± …, 95 %), N of M pairs";
// the slip from the rows whose feed speed `speeds` uses.
std::string GearSummary(const std::vector<FrameRow>& rows, const FeedSpeedSummary& speeds,
                        const calib::ScaleCalibration& conv, double radius_mm);

// The summary of the rows' feed speeds (SummariseFeedSpeeds), one use per row.
FeedSpeedSummary SummariseSpeeds(const std::vector<FrameRow>& rows);

// "; feed speed 0.8001 ± 0.0102 mm/s per row (mean ± 0.0027 mm/s, 95 %), N of M pairs used (…)":
// the mean is that of the rows marked used.
std::string SpeedSummary(const FeedSpeedSummary& summary, const calib::ScaleCalibration& conv);

// Logs why frame pairs have no value, once per reason with the first detail. `reason_of` returns
// an empty reason (Skipped()) for rows that need no word.
inline std::pair<std::string, std::string> Skipped() { return {}; }
template <typename ReasonOf>
void WarnOncePerReason(const std::string& input, const char* what,
                       const std::vector<FrameRow>& rows, ReasonOf reason_of) {
  std::map<std::string, std::pair<int, std::string>> reasons;  // count, first detail
  for (const FrameRow& r : rows) {
    const auto [reason, detail] = reason_of(r);
    if (reason.empty()) continue;
    auto& [count, first] = reasons[reason];
    if (count++ == 0) first = detail;
  }
  for (const auto& [reason, info] : reasons) {
    spdlog::warn("{}: {} frame pair(s) {}: {} (first: {})", input, info.first, what, reason,
                 info.second);
  }
}

}  // namespace clogscope::pipeline
