#pragma once

#include <string>

namespace clogscope::vision {

// Which way the strand differs from the background.
enum class Polarity {
  kAuto,          // measurement only: decide from the frame
  kBrightOnDark,  // lit strand on a dark background
  kDarkOnBright,  // silhouette on a backlight
  kMixed,         // measured only: brighter than the background on one side, darker on the other
};
const char* PolarityName(Polarity p);
// Parses "auto", "bright" or "dark"; throws std::invalid_argument otherwise.
Polarity ParsePolarity(const std::string& name);

}  // namespace clogscope::vision
