#pragma once

// The lit cylinder's model (cylinder_fit.h), shared by its full fit and by its fit as a template
// in later frames (cylinder_track.h). Internal to the vision module.
#include <algorithm>
#include <cmath>
#include <vector>

#include "common/robust.h"
#include "vision/edges/fit_shapes.h"

namespace clogscope::vision::fitcore::cylinder {

// A fit's residuals' robust scale: 1.4826·MAD about 0, at least 1e-6 grey levels.
inline double RobustScale(const std::vector<double>& residuals) {
  return std::max(kMadToSigma * Mad(residuals, 0.0), 1e-6);
}

// The silhouettes' and the width's standard errors from a fit's normal matrix (its centre and
// radius at indices c and r), scaled by the residual variance: centre ∓ radius and twice the
// radius.
struct SilhouetteSigmas {
  double left_px = 0, right_px = 0, width_px = 0;
};
template <int N>
SilhouetteSigmas SilhouetteSigmasOf(const Mat<N>& jtj, int c, int r, double residual_var) {
  const Eigen::Matrix<double, N, 2> cov = InverseColumns<N, 2>(jtj, {c, r}) * residual_var;
  const double cc = cov(c, 0), rr = cov(r, 1), cr = cov(r, 0);
  return {std::sqrt(std::max(0.0, cc + rr - 2 * cr)), std::sqrt(std::max(0.0, cc + rr + 2 * cr)),
          2.0 * std::sqrt(std::max(0.0, rr))};
}

constexpr double kMinSigmaPx = 0.15;  // the narrowest blur a fit may take
// Cauchy weights 1/(1 + (r/(c·s))²) with c = 2.385: 95 % efficiency on Gaussian noise.
constexpr double kCauchyC = 2.385;

// The model's shapes: the background left of the object (level at u_ref, slope) and right of it;
// the object's a, k, l. Their amplitudes are linear parameters, then come the centre, radius and
// blur.
enum Shape { kLeft0, kLeft1, kRight0, kRight1, kBox, kLit, kTilt, kShapes };

// The seven shapes at one u, blurred, and their derivatives by centre, radius and blur; without
// kEachSide only the object's three (box, lit, tilt: a model with one background line needs no
// more, and the others were a third of the evaluation).
// With dl = u − c + R and dr = c + R − u the distances inside the left and right silhouettes,
// a = dl/σ, b = dr/σ and x = u − u_ref:
//   left = 1 − Φ(a),  left·x = x·(1 − Φ(a)) − σφ(a)   (exact: blurred 1[t < c − R] and t·1[…])
//   right = 1 − Φ(b), right·x = x·(1 − Φ(b)) + σφ(b)
//   box = Φ(a) + Φ(b) − 1                              (exact)
//   tilt = [(u − c)·box + σ(φ(a) − φ(b))]/R            (exact: a blurred linear ramp on the box)
//   lit = [σ·G(a)·G(b) − q·(G'(a) + G'(b))]/R,  q = σ^1.5 / (2√(2R))
// The last blurs √(1 − x²) = √dl·√dr / R: the product of the blurred roots, corrected for the
// other root's slope across each blurred edge (√dr ≈ √(2R)·(1 − dl/4R) near the left one, and
// blurring √t·(t − z) gives G'(z)); what remains is of order (σ/R)² of k.
struct Shapes {
  double v[kShapes];
  double d[kShapes][3];  // d[shape][c, R, σ]
};

template <bool kEachSide = true>
inline void EvalShapes(double u, double u_ref, double c, double r, double s,
                       const fitcore::BlurredSqrt& root, Shapes* out) {
  const double inv_s = 1.0 / s, inv_r = 1.0 / r;
  const double a = (u - c + r) * inv_s, b = (c + r - u) * inv_s;
  double fa, pa, fb, pb, ga, gpa, gb, gpb, g2a, g2b;
  fitcore::StepShape(a, &fa, &pa);
  fitcore::StepShape(b, &fb, &pb);
  root.WithCurvature(a, &ga, &gpa, &g2a);
  root.WithCurvature(b, &gb, &gpb, &g2b);
  const double x = u - c, xr = u - u_ref;
  const auto set = [out](int i, double v, double dc, double dr, double ds) {
    out->v[i] = v;
    out->d[i][0] = dc;
    out->d[i][1] = dr;
    out->d[i][2] = ds;
  };
  if constexpr (kEachSide) {
    set(kLeft0, 1.0 - fa, pa * inv_s, -pa * inv_s, a * pa * inv_s);
    set(kLeft1, xr * (1.0 - fa) - s * pa, xr * pa * inv_s - a * pa, -xr * pa * inv_s + a * pa,
        xr * a * pa * inv_s - pa - a * a * pa);
    set(kRight0, 1.0 - fb, -pb * inv_s, -pb * inv_s, b * pb * inv_s);
    set(kRight1, xr * (1.0 - fb) + s * pb, -xr * pb * inv_s - b * pb, -xr * pb * inv_s - b * pb,
        xr * b * pb * inv_s + pb + b * b * pb);
  }
  const double box = fa + fb - 1.0;
  set(kBox, box, (pb - pa) * inv_s, (pa + pb) * inv_s, -(a * pa + b * pb) * inv_s);
  const double k = s * std::sqrt(s) / (2.0 * std::sqrt(2.0 * r));
  const double q = k * (gpa + gpb);
  const double q_c = k * (g2b - g2a) * inv_s;
  const double q_r = -0.5 * q * inv_r + k * (g2a + g2b) * inv_s;
  const double q_s = 1.5 * q * inv_s - k * (a * g2a + b * g2b) * inv_s;
  const double lit = (s * ga * gb - q) * inv_r;
  set(kLit, lit, (ga * gpb - gpa * gb - q_c) * inv_r, (gpa * gb + ga * gpb - q_r - lit) * inv_r,
      (ga * gb - a * gpa * gb - b * ga * gpb - q_s) * inv_r);
  const double tilt = (x * box + s * (pa - pb)) * inv_r;
  set(kTilt, tilt, (-box + x * (pb - pa) * inv_s + a * pa + b * pb) * inv_r,
      (x * (pa + pb) * inv_s - a * pa + b * pb - tilt) * inv_r,
      (-x * (a * pa + b * pb) * inv_s + pa - pb + a * a * pa - b * b * pb) * inv_r);
}

}  // namespace clogscope::vision::fitcore::cylinder
