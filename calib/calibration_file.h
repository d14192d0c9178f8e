#pragma once

#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "common/provenance.h"

namespace clogscope::calib {

// The calibration file format version this build writes and reads.
constexpr int kCalibrationFileVersion = 1;

// Writes the calibration as YAML (OpenCV FileStorage) under a temporary name, then renames: never a
// half-written file. `inputs` are the images (and CSV) it came from.
void WriteCalibrationFile(const std::string& path, const ScaleCalibration& cal,
                          const Provenance& provenance, const std::vector<std::string>& inputs);

// Reads a calibration file. Throws std::invalid_argument naming the file when it is unreadable, of
// another format version, not usable, or has a non-positive scale.
ScaleCalibration ReadCalibrationFile(const std::string& path);

}  // namespace clogscope::calib
