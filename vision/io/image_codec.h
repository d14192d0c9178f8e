#pragma once

// Image files in and out of memory, through Debian's codec libraries: PNG by libpng, JPEG by
// libjpeg-turbo (both report their errors to the caller rather than print them), TIFF, BMP and
// PGM/PPM by libavcodec, which the video reader links already.
#include <opencv2/core.hpp>
#include <string>
#include <string_view>

namespace clogscope::vision {

// An image file's pixels as stored: 8- or 16-bit; 1 channel (grey), 3 (BGR) or 4 (BGRA: a PNG
// with transparency). Empty, and *error says why, when the bytes are not a PNG, JPEG, TIFF, BMP or
// PGM/PPM, or the decoder refused them ("cannot decode image (libpng: IDAT: CRC error)"), or
// complained about them and filled in what it could not read ("damaged image (Premature end of
// JPEG file)": such a frame would be measured wrong), or its header gives no size or one over
// kMaxFramePixels (FrameSizeProblem), refused before decoding.
cv::Mat DecodeImage(std::string_view bytes, std::string* error);

// The image in the format of `extension` (".png", ".jpg"/".jpeg", ".tif"/".tiff", ".bmp",
// ".pgm", ".ppm"; case-insensitive): 8-bit grey or BGR in all of them, 16-bit grey or BGR in PNG,
// TIFF, PGM and PPM, BGRA in PNG. jpeg_quality is libjpeg's 1–100. Throws std::invalid_argument
// naming the extension when the format cannot hold the image.
std::string EncodeImage(const std::string& extension, const cv::Mat& image, int jpeg_quality = 95);

}  // namespace clogscope::vision
