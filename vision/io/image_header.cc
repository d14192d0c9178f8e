#include "vision/io/image_header.h"

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace clogscope::vision {
namespace {

class Bytes {
 public:
  explicit Bytes(std::string_view s) : s_(s) {}
  size_t size() const { return s_.size(); }
  bool Has(size_t i, size_t n) const { return i <= s_.size() && n <= s_.size() - i; }
  unsigned At(size_t i) const { return static_cast<unsigned char>(s_[i]); }
  // Unsigned integers of n bytes at i, big- or little-endian; 0 when out of range.
  unsigned long long Get(size_t i, int n, bool little) const {
    if (!Has(i, static_cast<size_t>(n))) return 0;
    unsigned long long v = 0;
    for (int k = 0; k < n; ++k)
      v |= static_cast<unsigned long long>(At(i + k)) << 8 * (little ? k : n - 1 - k);
    return v;
  }
  bool Starts(const char* magic, size_t n) const {
    return s_.size() >= n && !std::memcmp(s_.data(), magic, n);
  }

 private:
  std::string_view s_;
};

ImageHeader Png(const Bytes& b) {
  ImageHeader h{"png"};
  if (b.Has(12, 12) && b.Get(12, 4, false) == 0x49484452) {  // "IHDR"
    h.width_px = static_cast<long long>(b.Get(16, 4, false));
    h.height_px = static_cast<long long>(b.Get(20, 4, false));
  }
  return h;
}

ImageHeader Jpeg(const Bytes& b) {
  ImageHeader h{"jpeg"};
  size_t i = 2;
  while (b.Has(i, 4)) {
    if (b.At(i) != 0xFF) break;
    const unsigned marker = b.At(i + 1);
    if (marker == 0xFF) {  // fill byte
      ++i;
      continue;
    }
    // Frame headers SOF0..SOF15, but DHT (C4), JPG (C8) and DAC (CC): P, height, width.
    if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC) {
      h.height_px = static_cast<long long>(b.Get(i + 5, 2, false));
      h.width_px = static_cast<long long>(b.Get(i + 7, 2, false));
      break;
    }
    if (marker == 0xDA || marker == 0xD9) break;  // scan or end before any frame header
    i += 2 + b.Get(i + 2, 2, false);
  }
  return h;
}

ImageHeader Tiff(const Bytes& b) {
  ImageHeader h{"tiff"};
  const bool little = b.At(0) == 'I';
  const bool big_tiff = b.Get(2, 2, little) == 43;
  // Classic: 4-byte offset, 2-byte entry count, 12-byte entries with a 4-byte value field.
  // BigTIFF: 8-byte offset, 8-byte count, 20-byte entries with an 8-byte value field.
  const size_t ifd = b.Get(big_tiff ? 8 : 4, big_tiff ? 8 : 4, little);
  const int count_size = big_tiff ? 8 : 2, entry_size = big_tiff ? 20 : 12;
  const unsigned long long n = b.Get(ifd, count_size, little);
  for (unsigned long long k = 0; k < n && k < 4096; ++k) {
    const size_t e = ifd + count_size + k * entry_size;
    if (!b.Has(e, entry_size)) break;
    const unsigned tag = b.Get(e, 2, little), type = b.Get(e + 2, 2, little);
    const size_t value_at = e + (big_tiff ? 12 : 8);
    const long long v =
        static_cast<long long>(type == 3 ? b.Get(value_at, 2, little) : b.Get(value_at, 4, little));
    if (tag == 256) h.width_px = v;
    if (tag == 257) h.height_px = v;
  }
  return h;
}

ImageHeader Bmp(const Bytes& b) {
  ImageHeader h{"bmp"};
  const unsigned long long info = b.Get(14, 4, true);
  if (info == 12) {  // OS/2 BITMAPCOREHEADER: 16-bit sizes
    h.width_px = static_cast<long long>(b.Get(18, 2, true));
    h.height_px = static_cast<long long>(b.Get(20, 2, true));
  } else if (b.Has(18, 8)) {  // signed 32-bit; a negative height means top-down rows
    h.width_px = std::abs(static_cast<long long>(static_cast<int32_t>(b.Get(18, 4, true))));
    h.height_px = std::abs(static_cast<long long>(static_cast<int32_t>(b.Get(22, 4, true))));
  }
  return h;
}

ImageHeader Pnm(std::string_view s) {
  ImageHeader h{"pnm"};
  long long values[2] = {0, 0};
  size_t i = 2;
  for (int k = 0; k < 2; ++k) {
    while (i < s.size()) {  // whitespace and comments
      if (s[i] == '#') {
        while (i < s.size() && s[i] != '\n') ++i;
      } else if (std::isspace(static_cast<unsigned char>(s[i]))) {
        ++i;
      } else {
        break;
      }
    }
    long long v = 0;
    size_t digits = 0;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i])) && digits < 12) {
      v = v * 10 + (s[i++] - '0');
      ++digits;
    }
    if (digits == 0) return h;
    values[k] = v;
  }
  h.width_px = values[0];
  h.height_px = values[1];
  return h;
}

}  // namespace

ImageHeader ParseImageHeader(std::string_view bytes) {
  const Bytes b(bytes);
  if (b.Starts("\x89PNG\r\n\x1a\n", 8)) return Png(b);
  if (b.size() >= 3 && b.At(0) == 0xFF && b.At(1) == 0xD8 && b.At(2) == 0xFF) return Jpeg(b);
  if (b.Starts("II*\0", 4) || b.Starts("MM\0*", 4) || b.Starts("II+\0", 4) || b.Starts("MM\0+", 4))
    return Tiff(b);
  if (b.Starts("BM", 2)) return Bmp(b);
  if (b.size() >= 3 && bytes[0] == 'P' && bytes[1] >= '1' && bytes[1] <= '6' &&
      std::isspace(static_cast<unsigned char>(bytes[2])))
    return Pnm(bytes);
  return ImageHeader();
}

bool JpegEndsWhole(std::string_view bytes) {
  size_t end = bytes.size();
  // Padding after the marker: zeros (AVI chunks, drivers) or a line end (multipart streams).
  while (end > 0 && (bytes[end - 1] == '\0' || bytes[end - 1] == '\r' || bytes[end - 1] == '\n'))
    --end;
  return end >= 4 && static_cast<unsigned char>(bytes[end - 2]) == 0xFF &&
         static_cast<unsigned char>(bytes[end - 1]) == 0xD9;
}

}  // namespace clogscope::vision
