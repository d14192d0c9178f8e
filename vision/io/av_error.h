#pragma once

// FFmpeg's errors as the tool takes them, for vision/io's readers, writers and codecs (internal:
// a .cc that includes it includes libavutil).
#include <string>

extern "C" {
#include <libavutil/error.h>
#include <libavutil/log.h>
}

namespace clogscope::vision {

// FFmpeg prints nothing (x264 would report its settings on every open): its errors come back as
// codes, which the tool words itself. Every caller of FFmpeg's codecs calls this first.
inline void QuietFfmpeg() { av_log_set_level(AV_LOG_QUIET); }

inline std::string AvError(int code) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(code, buf, sizeof(buf));
  return buf;
}

}  // namespace clogscope::vision
