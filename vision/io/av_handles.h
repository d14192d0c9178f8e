#pragma once

// Owning handles for FFmpeg's codec objects and swscale's converters, for vision/io's encoders and
// decoders (internal: a .cc that includes it includes libavcodec and libswscale).
#include <memory>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libswscale/swscale.h>
}

namespace clogscope::vision {

struct AvCodecContextFree {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct AvFrameFree {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct AvPacketFree {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct SwsContextFree {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};
using AvCodecContextPtr = std::unique_ptr<AVCodecContext, AvCodecContextFree>;
using AvFramePtr = std::unique_ptr<AVFrame, AvFrameFree>;
using AvPacketPtr = std::unique_ptr<AVPacket, AvPacketFree>;
using SwsContextPtr = std::unique_ptr<SwsContext, SwsContextFree>;

// `sws` made fit for the conversion asked (sws_getCachedContext: kept when it fits, else
// replaced); false when swscale cannot make one.
inline bool FitSws(SwsContextPtr* sws, int width, int height, AVPixelFormat from, AVPixelFormat to,
                   int flags) {
  sws->reset(sws_getCachedContext(sws->release(), width, height, from, width, height, to, flags,
                                  nullptr, nullptr, nullptr));
  return *sws != nullptr;
}

}  // namespace clogscope::vision
