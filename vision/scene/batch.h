#pragma once

#include <functional>
#include <string>

#include "vision/io/frame_source.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

// Reads every frame of `source`, measures it and hands frame and result to `on_frame` in frame
// order. Decoding runs on a thread of its own, a few frames ahead of measurement, so the two
// overlap. An undecodable frame is passed on with status kUnreadable. Returns the frames read.
// `stop` (optional) is polled between frames; when it returns true reading ends early.
int MeasureFrames(FrameSource& source, const StrandMeasureOptions& options,
                  const std::function<void(InputFrame&, StrandMeasurement&)>& on_frame,
                  const std::function<bool()>& stop = nullptr);

}  // namespace clogscope::vision
