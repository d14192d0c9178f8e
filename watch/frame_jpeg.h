#pragma once

#include <optional>
#include <vector>

#include "calib/pixel_scale.h"
#include "watch/live_watch.h"

namespace clogscope::watch {

// The snapshot's frame with its measurement drawn on it (vision::DrawOverlay, with the width in µm
// when there is a scale), as JPEG bytes: what /frame.jpg serves and the MQTT camera shows. Empty
// when there is no frame yet.
std::vector<unsigned char> OverlayJpeg(const WatchSnapshot& snapshot,
                                       const std::optional<calib::ScaleCalibration>& conversion);

}  // namespace clogscope::watch
