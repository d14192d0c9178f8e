#pragma once

// `clogscope inspect`: what the tool sees in one frame, and the options to use.

#include <opencv2/core.hpp>
#include <string>

#include "vision/scene/scene.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::apps {

// Parses argv (argv[0] is the subcommand name) into the options below and calls the typed
// function; returns the process exit code (main.cc dispatches to it).
int RunInspect(int argc, char** argv);

struct InspectCommandOptions {
  std::string input;  // an image, a directory of images or a video
  int frame = 0;      // which frame of it
  std::string out_png = "inspect.png";
  vision::StrandMeasureOptions strand;  // roi, polarity; the target when target_given
  bool target_given = false;            // else: strand, or filament when no tip is in view
  bool band_given = false;              // the strand's band fields hold the user's band (px)
  bool Validate(std::string* why) const;
};

struct InspectReport {
  vision::MeasureTarget target = vision::MeasureTarget::kStrand;
  vision::SceneResult scene;
  vision::StrandMeasurement measurement;
  cv::Rect frame_rect, suggested_roi;  // empty ROI: none to suggest
  std::string text;                    // the report, with the suggested command and manifest keys
};

// Looks at one frame as `measure` would and explains what it found: every candidate edge pair
// with its score and verdict, the chosen one, tip, band and calipers (an annotated PNG at
// out_png, written atomically), and a suggested command line and manifest snippet. Throws
// std::invalid_argument for an input that cannot be read or has no such frame.
InspectReport InspectInput(const InspectCommandOptions& options);

}  // namespace clogscope::apps
