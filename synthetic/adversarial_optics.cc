#include "synthetic/adversarial_optics.h"

#include <algorithm>
#include <cmath>

namespace clogscope::synthetic {

double LensTransmission(double x, double n, double acceptance_rad, double floor) {
  const double ax = std::min(std::abs(x), 1.0);
  const double delta = 2 * (std::asin(ax) - std::asin(ax / n));
  const double pass = 0.5 * std::erfc((delta - acceptance_rad) / (0.12 * acceptance_rad + 1e-9));
  return 0.92 * (floor + (1 - floor) * pass);
}

double StrandEmission(const AdversarialScene& p, double x) {
  const double bulge = std::sqrt(std::max(0.0, 1 - x * x));
  return p.strand_level * (p.shading_ambient + (1 - p.shading_ambient) * bulge);
}

}  // namespace clogscope::synthetic
