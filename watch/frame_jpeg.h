#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "watch/live_watch.h"

namespace clogscope::watch {

// The snapshot's frame with its measurement drawn on it (vision::DrawOverlay, with the width in µm
// when there is a scale), as JPEG bytes: what /frame.jpg serves and the MQTT camera shows. Empty
// when there is no frame yet.
std::vector<unsigned char> OverlayJpeg(const WatchSnapshot& snapshot,
                                       const std::optional<calib::ScaleCalibration>& conversion);

// The board's latest overlay JPEG, drawn once per published frame however many readers ask for
// it (each of the page's clients, the MQTT camera): a 720p picture costs milliseconds to draw and
// encode. Safe to call from any thread.
class OverlayJpegCache {
 public:
  OverlayJpegCache(const WatchBoard* board, std::optional<calib::ScaleCalibration> conversion)
      : board_(board), conversion_(std::move(conversion)) {}
  // Null when there is no frame yet.
  std::shared_ptr<const std::vector<unsigned char>> Latest();

 private:
  const WatchBoard* board_;
  std::optional<calib::ScaleCalibration> conversion_;
  std::mutex mutex_;  // held while drawing: a second reader of the same frame waits for it
  long long sequence_ = -1;
  std::shared_ptr<const std::vector<unsigned char>> jpeg_;
};

// A camera as the watch's outputs see it (the HTTP server, the MQTT publisher): its name in a farm
// (empty for a single watch), its board, its scale, and its overlay pictures, shared by every
// output so that each frame is drawn once.
struct CameraFeed {
  std::string name;  // [A-Za-z0-9_-]+ in a farm
  const WatchBoard* board = nullptr;
  std::optional<calib::ScaleCalibration> conversion;
  std::shared_ptr<OverlayJpegCache> frames;  // null: the output draws its own
};

}  // namespace clogscope::watch
