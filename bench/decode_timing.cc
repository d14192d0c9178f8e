#include "bench/decode_timing.h"

#include <algorithm>
#include <chrono>
#include <cmath>

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

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

}  // namespace clogscope::bench
