#pragma once

// FFmpeg's text for an error code, for the readers and the x264 round trip. Internal to
// vision/io (a .cc that includes it includes libavutil).
#include <string>

extern "C" {
#include <libavutil/error.h>
}

namespace clogscope::vision {

inline std::string AvError(int code) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(code, buf, sizeof(buf));
  return buf;
}

}  // namespace clogscope::vision
