// A frame from bytes: decoding (PNG, JPEG, TIFF, … by content) and, when it decodes to something
// small, the whole measurement of it.
#include <opencv2/core/utils/logger.hpp>
#include <stdexcept>

#include "fuzz/fuzz_util.h"
#include "vision/io/video_io.h"
#include "vision/scene/strand_measure.h"

// As the tool runs (apps/main.cc): OpenCV's own log lines off, the tool reports instead.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = clogscope::fuzz::AsFile(data, size, ".img");
  std::string error;
  const cv::Mat img = clogscope::vision::ReadImage(path, &error);
  if (img.empty() || img.total() > 640 * 480) return 0;
  try {
    clogscope::vision::MeasureStrand(img, clogscope::vision::StrandMeasureOptions());
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
