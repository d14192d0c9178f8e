// Calibration files.
#include <stdexcept>

#include "calib/calibration_file.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string path = clogscope::fuzz::AsFile(data, size, ".yaml");
  try {
    clogscope::calib::ReadCalibrationFile(path);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
