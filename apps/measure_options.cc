#include "apps/measure_options.h"

#include "apps/cli_util.h"
#include "calib/calibration_file.h"
#include "common/path_check.h"
#include "pipeline/band.h"

namespace clogscope::apps {

void AddMeasurementOptions(CLI::App& app, pipeline::MeasureInputsOptions* o, MeasureCliText* text) {
  app.add_option("--scale-um-per-px", o->scale_um_per_px,
                 "Pixel scale; widths in µm need it or --calib");
  app.add_option("--calib", text->calib_path,
                 "Calibration file from clogscope calibrate (scale and edge bias)");
  app.add_option("--roi", text->roi, "Search only inside x,y,w,h (px)");
  app.add_option("--band-start-um", o->band.start_um, "Band start below the tip (default 50 µm)");
  app.add_option("--band-height-um", o->band.height_um, "Band height (default 150 µm)");
  app.add_option("--band-start-px", o->band.start_px,
                 "Band start in px (default 50 µm at 3 µm/px)");
  app.add_option("--band-height-px", o->band.height_px,
                 "Band height in px (default 150 µm at 3 µm/px)");
  app.add_option("--caliper-px", o->strand.caliper_spacing_px, "Caliper thickness along the axis")
      ->capture_default_str();
  app.add_option("--polarity", text->polarity, "auto, bright (lit strand) or dark (silhouette)")
      ->capture_default_str();
  app.add_option("--target", text->target,
                 "strand (below a nozzle tip; band from the tip) or filament (no tip: feedstock, "
                 "needle, pin; band along the whole visible stretch)")
      ->capture_default_str();
  app.add_option("--max-blur-px", o->strand.max_blur_px,
                 "Frames blurrier than this are out of focus")
      ->capture_default_str();
  app.add_option("--min-contrast", text->min_contrast_levels,
                 "Minimum edge contrast in 8-bit grey levels (default 15)");
  app.add_option("--max-sigma-px", o->strand.max_sigma_px,
                 "Widths whose σ is above this (or 0.17 % of the width, if more) are refused as "
                 "imprecise: a valid width is good to max(0.3 px, 0.5 %) at 3σ")
      ->capture_default_str();
  app.add_flag("--no-shading", text->no_shading,
               "Fit every edge as a plain blurred step (no shading term for front-lit strands)");
}

void ApplyMeasurementOptions(const CLI::App& app, const MeasureCliText& text,
                             pipeline::MeasureInputsOptions* o) {
  if (!text.roi.empty()) o->strand.roi = pipeline::ParseRoi(text.roi);
  if (!text.calib_path.empty()) {
    RequireInputPath("--calib", text.calib_path, PathExpect::kFile);
    o->calibration = calib::ReadCalibrationFile(text.calib_path);
  }
  o->strand.polarity = vision::ParsePolarity(text.polarity);
  o->strand.target = vision::ParseMeasureTarget(text.target);
  if (app.count("--min-contrast")) {
    if (!(text.min_contrast_levels > 0 && text.min_contrast_levels < 255))
      throw std::invalid_argument("--min-contrast: must be in (0, 255) grey levels");
    o->strand.min_contrast_fraction = text.min_contrast_levels / 255.0;
  }
  o->strand.shading = !text.no_shading;
}

}  // namespace clogscope::apps
