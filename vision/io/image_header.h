#pragma once

// What an image file's first bytes say it is, read without decoding it: the tool decodes only the
// formats cameras write, and refuses a frame too large to measure before a decoder allocates it
// (a 32-byte WebP bitstream may claim 16384×12164 pixels).
#include <string>
#include <string_view>

namespace clogscope::vision {

struct ImageHeader {
  std::string format;      // "png", "jpeg", "tiff", "bmp", "pnm"; empty: none of these
  long long width_px = 0;  // 0 when the header does not say (cut short or damaged)
  long long height_px = 0;
};

// The header of an image file's bytes (the whole file: a TIFF's first directory may lie after
// the pixels).
ImageHeader ParseImageHeader(std::string_view bytes);

// True when a JPEG's bytes end with its end-of-image marker (FF D9), padding after it allowed
// (zeros, a line end): a JPEG cut short ends without one, and decoders fill in what is missing
// without a word.
bool JpegEndsWhole(std::string_view bytes);

}  // namespace clogscope::vision
