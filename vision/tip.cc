#include "vision/tip.h"

#include <algorithm>
#include <cmath>

namespace clogscope::vision {
namespace {

constexpr double kOffsetPx = 2.0;  // contrast is read this far either side of the edge
constexpr double kSearchPx = 2.0;  // how far an edge may move from where it was heading, per px
constexpr double kSearchStepPx = 0.25;
constexpr int kWeakSteps = 3;  // an edge ends after this many weak px in a row

// sign·(I(u + d) − I(u − d)) across the axis at s; false outside the image.
bool Contrast(const GreyImage& img, const AxisFrame& a, double s, double u, int sign, double* c) {
  const double xa = a.ImageX(s, u - kOffsetPx), ya = a.ImageY(s, u - kOffsetPx);
  const double xb = a.ImageX(s, u + kOffsetPx), yb = a.ImageY(s, u + kOffsetPx);
  if (!img.InsideForBilinear(xa, ya) || !img.InsideForBilinear(xb, yb)) return false;
  *c = sign * (img.Bilinear(xb, yb) - img.Bilinear(xa, ya));
  return true;
}

struct Curve {
  double s_end = 0;       // the last strong s
  std::vector<double> u;  // u at s_from − i
};

Curve Follow(const GreyImage& img, const AxisFrame& a, double u_start, double slope, int sign,
             double ref, double s_from, double max_steps) {
  Curve out;
  out.s_end = s_from;
  double u = u_start, velocity = -slope;  // du per px going up
  int weak = 0;
  for (int i = 1; i <= max_steps; ++i) {
    const double s = s_from - i;
    const double heading = u + velocity;
    double best_u = heading, best_c = -1e30;
    for (double du = -kSearchPx; du <= kSearchPx + 1e-9; du += kSearchStepPx) {
      double c;
      if (!Contrast(img, a, s, heading + du, sign, &c)) return out;
      if (c > best_c) {
        best_c = c;
        best_u = heading + du;
      }
    }
    if (best_c < 0.5 * ref) {
      if (++weak >= kWeakSteps) return out;
      continue;  // keep heading the same way over a weak px
    }
    weak = 0;
    // Smooth the heading: one noisy px must not turn the curve.
    velocity = 0.7 * velocity + 0.3 * (best_u - u);
    u = best_u;
    out.s_end = s;
    out.u.resize(i, u);
    out.u[i - 1] = u;
  }
  return out;
}

}  // namespace

TipTrace TraceToNozzle(const GreyImage& img, const AxisFrame& a, double left_u0, double right_u0,
                       double slope, int left_sign, int right_sign, double ref_l, double ref_r,
                       double s_from) {
  TipTrace t;
  const double width = right_u0 - left_u0;
  const double max_steps = std::max(20.0, 2.0 * width);
  const Curve l =
      Follow(img, a, left_u0 + slope * s_from, slope, left_sign, ref_l, s_from, max_steps);
  const Curve r =
      Follow(img, a, right_u0 + slope * s_from, slope, right_sign, ref_r, s_from, max_steps);
  // A nozzle face ends both edges together; a hair or a flank that one edge ran into does not.
  if (std::abs(l.s_end - r.s_end) > std::max(4.0, 0.14 * width)) return t;
  t.found = true;
  t.s_tip_px = 0.5 * (l.s_end + r.s_end);
  t.widest_px = width;
  const size_t n = std::min(l.u.size(), r.u.size());
  for (size_t i = 0; i < n; ++i) t.widest_px = std::max(t.widest_px, r.u[i] - l.u[i]);
  return t;
}

}  // namespace clogscope::vision
