#pragma once

// The pixel scale from images of reference targets: pin gauges or a stage micrometer. The images
// are measured here (vision: the pin as a filament, the micrometer's lines) and the scale fitted
// by calib/ (which speaks plain structs and no OpenCV, so measuring images cannot live there).

#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

struct TargetCalibrationOptions {
  std::string pins_csv;                        // pin gauges: image,diameter_um[,tolerance_um]
  std::vector<std::string> micrometer_images;  // or stage micrometer images
  double pitch_um = 0;                         // micrometer line pitch, µm
  bool fit_distortion = false;                 // micrometer: second-order term
  // Micrometer: refuse a pitch that gives a scale more than 25 % from this (µm/px).
  std::optional<double> expect_scale_um_per_px;
  vision::StrandMeasureOptions pin_measure;  // roi, polarity for the pins (roi for the micrometer)
  bool Validate(std::string* why) const;
};

struct TargetCalibration {
  calib::ScaleCalibration calibration;
  std::vector<std::string> inputs;  // files read
  std::vector<std::string> notes;   // one line per target measured, for the log
};

// Measures the reference images and fits the scale; writes nothing. Throws std::invalid_argument
// naming the image or CSV row for bad input (unreadable image, pin or lines not found, missing
// diameter, too few targets, a pitch that does not fit, a scale no microscope has). A fit that is
// not usable comes back with calibration.usable false.
TargetCalibration CalibrateFromTargets(const TargetCalibrationOptions& options);

}  // namespace clogscope::pipeline
