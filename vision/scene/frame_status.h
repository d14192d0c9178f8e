#pragma once

#include <string>

namespace clogscope::vision {

// Why a frame gives no width. kValid when it does.
enum class FrameStatus {
  kValid,
  kUnreadable,        // the frame could not be decoded
  kNoStrand,          // nothing strand-like in the frame or ROI
  kNoTip,             // a strand but no nozzle tip above it, or none fixed over a changing width
  kTouchesBorder,     // the strand's edges in the band reach the frame or ROI border
  kBandOutsideFrame,  // the band leaves the frame/ROI or runs into the bed or an obstacle
  kLowContrast,
  kOutOfFocus,
  kSaturated,
  kOccluded,       // too few calipers agree
  kWidthOutlier,   // far from the neighbouring frames' widths (set by FlagWidthOutliers)
  kAmbiguous,      // two strand-like objects of similar score: no guess
  kNotSilhouette,  // one edge does not fit a silhouette against a plain background
  kImprecise,      // the width's σ is above what a valid width may carry
};
inline constexpr int kFrameStatusCount = static_cast<int>(FrameStatus::kImprecise) + 1;

// A width was measured: valid, or with a σ too large to be (kImprecise).
inline bool GivesWidth(FrameStatus s) {
  return s == FrameStatus::kValid || s == FrameStatus::kImprecise;
}
const char* FrameStatusName(FrameStatus status);

// What is measured: a strand below a nozzle tip (the band is placed from the tip), or a filament,
// needle, pin or nozzle body with no tip (the band runs along the visible straight stretch).
enum class MeasureTarget { kStrand, kFilament };
const char* MeasureTargetName(MeasureTarget target);
// Parses "strand" or "filament"; throws std::invalid_argument otherwise.
MeasureTarget ParseMeasureTarget(const std::string& name);

}  // namespace clogscope::vision
