#include "pipeline/frame_overlays.h"

#include <algorithm>
#include <filesystem>

#include "vision/io/video_io.h"
#include "vision/overlay/overlay.h"

namespace clogscope::pipeline {

OverlayWriter::OverlayWriter(std::string dir, bool from_video, bool flag_outliers,
                             std::optional<calib::ScaleCalibration> conversion,
                             std::set<std::string>* names)
    : dir_(std::move(dir)),
      from_video_(from_video),
      flag_outliers_(flag_outliers),
      conversion_(std::move(conversion)),
      names_(names) {}

void OverlayWriter::Add(size_t row, const cv::Mat& image) {
  if (!error_.empty()) return;
  held_.emplace_back(row, image);
  held_peak_ = std::max(held_peak_, static_cast<int>(held_.size()));
}

void OverlayWriter::WriteReady(const std::vector<FrameRow>& rows, bool all) {
  size_t done = 0;
  for (; done < held_.size() && error_.empty(); ++done) {
    const size_t row = held_[done].first;
    if (all || !flag_outliers_) {
      Write(rows[row], rows[row].m, held_[done].second);
      continue;
    }
    // The verdict needs the rows up to `half` ahead (the outlier window of measure); it is the one
    // the whole input will give, as it looks no further.
    const size_t half = vision::kWidthOutlierHalfWindow;
    if (rows.size() <= row + half) break;
    const size_t first = row >= half ? row - half : 0;
    std::vector<vision::StrandMeasurement> window;
    for (size_t i = first; i <= row + half; ++i) window.push_back(rows[i].m);
    vision::FlagWidthOutliers(window, vision::kWidthOutlierHalfWindow);
    Write(rows[row], window[row - first], held_[done].second);
  }
  held_.erase(held_.begin(), held_.begin() + static_cast<std::ptrdiff_t>(done));
  if (!error_.empty()) held_.clear();
}

void OverlayWriter::Write(const FrameRow& row, const vision::StrandMeasurement& m,
                          const cv::Mat& image) {
  const std::string name =
      (std::filesystem::path(dir_) / OverlayName(row, from_video_, names_)).string();
  try {
    vision::WriteImageAtomically(
        name, vision::DrawOverlay(image, m, conversion_ ? conversion_->scale_um_per_px : 0.0,
                                  conversion_ ? conversion_->edge_bias_px : 0.0));
    ++written_;
  } catch (const std::exception& e) {
    // Overlays are a view of the table: without them the measurement still stands.
    error_ = e.what();
  }
}

}  // namespace clogscope::pipeline
