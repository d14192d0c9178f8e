#pragma once

#include <cstddef>
#include <string>

namespace clogscope::vision {

// The settings x264 writes into every H.264 stream it encodes (a user-data SEI: "x264 - core N …
// options: … aq=MODE:STRENGTH … crf=F …"), read from a file's first bytes.
struct X264Settings {
  bool found = false;  // the file holds x264's note
  // Adaptive quantisation: off at mode 0 or strength 0 (x264 writes "aq=1:0.00" for -aq-mode 0);
  // -1 not told (no advice then).
  int aq_mode = -1;
  double aq_strength = -1;
  double crf = -1;  // constant rate factor; -1 not told (another rate control)
};

// Looks through the first max_bytes of the file at `path` (a URL or a missing file: not found).
X264Settings ReadX264Settings(const std::string& path, size_t max_bytes = 1 << 20);

// Edges move under x264's adaptive quantisation: on rendered lit strands 0.2–0.3 px a side at its
// defaults (aq-mode 1, CRF 23), and not with -aq-mode 0 or at CRF ≤ 18 (docs/accuracy.md). A
// one-line advice when the settings are those that move them, else empty.
std::string X264EdgeAdvice(const X264Settings& settings);
inline constexpr double kX264MaxCrfForEdges = 18.0;

}  // namespace clogscope::vision
