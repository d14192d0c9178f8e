#pragma once

#include <opencv2/core.hpp>

#include "vision/io/encoder_note.h"

namespace clogscope::vision {

// Passes an image once more through x264 (libavcodec's libx264 encoder, then its H.264 decoder):
// what a second generation of a stream's own encoder does to it. With the stream's CRF (23 when
// not told) and adaptive quantisation, the rest at x264's defaults; the image is coded as the key
// frame of a short steady run, as a steady scene's strand is (the frames between key frames code
// little but noise, and x264 gives a key frame they copy a finer quantiser than a lone one).
class X264RoundTrip {
 public:
  explicit X264RoundTrip(const X264Settings& settings);
  // This FFmpeg has libx264's encoder and an H.264 decoder (Debian's does).
  static bool Available();

  // image: 8-bit grey (coded as luma, with neutral chroma) or BGR (BT.601 4:2:0, as an RGB
  // recording is), even width and height. Returns the decoded image in the same form. Throws
  // std::runtime_error when the encoder or decoder fails (FFmpeg built without libx264).
  cv::Mat Apply(const cv::Mat& image);

 private:
  X264Settings settings_;
};

}  // namespace clogscope::vision
