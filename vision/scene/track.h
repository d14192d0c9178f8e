#pragma once

#include <opencv2/core.hpp>
#include <optional>

#include "vision/io/frame_source.h"
#include "vision/scene/codec_doubt.h"
#include "vision/scene/cylinder_memory.h"
#include "vision/scene/scene.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

// Per-video state for measuring a strand frame after frame: after the first frame it looks for the
// strand where it was (its fitted edges, tip and band) and falls back to full scene finding when
// that fails, so a steady scene costs only the caliper fits. The band also stays where it was, so
// frame-to-frame changes of the width are the strand's and not a different choice of calipers.
class StrandTracker {
 public:
  // Throws std::invalid_argument when the options do not validate.
  explicit StrandTracker(const StrandMeasureOptions& options);

  // Frames from a video x264 encoded (encoder.found): every width carries the codec's doubt
  // (codec_doubt.h); other encoders, or an FFmpeg without libx264 (X264RoundTrip::Available):
  // none.
  void SetEncoder(const X264Settings& encoder);
  // Measures one frame (as MeasureStrand does).
  StrandMeasurement Measure(const cv::Mat& frame);
  // Measures a frame as a source read it, in its own luma range (which then holds for images
  // given to Measure after it).
  StrandMeasurement Measure(const InputFrame& frame);

  // Forgets the strand and the codec's checks: the next frame is searched from scratch.
  void Reset() {
    tracking_ = false;
    short_straight_frames_ = 0;
    cylinders_.Clear();
    if (codec_) codec_->Reset();
  }

  int full_detections() const { return full_detections_; }
  int tracked_frames() const { return tracked_frames_; }
  // A filament's calipers' lit cylinders, kept as templates (cylinder_memory.h).
  const CylinderMemory& cylinders() const { return cylinders_; }

 private:
  StrandMeasurement Detect(const cv::Mat& frame);
  bool Follow(const cv::Mat& frame, StrandMeasurement* out);
  void Remember(const SceneResult& scene, const StrandMeasurement& m, cv::Size frame_size);

  StrandMeasureOptions options_;
  bool tracking_ = false;
  SceneResult scene_;         // the last good scene; its geometry holds the fitted edge lines
  CylinderMemory cylinders_;  // a filament's calipers' lit cylinders, fitted as templates
  double width_px_ = 0;
  cv::Size frame_size_;
  int full_detections_ = 0;
  int tracked_frames_ = 0;
  int short_straight_frames_ = 0;  // a filament's: frames in a row on a short straight part
  std::optional<CodecDoubt> codec_;
};

}  // namespace clogscope::vision
