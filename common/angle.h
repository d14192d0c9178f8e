#pragma once

#include <cmath>

namespace clogscope {

// Degrees to radians (options and scenes give angles in degrees; the maths takes radians).
inline constexpr double kDegToRad = M_PI / 180.0;

}  // namespace clogscope
