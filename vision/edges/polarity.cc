#include "vision/edges/polarity.h"

#include <stdexcept>

namespace clogscope::vision {

const char* PolarityName(Polarity p) {
  switch (p) {
    case Polarity::kAuto:
      return "auto";
    case Polarity::kBrightOnDark:
      return "bright";
    case Polarity::kDarkOnBright:
      return "dark";
    case Polarity::kMixed:
      return "mixed";
  }
  return "?";
}

Polarity ParsePolarity(const std::string& name) {
  if (name == "auto") return Polarity::kAuto;
  if (name == "bright") return Polarity::kBrightOnDark;
  if (name == "dark") return Polarity::kDarkOnBright;
  throw std::invalid_argument("polarity '" + name + "': expected auto, bright or dark");
}

}  // namespace clogscope::vision
