#pragma once

#include <cmath>

namespace clogscope {

// Degrees to radians and back (options, scenes and tables give angles in degrees; the maths takes
// radians).
inline constexpr double kDegToRad = M_PI / 180.0;
inline constexpr double kRadToDeg = 180.0 / M_PI;

}  // namespace clogscope
