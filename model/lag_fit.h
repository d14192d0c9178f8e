#pragma once

// Fits the extrusion lag K to a measured width series: width(t) = gain · Q_out(t − offset; K),
// the outlet flow of the first-order lag at constant print speed (the pressure-advance study
// compares simulated flow with measured line width).
#include <string>
#include <vector>

#include "model/extrusion_lag.h"

namespace clogscope::model {

struct WidthSample {
  double time_s = 0;
  double width = 0;  // any unit (px or µm): the gain carries it
};

// The bounds of every search the fit makes: the time offset range (clocks further apart must be
// aligned first, by shifting the profile's times), the offsets tried by the coarse grid (its step
// grows with the range past this count) and the solver's iterations.
inline constexpr double kMaxLagOffsetS = 60;
inline constexpr int kMaxGridOffsets = 600;  // on each side of 0
inline constexpr int kMaxLagIterations = 1000;

struct LagFitOptions {
  double min_k_s = 1e-3, max_k_s = 10;  // bounds of K
  double max_offset_s = 0.5;  // |time offset| between the profile's and video's clocks, ≤ 60 s
  double outlier_threshold_sigma = 5;  // residuals beyond this many robust σ are left out, once
  int max_iterations = 100;            // ≤ kMaxLagIterations
  // Names the lag command's option where there is one (--max-offset-s).
  bool Validate(std::string* why) const;
};

// Every fitted number comes with its σ (covariance scaled by the residual variance).
struct LagFitSummary {
  bool usable = false;
  std::string message;  // why not, when not usable
  double k_s = 0, k_sigma_s = 0;
  double gain = 0, gain_sigma = 0;  // width per mm³/s
  double offset_s = 0, offset_sigma_s = 0;
  double k_la_s = 0;  // linear advance to set: K
  double rms = 0;     // residual RMS, width units
  double worst_residual = 0;
  double worst_time_s = 0;
  int samples_used = 0, samples_total = 0, outliers = 0;
  std::vector<bool> outlier;         // per sample
  std::vector<double> fitted_width;  // per sample, at the solution
  int iterations = 0;
  std::string solver_report;
};

// Throws std::invalid_argument for contract violations: fewer than 8 samples, times not
// ascending, a profile that does not overlap the samples' time span, or one whose flow does not
// change there.
LagFitSummary FitLag(const FlowProfile& commanded, const std::vector<WidthSample>& samples,
                     const LagFitOptions& options);

}  // namespace clogscope::model
