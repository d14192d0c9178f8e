#pragma once

// What the benches time against: decoding alone.
#include <string>

namespace clogscope::bench {

// Frames per second of decoding `path` alone with clogscope's reader (VideoDecoder) on `threads`
// decoder threads (0: FFmpeg's choice).
double DecodeOnlyFps(const std::string& path, int threads);

}  // namespace clogscope::bench
