#include "synthetic/edge_profile.h"

#include <algorithm>
#include <cmath>

namespace clogscope::synthetic {
namespace {

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;

// First antiderivative of the blurred step g(u) = Phi(u / sigma): G1(u) = u Phi + sigma phi.
double G1(double u, double sigma) {
  if (sigma <= 0) return u > 0 ? u : 0.0;
  double z = u / sigma;
  return u * NormalCdf(z) + sigma * kInvSqrt2Pi * std::exp(-0.5 * z * z);
}

// Second antiderivative: G2(u) = (u² + sigma²)/2 Phi + u sigma/2 phi.
double G2(double u, double sigma) {
  if (sigma <= 0) return u > 0 ? 0.5 * u * u : 0.0;
  double z = u / sigma;
  return 0.5 * (u * u + sigma * sigma) * NormalCdf(z) +
         0.5 * u * sigma * kInvSqrt2Pi * std::exp(-0.5 * z * z);
}

}  // namespace

double NormalCdf(double z) { return 0.5 * std::erfc(-z * kInvSqrt2); }

double PixelMeanOfBlurredStep(double t, double sigma, double nx, double ny) {
  double a = std::max(std::abs(nx), std::abs(ny));
  double b = std::min(std::abs(nx), std::abs(ny));
  // Beyond the reach of footprint and PSF the value is exactly 0 or 1 (Phi(-9) < 1e-18).
  double reach = 0.5 * (a + b) + 9.0 * sigma;
  if (t >= reach) return 1.0;
  if (t <= -reach) return 0.0;
  if (b < 1e-7) {
    // Axis-aligned edge: the footprint is a single box of width a (= 1).
    return (G1(t + 0.5 * a, sigma) - G1(t - 0.5 * a, sigma)) / a;
  }
  double hp = 0.5 * (a + b);
  double hm = 0.5 * (a - b);
  return (G2(t + hp, sigma) - G2(t + hm, sigma) - G2(t - hm, sigma) + G2(t - hp, sigma)) / (a * b);
}

}  // namespace clogscope::synthetic
