#include "vision/io/encoder_note.h"

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>

#include "vision/io/x264_round_trip.h"

namespace clogscope::vision {

X264Settings ReadX264Settings(const std::string& path, size_t max_bytes) {
  X264Settings out;
  std::ifstream in(path, std::ios::binary);
  if (!in) return out;
  std::string data(max_bytes, '\0');
  in.read(data.data(), static_cast<std::streamsize>(max_bytes));
  data.resize(static_cast<size_t>(in.gcount()));
  const size_t note = data.find("x264 - core");
  if (note == std::string::npos) return out;
  out.found = true;
  // The note is one NUL-terminated string.
  const std::string text = data.substr(note, data.find('\0', note) - note);
  const auto value = [&](const char* key) -> const char* {
    const size_t at = text.find(std::string(" ") + key + "=");
    return at == std::string::npos ? nullptr
                                   : text.c_str() + at + 2 + std::char_traits<char>::length(key);
  };
  if (const char* aq = value("aq")) {
    char* end = nullptr;
    out.aq_mode = static_cast<int>(std::strtol(aq, &end, 10));
    out.aq_strength = *end == ':' ? std::strtod(end + 1, nullptr) : -1;
  }
  if (const char* crf = value("crf")) out.crf = std::strtod(crf, nullptr);
  return out;
}

std::string X264EdgeAdvice(const X264Settings& s) {
  if (!s.found || s.aq_mode <= 0 || s.aq_strength == 0 ||
      (s.crf >= 0 && s.crf <= kX264MaxCrfForEdges))
    return "";
  return fmt::format(
      "H.264 from x264 with adaptive quantisation (aq-mode {}{}): it can move a lit strand's edges "
      "by 0.2-0.3 px ({}); record with -aq-mode 0 or -crf {:.0f} or less for measurement",
      s.aq_mode, s.crf >= 0 ? fmt::format(", CRF {:.0f}", s.crf) : std::string(),
      X264RoundTrip::Available()
          ? "each width's σ carries what a second pass through x264 shows, and fewer are valid"
          : "this FFmpeg has no libx264 for a second pass, and the widths' σ does not show it",
      kX264MaxCrfForEdges);
}

}  // namespace clogscope::vision
