#pragma once

// TIFF, BMP and PGM/PPM through libavcodec's image codecs, for image_codec.cc (internal to
// vision/io).
#include <opencv2/core.hpp>
#include <string>
#include <string_view>

namespace clogscope::vision {

// format: "tiff", "bmp" or "pnm" (as ParseImageHeader names it). The pixels as stored: 8- or
// 16-bit grey or BGR (an alpha channel is dropped); empty and *error on failure.
cv::Mat DecodeWithLibav(std::string_view bytes, const std::string& format, std::string* error);

// format: "tiff", "bmp" or "pnm" (PGM for grey, PPM for colour). image: 8- or 16-bit grey or BGR
// (16-bit not in BMP). Throws std::runtime_error when the encoder fails.
std::string EncodeWithLibav(const std::string& format, const cv::Mat& image);

}  // namespace clogscope::vision
