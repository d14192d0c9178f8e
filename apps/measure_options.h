#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "pipeline/measure_inputs.h"

namespace clogscope::apps {

// The measurement options `measure` and `watch` share (scale or calibration, ROI, band, caliper,
// polarity, target, blur and contrast limits, shading), as typed on the command line.
struct MeasureCliText {
  std::string roi, polarity = "auto", target = "strand", calib_path;
  double min_contrast_levels = 0;
  bool no_shading = false;
};

// Adds those options to `app`, writing into *o and *text.
void AddMeasurementOptions(CLI::App& app, pipeline::MeasureInputsOptions* o, MeasureCliText* text);

// After parsing: the ROI, calibration file, polarity, target, contrast and shading into *o (the
// band stays to ResolveBand). Throws std::invalid_argument naming the option or file.
void ApplyMeasurementOptions(const CLI::App& app, const MeasureCliText& text,
                             pipeline::MeasureInputsOptions* o);

}  // namespace clogscope::apps
