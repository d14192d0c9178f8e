#pragma once

#include <opencv2/core.hpp>

namespace clogscope::vision {

// The largest value the frame's data can hold: 255 for 8 bit; for 16 bit, 2^b − 1 for the smallest
// b (8…16) that holds its largest pixel (12-bit cameras write 16-bit files).
double DataMax(const cv::Mat& image);

// Where a frame's black and white lie. Images and full-range ("JPEG") video use the data's whole
// range; limited-range ("TV", MPEG) video luma puts black at 16 and white at 235 of 255 (scaled to
// deeper data), and a codec's ringing reaches beyond both.
enum class LumaRange { kFull, kLimited };
inline constexpr double kLimitedBlack8 = 16, kLimitedWhite8 = 235;

}  // namespace clogscope::vision
