#include "vision/scene/scene_memory.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace clogscope::vision {
namespace {

cv::Mat GreyFloat(const cv::Mat& frame, const cv::Rect& r) {
  cv::Mat roi = frame(r), grey, out;
  if (roi.channels() == 3)
    cv::cvtColor(roi, grey, cv::COLOR_BGR2GRAY);
  else if (roi.channels() == 4)
    cv::cvtColor(roi, grey, cv::COLOR_BGRA2GRAY);
  else
    grey = roi;
  // Levels as fractions of full scale, so 8- and 16-bit frames compare alike.
  grey.convertTo(out, CV_32F, grey.depth() == CV_16U ? 1.0 / 65535 : 1.0 / 255);
  return out;
}

}  // namespace

void SceneMemory::Remember(const cv::Mat& frame, const StrandMeasurement& m, int refresh_every) {
  if (target_ != MeasureTarget::kStrand || !m.valid() || !m.has_geometry || frame.empty()) return;
  if (!patch_.empty() && ++calls_since_refresh_ < refresh_every) return;
  calls_since_refresh_ = 0;
  // The nozzle just above the tip: three strand widths across, one and a half high, ending a few
  // px above the tip so the strand itself is not in it.
  const double w = std::max(m.width_px, 12.0);
  const cv::Rect want(static_cast<int>(std::lround(m.tip_x_px - 1.5 * w)),
                      static_cast<int>(std::lround(m.tip_y_px - 3 - 1.5 * w)),
                      static_cast<int>(std::lround(3 * w)), static_cast<int>(std::lround(1.5 * w)));
  const cv::Rect r = want & cv::Rect(0, 0, frame.cols, frame.rows);
  if (r.width < 8 || r.height < 8) {
    patch_.release();
    return;
  }
  rect_ = r;
  patch_ = GreyFloat(frame, r);
}

bool SceneMemory::SeesNozzle(const cv::Mat& frame, double min_correlation) const {
  if (patch_.empty() || frame.empty() || (rect_ & cv::Rect(0, 0, frame.cols, frame.rows)) != rect_)
    return false;
  const cv::Mat now = GreyFloat(frame, rect_);
  cv::Scalar m0, s0, m1, s1;
  cv::meanStdDev(patch_, m0, s0);
  cv::meanStdDev(now, m1, s1);
  // A flat patch (an evenly lit nozzle face) carries no pattern to correlate: compare levels.
  if (s0[0] < 0.01 || s1[0] < 0.01) return s0[0] < 0.02 && std::abs(m0[0] - m1[0]) < 0.1;
  cv::Mat score;
  cv::matchTemplate(now, patch_, score, cv::TM_CCOEFF_NORMED);
  return score.at<float>(0, 0) >= min_correlation;
}

}  // namespace clogscope::vision
