#pragma once

#include <opencv2/core.hpp>

namespace clogscope::vision {

// The largest value the frame's data can hold: 255 for 8 bit; for 16 bit, 2^b − 1 for the smallest
// b (8…16) that holds its largest pixel (12-bit cameras write 16-bit files).
double DataMax(const cv::Mat& image);

}  // namespace clogscope::vision
