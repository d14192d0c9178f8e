#include "vision/io/data_range.h"

namespace clogscope::vision {

double DataMax(const cv::Mat& image) {
  if (image.depth() != CV_16U) return 255.0;
  double lo = 0, hi = 0;
  cv::minMaxLoc(image.reshape(1), &lo, &hi);
  // The smallest bit depth of 8 to 16 that holds the largest value: 10- and 12-bit cameras write
  // 16-bit files whose top bits are always zero.
  int bits = 8;
  while (bits < 16 && hi > (1 << bits) - 1) ++bits;
  return (1 << bits) - 1.0;
}

}  // namespace clogscope::vision
