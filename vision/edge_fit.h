#pragma once

#include <vector>

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
  double rms = 0;  // residual RMS, grey levels
  int samples = 0;
  int iterations = 0;
};

// Levenberg–Marquardt fit of the blurred-step model, started at edge_guess_px with width
// sigma_guess_px. `u_ref` is where the linear background term is anchored (the window centre).
// Written by hand rather than with Ceres: it runs ~100 times per frame in a 1 ms budget, where a
// 5-parameter dense solve costs less than Ceres' per-problem set-up.
EdgeFit FitBlurredStep(const std::vector<EdgeSample>& samples, double edge_guess_px,
                       double sigma_guess_px, double u_ref);

// Fit of a thin line's profile, value(u) = base + slope·(u − centre_guess) + depth·exp(−z²/2),
// z = (u − centre)/width. The result's edge_px is the line centre, sigma_px its Gaussian width,
// step its (signed) depth.
EdgeFit FitLineProfile(const std::vector<EdgeSample>& samples, double centre_guess_px,
                       double width_guess_px);

}  // namespace clogscope::vision
