#pragma once

// `clogscope calibrate`: the pixel scale from pin gauges or a stage micrometer.

#include <optional>
#include <string>
#include <vector>

#include "calib/pixel_scale.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunCalibrate(int argc, char** argv);

struct CalibrateCommandOptions {
  std::string pins_csv;                        // pin gauges: image,diameter_um[,tolerance_um]
  std::vector<std::string> micrometer_images;  // or stage micrometer images
  double pitch_um = 0;                         // micrometer line pitch
  bool fit_distortion = false;                 // micrometer: second-order term
  std::optional<double>
      expect_scale_um_per_px;                // micrometer: refuse a pitch that gives far from this
  std::string out;                           // calibration YAML
  std::string plot;                          // residual plot PNG; empty: next to out
  vision::StrandMeasureOptions pin_measure;  // roi, polarity for the pins
  bool Validate(std::string* why) const;
};

struct CalibrateResult {
  calib::ScaleCalibration calibration;
  std::vector<std::string> inputs;  // files read
};

// Measures the reference images and fits the scale; writes nothing. Throws std::invalid_argument
// naming the image or CSV row for bad input (unreadable image, pin or lines not found, missing
// diameter, too few targets, a pitch that does not fit).
CalibrateResult ComputeCalibration(const CalibrateCommandOptions& options);

}  // namespace clogscope::apps
