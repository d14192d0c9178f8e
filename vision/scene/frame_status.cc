#include "vision/scene/frame_status.h"

#include <stdexcept>

namespace clogscope::vision {

const char* FrameStatusName(FrameStatus status) {
  switch (status) {
    case FrameStatus::kValid:
      return "";
    case FrameStatus::kUnreadable:
      return "unreadable";
    case FrameStatus::kNoStrand:
      return "no_strand";
    case FrameStatus::kNoTip:
      return "no_tip";
    case FrameStatus::kTouchesBorder:
      return "touches_border";
    case FrameStatus::kBandOutsideFrame:
      return "band_outside_frame";
    case FrameStatus::kLowContrast:
      return "low_contrast";
    case FrameStatus::kOutOfFocus:
      return "out_of_focus";
    case FrameStatus::kSaturated:
      return "saturated";
    case FrameStatus::kOccluded:
      return "occluded";
    case FrameStatus::kWidthOutlier:
      return "width_outlier";
    case FrameStatus::kAmbiguous:
      return "ambiguous";
    case FrameStatus::kNotSilhouette:
      return "not_silhouette";
    case FrameStatus::kImprecise:
      return "imprecise";
  }
  return "?";
}

const char* MeasureTargetName(MeasureTarget target) {
  return target == MeasureTarget::kStrand ? "strand" : "filament";
}

MeasureTarget ParseMeasureTarget(const std::string& name) {
  if (name == "strand") return MeasureTarget::kStrand;
  if (name == "filament") return MeasureTarget::kFilament;
  throw std::invalid_argument("target '" + name + "': expected strand or filament");
}

}  // namespace clogscope::vision
