#include "watch/frame_jpeg.h"

#include "vision/io/image_codec.h"
#include "vision/overlay/overlay.h"

namespace clogscope::watch {

std::vector<unsigned char> OverlayJpeg(const WatchSnapshot& s,
                                       const std::optional<calib::ScaleCalibration>& conversion) {
  std::vector<unsigned char> jpeg;
  if (s.frame.empty()) return jpeg;
  const std::string bytes = vision::EncodeImage(
      ".jpg",
      vision::DrawOverlay(s.frame, s.measurement, conversion ? conversion->scale_um_per_px : 0.0,
                          conversion ? conversion->edge_bias_px : 0.0),
      85);
  jpeg.assign(bytes.begin(), bytes.end());
  return jpeg;
}

std::shared_ptr<const std::vector<unsigned char>> OverlayJpegCache::Latest() {
  const WatchSnapshot s = board_->Read();
  if (s.frame.empty()) return nullptr;
  std::lock_guard<std::mutex> lock(mutex_);
  // A reader that took its snapshot before another drew a newer one gets the newer picture.
  if (!jpeg_ || s.sequence > sequence_) {
    jpeg_ = std::make_shared<const std::vector<unsigned char>>(OverlayJpeg(s, conversion_));
    sequence_ = s.sequence;
  }
  return jpeg_;
}

}  // namespace clogscope::watch
