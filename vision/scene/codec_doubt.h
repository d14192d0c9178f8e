#pragma once

#include <cmath>
#include <opencv2/core.hpp>

#include "vision/io/x264_round_trip.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

// What a lossy codec did to a width, which no single frame's residuals show: x264's adaptive
// quantisation moves a lit strand's edges by tenths of a pixel, smoothly, so the edge model fits
// the moved edge as well as the true one, and where the choice of object, channel or tip is
// close it can tip that choice. A second pass through the same encoder does the same again by
// about as much; how far the width moves is taken as one σ of what the first pass may have done.
// The second pass also re-quantises the frame's noise, which moves each caliper at random; that
// part, from the calipers' own shifts, is not the codec's doubt.
struct CodecCheck {
  // The check's outcome: kNotChecked when the frame measured afresh gave no width (the tracker's
  // may still have), or is not 8-bit grey or colour: nothing known about the codec.
  enum class Outcome { kNotChecked, kDone, kLostInSecondPass };
  Outcome outcome = Outcome::kNotChecked;
  bool done() const { return outcome == Outcome::kDone; }
  double shift_px = 0;  // the second pass's width minus the frame's
  // The shift's standard error from its calipers' scatter (-1: too few calipers in both).
  double shift_sigma_px = -1;
  // The doubt of a second pass on a grid half a macroblock off the stream's (-1: none done).
  double off_grid_doubt_px = -1;
  FrameStatus second_pass_status = FrameStatus::kNoStrand;

  // The codec's doubt: the shift with its noise taken out (all of it when the noise is unknown),
  // or the pass off the stream's grid's, whichever is larger.
  double DoubtPx() const;
};

// Measures `frame` afresh, passes the region from the strand's tip to the end of its band (with
// a margin, on the codec's 16-px macroblock grid) once more through `round_trip`, and measures
// that afresh too. Its calipers are paired with the first measurement's by their place along the
// axis. Then the same with the region half a macroblock up and to the left (within the frame),
// off the grid.
CodecCheck CheckCodec(const cv::Mat& frame, const StrandMeasureOptions& options,
                      X264RoundTrip* round_trip);

// A stream's codec doubt for frame after frame: checked (CheckCodec) on the first frame with a
// width and on every check_every_frames-th after it, and given to every frame with a width as the
// RMS of the checks so far: a steady scene's codec acts on it the same way from frame to frame,
// while one check's shift is noisy. A check that gave no shift (the frame measured afresh gave no
// width, or its second pass none) is tried again on the 1st, 2nd, 4th … frame with a width after
// it; until one gives a shift, the widths carry none. (A second pass that loses the strand says
// little of the stream's codec: on the matrix's colour seed 16 it came out `saturated` on frames
// the stream measured within 0.02 px, and refusing such frames cost 12 frames within the
// tolerance over the four adversarial matrices and caught no wrong one.)
// Every 100th: a check is two passes (on the stream's grid and off it, ~12 ms on a 720p strand),
// and one every 100 frames costs what one pass every 50 did.
inline constexpr int kCodecCheckEveryFrames = 100;
class CodecDoubt {
 public:
  // Throws std::invalid_argument when check_every_frames < 1.
  CodecDoubt(const X264Settings& encoder, int check_every_frames = kCodecCheckEveryFrames);
  // For a frame with a width: checks it when due, then adds the doubt to m (codec_sigma_px, and
  // with it model_sigma_px and width_sigma_px) and judges m's precision again.
  void Apply(const cv::Mat& frame, const StrandMeasureOptions& options, StrandMeasurement* m);
  // Forgets the checks (another scene).
  void Reset();
  int checks() const { return checks_; }
  int attempts() const { return attempts_; }  // checks tried, with a shift or not
  double doubt_px() const { return checks_ > 0 ? std::sqrt(sum2_px2_ / checks_) : 0.0; }

 private:
  X264RoundTrip round_trip_;
  int every_;
  int until_check_ = 0;  // frames with a width to go before the next check (0: this one)
  int failed_ = 0;       // checks in a row that gave no shift
  int attempts_ = 0;
  int checks_ = 0;  // checks that gave a shift
  double sum2_px2_ = 0;
};

}  // namespace clogscope::vision
