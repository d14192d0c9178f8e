#pragma once

#include <vector>

#include "vision/edges/edge_fit.h"

namespace clogscope::vision {

// A front-lit cylinder's whole profile across a caliper, blurred:
//   value(u) = b₀ + b₁·(u − u_ref) + blur_σ{ 1[|x| < 1] · (a + k·√(1 − x²) + l·x) },
//   x = (u − centre)/radius.
// a is the ambient (flat) part of the object's brightness, k the Lambertian part (n·v of a lit
// cylinder), l a tilt for light from one side. Both edges share the centre, the radius, the blur
// and the shading, so the interior's curvature fixes k and each silhouette is placed where the
// shading's √d ramp starts — not where a per-edge fit, trading its step against its ramp, puts it.
// Residuals are weighted robustly (Cauchy, from the residuals' MAD), so a specular stripe or a
// clear strand's internal lines do not pull the fit.
struct CylinderFit {
  bool converged = false;
  double centre_px = 0, radius_px = 0;
  double left_px = 0, right_px = 0;                    // centre ∓ radius: the silhouette
  double left_sigma_px = 0, right_sigma_px = 0;        // standard errors of the edges
  double width_sigma_px = 0;                           // standard error of 2·radius
  double sigma_px = 0;                                 // Gaussian width of the blur
  double background = 0, background_slope_per_px = 0;  // b₀, b₁
  double u_ref_px = 0;  // where b₁ is anchored: midway between the guessed edges
  double ambient = 0, shading = 0, tilt = 0;  // a, k, l
  double rms = 0;                             // weighted residual RMS, grey levels
  double noise = 0;                           // robust residual scale (1.4826·MAD), grey levels
  int samples = 0;
  int outliers = 0;  // residuals beyond 4 robust σ
  int iterations = 0;
};

// Fits the model to samples spanning both edges and the background beyond each, started from the
// two edges (left < right) and a blur.
CylinderFit FitLitCylinder(const std::vector<EdgeSample>& samples, double left_guess_px,
                           double right_guess_px, double sigma_guess_px);

// A fitted cylinder's contrast at one silhouette (side 0 left, 1 right), as a per-edge fit's
// (EdgeFit::contrast): the model's change from the background to 2σ inside the object, signed
// like the step from −u to +u there.
double CylinderEdgeContrast(const CylinderFit& fit, int side);

}  // namespace clogscope::vision
