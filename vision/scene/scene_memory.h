#pragma once

#include <opencv2/core.hpp>

#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

// Whether the camera still sees the scene it measured. After a valid frame it keeps a patch of the
// nozzle just above the tip; a later frame without a strand is compared with that patch, so that
// "the nozzle is in view but nothing comes out of it" can be told from "the view is lost"
// (covered, moved, dark). A filament target has no nozzle: nothing is remembered.
class SceneMemory {
 public:
  explicit SceneMemory(MeasureTarget target) : target_(target) {}
  // Keeps the nozzle patch of a valid strand measurement (refreshed every `refresh_every` calls,
  // so slow lighting changes are followed). Ignores invalid measurements.
  void Remember(const cv::Mat& frame, const StrandMeasurement& m, int refresh_every = 25);
  // True when a patch is kept and the frame's patch at the same place matches it (normalised
  // cross-correlation ≥ min_correlation; for a featureless patch, the same mean level within
  // 10 % of the data range).
  bool SeesNozzle(const cv::Mat& frame, double min_correlation = 0.7) const;
  bool empty() const { return patch_.empty(); }
  const cv::Rect& patch_rect() const { return rect_; }

 private:
  MeasureTarget target_;
  cv::Mat patch_;  // 32-bit float grey
  cv::Rect rect_;
  int calls_since_refresh_ = 0;
};

}  // namespace clogscope::vision
