#include "bench/decode_timing.h"

#include <chrono>

#include "vision/io/video_decoder.h"

namespace clogscope::bench {

double DecodeOnlyFps(const std::string& path, int threads) {
  vision::VideoDecoder decoder(path, threads);
  vision::DecodedFrame frame;
  int n = 0;
  const auto t0 = std::chrono::steady_clock::now();
  while (decoder.Read(&frame)) ++n;
  return n / std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace clogscope::bench
