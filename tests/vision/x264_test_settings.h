#pragma once

#include "vision/io/encoder_note.h"

namespace clogscope::vision {

// The note x264 writes into a stream at this CRF with its default adaptive quantisation (mode 1,
// strength 1), as the codec's tests want it.
inline X264Settings X264AtCrf(double crf) {
  X264Settings s;
  s.found = true;
  s.crf = crf;
  s.aq_mode = 1;
  s.aq_strength = 1.0;
  return s;
}

}  // namespace clogscope::vision
