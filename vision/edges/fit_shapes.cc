#include "vision/edges/fit_shapes.h"

namespace clogscope::vision::fitcore {

const BlurredSqrt& BlurredSqrt::Get() {
  static const BlurredSqrt table;
  return table;
}

// G, G' = ∫₀^∞ φ(z − v²) dv (from t = v²) and G'' = −∫₀^∞ (z − v²)·φ(z − v²) dv, by Simpson's
// rule in v, where the integrands are smooth.
BlurredSqrt::BlurredSqrt() {
  const int n = static_cast<int>((kZMax - kZMin) / kH) + 2;
  g_.resize(n);
  dg_.resize(n);
  d2g_.resize(n);
  for (int i = 0; i < n; ++i) {
    const double z = kZMin + i * kH;
    // φ(z − v²) matters for |z − v²| < 9: v from √max(0, z − 9) to √(z + 9).
    const double lo = std::sqrt(std::max(0.0, z - 9.0)), hi = std::sqrt(std::max(0.0, z + 9.0));
    constexpr int kSteps = 100;
    const double h = (hi - lo) / kSteps;
    double sg = 0, sd = 0, sd2 = 0;
    for (int k = 0; k <= kSteps; ++k) {
      const double v = lo + k * h;
      const double w = (k == 0 || k == kSteps) ? 1 : (k % 2 ? 4 : 2);
      const double ph = kInvSqrt2Pi * std::exp(-0.5 * (z - v * v) * (z - v * v));
      sg += w * 2 * v * v * ph;
      sd += w * ph;
      sd2 -= w * (z - v * v) * ph;
    }
    g_[i] = sg * h / 3;
    dg_[i] = sd * h / 3;
    d2g_[i] = sd2 * h / 3;
  }
}

}  // namespace clogscope::vision::fitcore
