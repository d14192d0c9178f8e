#include "vision/caliper_samples.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace clogscope::vision {

bool GatherEdgeSamples(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                       double u1, double data_max, std::vector<EdgeSample>* out, int* saturated) {
  out->clear();
  double xmin = 1e30, xmax = -1e30, ymin = 1e30, ymax = -1e30;
  for (double s : {s0, s1}) {
    for (double u : {u0, u1}) {
      xmin = std::min(xmin, f.ImageX(s, u));
      xmax = std::max(xmax, f.ImageX(s, u));
      ymin = std::min(ymin, f.ImageY(s, u));
      ymax = std::max(ymax, f.ImageY(s, u));
    }
  }
  const int x_lo = static_cast<int>(std::ceil(xmin)), x_hi = static_cast<int>(std::floor(xmax));
  const int y_lo = static_cast<int>(std::ceil(ymin)), y_hi = static_cast<int>(std::floor(ymax));
  if (x_lo < 0 || y_lo < 0 || x_hi >= img.m.cols || y_hi >= img.m.rows) return false;
  const float top = static_cast<float>(data_max);
  for (int y = y_lo; y <= y_hi; ++y) {
    const double ry = y - f.oy;
    for (int x = x_lo; x <= x_hi; ++x) {
      const double rx = x - f.ox;
      const double s = rx * f.dx + ry * f.dy;
      if (s < s0 || s >= s1) continue;
      const double u = rx * f.dy - ry * f.dx;
      if (u < u0 || u > u1) continue;
      const float v = img.At(x, y);
      if (v <= 0.0f || v >= top) ++*saturated;
      out->push_back({static_cast<float>(u), v});
    }
  }
  return true;
}

double RefineEdgeGuess(const GreyImage& img, const AxisFrame& f, double s, double u_guess,
                       double half, double min_step) {
  constexpr double kStep = 0.5;
  const int n = static_cast<int>(2 * half / kStep) + 1;
  std::array<float, 128> v;
  if (n > static_cast<int>(v.size())) return u_guess;
  float lo = 1e30f, hi = -1e30f;
  for (int i = 0; i < n; ++i) {
    const double u = u_guess - half + i * kStep;
    const double x = f.ImageX(s, u), y = f.ImageY(s, u);
    if (!img.InsideForBilinear(x, y)) return u_guess;
    v[i] = img.Bilinear(x, y);
    lo = std::min(lo, v[i]);
    hi = std::max(hi, v[i]);
  }
  if (hi - lo < min_step) return u_guess;
  const float mid = 0.5f * (lo + hi);
  double best = u_guess, best_dist = 1e30;
  for (int i = 0; i + 1 < n; ++i) {
    if ((v[i] < mid) == (v[i + 1] < mid)) continue;
    const double u = u_guess - half + (i + (mid - v[i]) / (v[i + 1] - v[i])) * kStep;
    if (std::abs(u - u_guess) < best_dist) {
      best_dist = std::abs(u - u_guess);
      best = u;
    }
  }
  return best;
}

}  // namespace clogscope::vision
