#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "calib/pixel_scale.h"
#include "pipeline/frame_rows.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

// `measure --overlay` for one input: each frame is drawn and written as soon as its row is final,
// at once without outlier flags, else once the frames its outlier verdict depends on are in. So
// at most vision::kWidthOutlierHalfWindow + 1 frames wait, however long the video.
class OverlayWriter {
 public:
  OverlayWriter(std::string dir, bool from_video, bool flag_outliers,
                std::optional<calib::ScaleCalibration> conversion, std::set<std::string>* names);
  // Keeps rows[row]'s frame until its row is final.
  void Add(size_t row, const cv::Mat& image);
  // Writes the frames whose rows are final among `rows`; with `all`, every frame kept (the rows'
  // outlier flags are set by then).
  void WriteReady(const std::vector<FrameRow>& rows, bool all);
  int written() const { return written_; }
  int held_peak() const { return held_peak_; }
  // The first write that failed (the writer stops there); empty when none did.
  const std::string& error() const { return error_; }

 private:
  void Write(const FrameRow& row, const vision::StrandMeasurement& m, const cv::Mat& image);

  std::string dir_;
  bool from_video_, flag_outliers_;
  std::optional<calib::ScaleCalibration> conversion_;
  std::set<std::string>* names_;
  std::vector<std::pair<size_t, cv::Mat>> held_;  // by row, in row order
  int written_ = 0, held_peak_ = 0;
  std::string error_;
};

}  // namespace clogscope::pipeline
