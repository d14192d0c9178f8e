#pragma once

#include <algorithm>
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/edge_fit.h"

namespace clogscope::vision {

// The background of a lit cylinder (below): how its fit models what lies beside the object.
enum class CylinderBackground {
  // An object in front of a backdrop (a strand below the nozzle): an uneven lamp or a textured
  // backdrop differs from one side to the other, and one line bent through both would move the
  // silhouettes (up to 0.33 px measured).
  kEachSide,
  // One line, two parameters fewer: a filament's calipers, whose backgrounds beside it are gear
  // teeth and guides as often as a backdrop (Greeff's real video: 281 of 281 frames valid at
  // 137.65 px with one line, 274 at 137.91 px with a line each side).
  kOneLine,
};

// A front-lit cylinder's whole profile across a caliper, blurred:
//   value(u) = blur_σ{ 1[x < −1]·(bl₀ + bl₁·u) + 1[x > 1]·(br₀ + br₁·u)
//                      + 1[|x| < 1]·(a + k·√(1 − x²) + l·x) },   x = (u − centre)/radius,
// each side's background its own line, seen only beside the opaque object (kEachSide), or
//   value(u) = b₀ + b₁·u + blur_σ{ 1[|x| < 1]·(a + k·√(1 − x²) + l·x) }
// with one line through both sides (kOneLine). a is the ambient (flat) part
// of the object's brightness, k the Lambertian part (n·v of a lit cylinder), l a tilt for light
// from one side. With a line each side, light from a lamp within 60° of the camera's axis
// (cylinder_fit.cc) is clamped at 0 past the terminator, as a lamp's is:
// a + max(0, k·√(1 − x²) + l·x) (the far rim's dark strip).
// Both edges share the centre, the radius, the blur and the shading, so the interior's curvature
// fixes k and each silhouette is placed where the shading's √d ramp starts —
// not where a per-edge fit, trading its step against its ramp, puts it. Residuals are weighted
// robustly (Cauchy, from the residuals' MAD), so a specular stripe or a clear strand's internal
// lines do not pull the fit.
struct CylinderFit {
  bool converged = false;
  double centre_px = 0, radius_px = 0;
  double left_px = 0, right_px = 0;              // centre ∓ radius: the silhouette
  double left_sigma_px = 0, right_sigma_px = 0;  // standard errors of the edges
  double width_sigma_px = 0;                     // standard error of 2·radius
  double sigma_px = 0;                           // Gaussian width of the blur
  // Each side's background at its silhouette, and its slope.
  double background_left = 0, background_right = 0;
  double background_slope_left_per_px = 0, background_slope_right_per_px = 0;
  CylinderBackground background = CylinderBackground::kEachSide;  // the model fitted
  double u_ref_px = 0;  // where the lines' levels are anchored: midway between the guessed edges
  double ambient = 0, shading = 0, tilt = 0;  // a (over the background behind the centre), k, l
  // Light from one side: how deep the dark strip inside the far rim, out to the terminator, that
  // the fit modelled (cylinder_fit.cc); 0 without one.
  double terminator_px = 0;
  double rms = 0;    // weighted residual RMS, grey levels
  double noise = 0;  // robust residual scale (1.4826·MAD), grey levels
  int samples = 0;
  int outliers = 0;  // residuals beyond 4 robust σ
  int iterations = 0;
};

// Fits the model to samples spanning both edges and the background beyond each, started from the
// two edges (left < right) and a blur; samples at about the same u are taken in groups
// (GroupCylinderPixels about the guesses). residuals_out, when given, receives each sample's
// residual (model − value) at the fit.
CylinderFit FitLitCylinder(const std::vector<EdgeSample>& samples, double left_guess_px,
                           double right_guess_px, double sigma_guess_px,
                           CylinderBackground background = CylinderBackground::kEachSide,
                           std::vector<double>* residuals_out = nullptr);

// How far inside each silhouette (left_px, right_px, blur sigma_px) a lit cylinder's profile is
// its shading's alone: the silhouettes' steps have settled (to 1e-5 of their height at blurs up to
// 3 px, 2e-4 at 8 px).
inline double CylinderInteriorMarginPx(double sigma_px) {
  return std::max(10.0, 3.0 * sigma_px + 4.0);
}

// A lit cylinder's pixels in groups for its fits (GroupByU): within kGroupSpanBlurs of u about the
// silhouettes; within kInteriorGroupSpanPx beyond CylinderInteriorMarginPx,
// where the shading's curvature over it leaves a group's mean below 0.05 grey levels on an object
// 100 levels bright and 30 px in radius.
inline constexpr double kInteriorGroupSpanPx = 2.0;
PixelGroups GroupCylinderPixels(const std::vector<EdgeSample>& samples, double left_px,
                                double right_px, double sigma_px);

// A fitted cylinder's contrast at one silhouette (side 0 left, 1 right), as a per-edge fit's
// (EdgeFit::contrast): the object's part of the model (a, k, l; over the background behind it)
// 2σ inside the silhouette, signed like the step from −u to +u there. Without the terminator's
// fill (a lamp-lit strand's dark rim reads up to |l| low): it serves filaments' tracked fits, which
// have none.
double CylinderEdgeContrast(const CylinderFit& fit, int side);

}  // namespace clogscope::vision
