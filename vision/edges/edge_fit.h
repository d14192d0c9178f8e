#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "vision/edges/clip_levels.h"

namespace clogscope::vision {

// One pixel near an edge: its distance across the edge direction (px) and its grey value.
struct EdgeSample {
  float u_px;
  float value;
};

// A blurred straight step fitted to samples across it:
//   value(u) = base + slope·(u − u_ref) + step · Φ((u − edge_px) / sigma_px).
struct EdgeFit {
  bool converged = false;
  double edge_px = 0;        // 50 % point of the step
  double edge_sigma_px = 0;  // standard error of edge_px from the residuals
  double sigma_px = 0;       // Gaussian width of the step (PSF ⊗ pixel footprint)
  double step = 0;           // signed: value far at +u minus value far at −u
  double base = 0;
  double slope_per_px = 0;
  double shading = 0;  // FitShadedStep: amplitude of the blurred √d ramp on the object side
  // Signed like `step`: the model's change from the outside to 2σ inside the object, shading
  // included (equals `step` without shading). A shaded edge may have almost no step at all.
  double contrast = 0;
  double rms = 0;  // residual RMS, grey levels
  int samples = 0;
  int iterations = 0;
  double slope_change_per_px = 0;  // FitTwoSlopeStep: slope at +u minus slope at −u
  double u_ref = 0;                // where the linear term is anchored
  int object_side = 0;             // FitShadedStep: the object's side (±1); 0 for the plain step
  // FitStepBeforeInnerStep: the second step inside the object (0 without one) and where it lies;
  // where a stripe's far side takes it off again (infinity: the step stays to the window's end).
  double inner_step = 0, inner_edge_px = 0;
  double inner_far_px = std::numeric_limits<double>::infinity();
};

// The blurred step's reach from its edge: kBlurredStepBlurs of its sigma_px and a px.
inline constexpr double kBlurredStepBlurs = 2.5;
inline double BlurredStepReachPx(double sigma_px) { return kBlurredStepBlurs * sigma_px + 1.0; }

// The PSF's sigma in a fitted step's width, px: sigma_px less the pixel footprint, whose variance
// across any straight edge is 1/12 px² whatever its tilt.
inline double PsfSigmaPx(const EdgeFit& fit) {
  return std::sqrt(std::max(0.0, fit.sigma_px * fit.sigma_px - 1.0 / 12.0));
}

// Clipped samples in the step fits (`censor`, when given): a sample at or beyond a clip level says
// only that the scene there is at or beyond it. The clipped samples are grouped by u apart from
// the others; where the model at such a group lies beyond its level, the group is left out of the
// fit; elsewhere it counts at its values, as without `censor`. The fit's `samples` and `rms` are
// then the counted samples'. A clipped lamp's spot behind an edge, or a stripe clipped inside the
// object, then no longer pulls the step's plateau down to the clip.

// The blurred step whose sides slope differently (a background gradient or texture on one side of
// a silhouette, a flat object on the other):
//   value(u) = base + slope·(u − u_ref) + step·Φ(z) + k·sigma_px·(zΦ(z) + φ(z)),
// the last term a ramp of slope k on the +u side, blurred with the step. One parameter more than
// FitBlurredStep, which it equals when both sides slope alike.
EdgeFit FitTwoSlopeStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                        double sigma_guess_px, double u_ref, const ClipLevels* censor = nullptr);

// The blurred step through a symmetric PSF somewhat more or less peaked than a Gaussian (a colour
// camera's demosaiced luma, a lens's aberrations), to the first Gram–Charlier term:
//   value(u) = base + slope·(u − u_ref) + step·Φ(z) + k·φ(z)·(3z − z³).
// Symmetric about the edge: where it describes an edge as well as FitShadedStep does, the edge's
// profile is no evidence of a lit cylinder's one-sided shading. One parameter more than
// FitBlurredStep. (EdgeModelValue does not evaluate it: only its residuals are used.)
EdgeFit FitPeakedStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                      double sigma_guess_px, double u_ref, const ClipLevels* censor = nullptr);

// How far FitBlurredStep over [−below_px, above_px] puts the edge of a step of `step` (signed:
// value at +u less value at −u) and blur sigma_px (EdgeFit::sigma_px) whose +u side slopes by
// one grey level per px more than its −u side (FitTwoSlopeStep's slope change): px per grey
// level per px, to first order (the plain step's single slope between the two).
double PlainStepMovePerSlopeChange(double step, double sigma_px, double below_px, double above_px);

// The fitted model's value at u (FitBlurredStep, FitShadedStep, FitTwoSlopeStep results).
double EdgeModelValue(const EdgeFit& fit, double u_px);

// Levenberg–Marquardt fit of the blurred-step model, started at edge_guess_px with width
// sigma_guess_px. `u_ref` is where the linear background term is anchored (the window centre).
// Written by hand rather than with Ceres: it runs ~100 times per frame in a 1 ms budget, where a
// 5-parameter dense solve costs less than Ceres' per-problem set-up.
EdgeFit FitBlurredStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                       double sigma_guess_px, double u_ref, const ClipLevels* censor = nullptr);

// FitBlurredStep with a second step of the same blur inside the object, started at
// inner_guess_px: a stripe's or a lens core's near edge, too close to the silhouette for the
// window to stop short of it (the window then reaches onto the stripe):
//   value(u) = base + slope·(u − u_ref) + step·Φ(z) + inner_step·Φ((u − inner_edge_px)/sigma_px).
// edge_px is the silhouette's step. Not converged unless the two steps lie apart by at least the
// blur, the inner one on inner_guess_px's side of the silhouette. With a finite far_guess_px, the
// window reaches past a narrow stripe's far side too, and the stripe is a box of the same blur:
//   … + inner_step·(Φ((u − inner_edge_px)/sigma_px) − Φ((u − inner_far_px)/sigma_px)),
// its far side beyond its near side.
EdgeFit FitStepBeforeInnerStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                               double sigma_guess_px, double u_ref, double inner_guess_px,
                               double far_guess_px = std::numeric_limits<double>::infinity(),
                               const ClipLevels* censor = nullptr);

// The blurred step with a lit cylinder's shading on the object side:
//   value(u) = base + slope·(u − u_ref) + step·Φ(z) + shading·G(ι·z),  z = (u − edge_px)/sigma_px,
// G the unit-blurred √d ramp (a Lambertian cylinder brightens like √d inward from its silhouette)
// and ι = object_side (+1: the object lies at +u). edge_px is then the silhouette itself, not the
// 50 % level of a sloping plateau. With no shading present the fit returns shading ≈ 0 and the
// same edge as FitBlurredStep.
EdgeFit FitShadedStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                      double sigma_guess_px, double u_ref, int object_side,
                      const ClipLevels* censor = nullptr);

// Fit of a thin line's profile, value(u) = base + slope·(u − centre_guess) + depth·exp(−z²/2),
// z = (u − centre)/width. The result's edge_px is the line centre, sigma_px its Gaussian width,
// step its (signed) depth.
EdgeFit FitLineProfile(const std::vector<EdgeSample>& samples, double centre_guess_px,
                       double width_guess_px);

}  // namespace clogscope::vision
