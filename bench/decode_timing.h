#pragma once

// What the benches time against: decoding alone, and a median of alternating passes.
#include <string>
#include <vector>

namespace clogscope::bench {

// Frames per second of decoding `path` alone with clogscope's reader (VideoDecoder) on `threads`
// decoder threads (0: FFmpeg's choice).
double DecodeOnlyFps(const std::string& path, int threads);

// The median of passes (the middle one of an odd count); NaN when there are none.
double Median(std::vector<double> v);

}  // namespace clogscope::bench
