#pragma once

#include <optional>
#include <string>
#include <vector>

namespace clogscope::pipeline {

// One temperature (or clog) step and where its frames are.
struct StepSpec {
  int step = 0;
  double temperature_c = 0;
  std::string video;   // a video file, or
  std::string images;  // a directory of images
  double start_s = 0;  // part of the video to use (end_s < 0: to the end)
  double end_s = -1;
  double settle_s = 0;  // skipped at the start of the part
  int line = 0;         // manifest line, for messages
  // The feedstock filament filmed during the step: a video (same part of it as the step's), or
  // empty; with the manifest's feedstock: roi: and no video here, the step's own video.
  std::string feedstock_video;
};

// How a step's feedstock is measured (the manifest's feedstock: block): the filament's ROI, and a
// drive gear's for its speed and the slip. Strings as on the command line (x,y,w,h; x,y).
struct FeedstockSpec {
  bool enabled = false;  // the block is present (or a step names a feedstock video)
  std::string roi, gear_roi, gear_centre;
  double gear_radius_mm = 0;
  std::string polarity = "auto";
  // The feedstock camera's scale, when it is not the strand camera: a plain scale or a
  // calibration file.
  std::optional<double> scale_um_per_px;
  std::string calibration_file;
};

// An experiment: its steps and how to measure them. Paths are resolved against the manifest's
// folder. YAML keys (all optional but the steps):
//   name, samples, settle_s, scale_um_per_px, calibration (file), calibrate: {pins | micrometer,
//   pitch_um}, extruder, extruder_set: [name=value…], roi, polarity, target, band_start_um,
//   band_height_um, steps: [{step, temperature_c, video | images, start_s, end_s,
//   feedstock_video}…] or instead of steps: video, temperature_log, video_start_s,
//   hold_tolerance_c, min_step_s; feedstock: {roi, gear_roi, gear_centre, gear_radius_mm,
//   polarity, scale_um_per_px | calibration}.
// The CSV form holds steps only: step,temperature_c,source[,start_s,end_s].
struct Manifest {
  std::string path;
  std::string name;
  std::vector<StepSpec> steps;
  int samples = 50;
  double settle_s = 0;
  std::optional<double> scale_um_per_px;
  std::string calibration_file;
  std::string calibrate_pins_csv;
  std::vector<std::string> calibrate_micrometer;
  double calibrate_pitch_um = 0;
  std::string extruder;
  std::vector<std::string> extruder_set;
  std::string roi;
  std::string polarity = "auto";
  std::string target = "strand";  // strand (below a nozzle tip) or filament (no tip)
  std::optional<double> band_start_um, band_height_um;
  FeedstockSpec feedstock;
  // One long video cut into steps by the temperature log.
  std::string video;
  std::string temperature_log;
  double video_start_s = 0;  // log time at the video's first frame
  double hold_tolerance_c = 1.0;
  double min_step_s = 3.0;
};

// Reads a manifest (.yaml/.yml or .csv). Throws std::invalid_argument naming the file and line for
// an unknown key, a value of the wrong type, a duplicate step, a step without a source, or a
// temperature log that never holds.
Manifest LoadManifest(const std::string& path);

}  // namespace clogscope::pipeline
