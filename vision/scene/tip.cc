#include "vision/scene/tip.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "vision/edges/edge_fit.h"

namespace clogscope::vision {
namespace {

constexpr double kOffsetPx = 2.0;  // contrast is read this far either side of the edge
constexpr double kSearchPx = 3.0;  // how far an edge may move from where it was heading, per px
constexpr double kSearchStepPx = 0.25;
constexpr int kWeakSteps = 3;      // an edge ends after this many weak px in a row
constexpr double kInsidePx = 4.0;  // the object's level is read this far inside its edge

struct Curve {
  double s_end = 0;       // the last strong s
  std::vector<double> u;  // u at s_from − i
};

// The object's level just inside an edge (object_side: +1 the object lies at +u).
bool InsideLevel(const GreyImage& img, const AxisFrame& a, double s, double u, int object_side,
                 double* level) {
  const double ui = u + object_side * kInsidePx;
  const double x = a.ImageX(s, ui), y = a.ImageY(s, ui);
  if (!img.InsideForBilinear(x, y)) return false;
  *level = img.Bilinear(x, y);
  return true;
}

Curve Follow(const GreyImage& img, const AxisFrame& a, double u_start, double slope, int sign,
             int object_side, double ref, double s_from, double max_steps) {
  Curve out;
  out.s_end = s_from;
  double u = u_start, velocity = -slope;  // du per px going up
  int weak = 0;
  double strong_c = ref, first_weak_c = 0;
  // The strand's own level inside the edge: where it changes, the edge belongs to another
  // object (the nozzle's outline carries on from the strand's when the nozzle, like the strand,
  // is darker or brighter than the background).
  double inside_ref = 0;
  if (!InsideLevel(img, a, s_from, u_start, object_side, &inside_ref)) return out;
  for (int i = 1; i <= max_steps; ++i) {
    const double s = s_from - i;
    const double heading = u + velocity;
    double best_u = heading, best_c = -1e30;
    for (double du = -kSearchPx; du <= kSearchPx + 1e-9; du += kSearchStepPx) {
      double c;
      if (!ContrastAcross(img, a, s, heading + du, sign, kOffsetPx, &c)) return out;
      if (c > best_c) {
        best_c = c;
        best_u = heading + du;
      }
    }
    double inside = inside_ref;
    InsideLevel(img, a, s, best_u, object_side, &inside);
    if (best_c < 0.5 * ref || std::abs(inside - inside_ref) > 0.3 * ref) {
      if (weak == 0) first_weak_c = best_c;
      if (++weak >= kWeakSteps) {
        // The half-contrast crossing between the last strong px and the first weak one.
        if (first_weak_c < 0.5 * ref && strong_c > first_weak_c)
          out.s_end -= std::clamp((strong_c - 0.5 * ref) / (strong_c - first_weak_c), 0.0, 1.0);
        return out;
      }
      continue;  // keep heading the same way over a weak px
    }
    weak = 0;
    strong_c = best_c;
    // Smooth the heading: one noisy px must not turn the curve.
    velocity = 0.5 * velocity + 0.5 * (best_u - u);
    u = best_u;
    out.s_end = s;
    out.u.resize(i, u);
    out.u[i - 1] = u;
  }
  return out;
}

// The nozzle's face beside the strand: just outside the outline on each side, the profile along
// the axis steps from the nozzle to the background at the face. A blurred step fitted there puts
// the tip to a fraction of a px, where the end of a followed edge is only good to the blur.
// Returns on how many sides (0–2) the face was found; with two, they agree within 3 px.
int FaceBesideStrand(const GreyImage& img, const AxisFrame& a, double s_guess, double half_px,
                     double min_contrast, double* s_face) {
  constexpr double kReachPx = 10.0, kColumnsPx = 4.0, kAgreePx = 3.0;
  // Columns from just outside the outline outward: near the face a swollen strand may still
  // be wider than the outline followed, and the profile there crosses it too.
  constexpr double kOffsetsPx[] = {3.0, 9.0, 15.0, 21.0};
  std::vector<double> found;
  std::vector<EdgeSample> samples;
  for (int side : {-1, 1}) {
    for (double offset : kOffsetsPx) {
      samples.clear();
      for (double du = 0; du <= kColumnsPx; du += 1.0) {
        const double u = side * (half_px + offset + du);
        for (double s = s_guess - kReachPx; s <= s_guess + kReachPx; s += 0.5) {
          const double x = a.ImageX(s, u), y = a.ImageY(s, u);
          if (!img.InsideForBilinear(x, y)) continue;
          samples.push_back({static_cast<float>(s), static_cast<float>(img.Bilinear(x, y))});
        }
      }
      if (samples.size() < 60) break;
      const EdgeFit fit = FitBlurredStep(samples, s_guess, 1.5, s_guess);
      if (!fit.converged || std::abs(fit.step) < min_contrast ||
          std::abs(fit.edge_px - s_guess) > kReachPx - 2.0 || fit.sigma_px > 6.0)
        continue;
      found.push_back(fit.edge_px);
      break;
    }
  }
  if (found.empty()) return 0;
  if (found.size() == 2 && std::abs(found[0] - found[1]) > kAgreePx) {
    // Not one face across the strand (a flank on one side): the end nearer the guess.
    *s_face = std::abs(found[0] - s_guess) < std::abs(found[1] - s_guess) ? found[0] : found[1];
    return 1;
  }
  *s_face = found.size() == 2 ? 0.5 * (found[0] + found[1]) : found[0];
  return static_cast<int>(found.size());
}

}  // namespace

TipTrace TraceToNozzle(const GreyImage& img, const AxisFrame& a, double left_u0, double right_u0,
                       double slope, int left_sign, int right_sign, double ref_l, double ref_r,
                       double s_from, double min_face_step) {
  TipTrace t;
  const double width = right_u0 - left_u0;
  const double max_steps = std::max(20.0, 2.0 * width);
  const Curve l =
      Follow(img, a, left_u0 + slope * s_from, slope, left_sign, +1, ref_l, s_from, max_steps);
  const Curve r =
      Follow(img, a, right_u0 + slope * s_from, slope, right_sign, -1, ref_r, s_from, max_steps);
  // A nozzle face ends both edges together; a hair or a flank that one edge ran into does not.
  if (std::abs(l.s_end - r.s_end) > std::max(4.0, 0.14 * width)) return t;
  t.found = true;
  t.s_tip_px = 0.5 * (l.s_end + r.s_end);
  t.widest_px = width;
  const size_t n = std::min(l.u.size(), r.u.size());
  for (size_t i = 0; i < n; ++i) t.widest_px = std::max(t.widest_px, r.u[i] - l.u[i]);
  // The followed edges end within the blur of the face; the face itself, where the nozzle shows
  // beside the strand, is sharper.
  double s_face = 0;
  const double axis_u = 0.5 * (left_u0 + right_u0) + slope * t.s_tip_px;
  AxisFrame centred = a;
  centred.ox = a.ImageX(0, axis_u);
  centred.oy = a.ImageY(0, axis_u);
  // Looked for from the edge that got furthest, then from both ends' middle: an edge that
  // stopped short in noise leaves the other's end nearer the face.
  for (double s_guess : {std::min(l.s_end, r.s_end), t.s_tip_px}) {
    const int sides =
        FaceBesideStrand(img, centred, s_guess, 0.5 * t.widest_px, min_face_step, &s_face);
    if (sides > 0 && std::abs(s_face - s_guess) <= 6.0) {
      t.s_tip_px = s_face;
      t.face_sides = sides;
      break;
    }
  }
  return t;
}

}  // namespace clogscope::vision
