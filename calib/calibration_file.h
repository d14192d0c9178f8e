#pragma once

#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "common/provenance.h"

namespace clogscope::calib {

// The calibration file format version this build writes and reads.
constexpr int kCalibrationFileVersion = 1;

// Writes the calibration as YAML under a temporary name, then renames: never a
// half-written file. `inputs` are the images (and CSV) it came from.
void WriteCalibrationFile(const std::string& path, const ScaleCalibration& cal,
                          const Provenance& provenance, const std::vector<std::string>& inputs);

// Reads a calibration file (also those written by earlier versions through OpenCV). Throws
// std::invalid_argument naming the file when it is unreadable, too deeply nested, of another format
// version, not usable, or holds a number that is not finite or a non-positive scale.
ScaleCalibration ReadCalibrationFile(const std::string& path);

}  // namespace clogscope::calib
