#pragma once

#include <string>
#include <vector>

namespace clogscope::calib {

// A pin gauge of certified diameter and the width the edge detector measured for it.
struct PinObservation {
  std::string name;  // image file, for reports
  double diameter_um = 0;
  double tolerance_um = 0;  // certified tolerance, taken as one standard deviation; 0 = none given
  double width_px = 0;
  double width_sigma_px = 0;  // standard error of width_px
};

// One line of a stage micrometer: its index along the scale and its measured centre.
struct LineObservation {
  int image = 0;  // which image: each has its own offset, all share the scale
  int index = 0;
  double position_px = 0;  // across the lines
  double sigma_px = 0;
};

struct ScaleFitOptions {
  bool fit_distortion = false;         // micrometer: add a second-order term
  double outlier_threshold_sigma = 4;  // |residual| beyond this many robust σ: an outlier
  int max_iterations = 100;
  bool Validate(std::string* why) const;
};

struct TargetResidual {
  std::string name;       // pin image, or "line k"
  double nominal_um = 0;  // pin diameter, or the line's position on the scale
  double measured_px = 0;
  double model_px = 0;
  double residual_px = 0;  // measured − model
  double residual_um = 0;
  bool outlier = false;
};

// A fitted pixel scale: width_um = (width_px − edge_bias_px) · scale_um_per_px.
struct ScaleCalibration {
  bool usable = false;
  std::string message;  // why not usable, or notes (e.g. the edge bias held at 0)
  std::string method;   // "pins" or "micrometer"
  double scale_um_per_px = 0;
  double scale_sigma_um_per_px = 0;
  double edge_bias_px = 0;
  double edge_bias_sigma_px = 0;
  bool edge_bias_fitted = false;
  double distortion_px = 0;  // micrometer, second-order term per index² (0 unless fitted)
  double distortion_sigma_px = 0;
  bool distortion_fitted = false;
  double rms_residual_px = 0, rms_residual_um = 0;
  double worst_residual_px = 0, worst_residual_um = 0;
  int outliers = 0;
  int targets = 0;
  std::vector<TargetResidual> residuals;

  // The pixel width in µm, and its standard deviation from the width's σ and the calibration's.
  double ToMicrons(double width_px) const;
  double MicronsSigma(double width_px, double width_sigma_px) const;
};

// Fits width_px = diameter_um / s + b jointly over all pins (Ceres, Huber loss scaled to the
// residuals' robust spread); with one pin b is held at 0. σ from ceres::Covariance scaled by the
// observed residual variance. Throws std::invalid_argument naming the pin for: no pins, a
// non-positive diameter or width, fewer distinct diameters than unknowns (all pins alike).
ScaleCalibration FitPinScale(const std::vector<PinObservation>& pins,
                             const ScaleFitOptions& options);

// Fits position_k = x_0,image + (k − k_mid)·pitch_um / s [+ d·(k − k_mid)²]: s is the scale at the
// middle line, shared by all images. Throws std::invalid_argument for a non-positive pitch, fewer
// lines than unknowns + 1, or an index repeated within an image.
ScaleCalibration FitMicrometerScale(const std::vector<LineObservation>& lines, double pitch_um,
                                    const ScaleFitOptions& options);

// Numbers lines found at `positions_px` (sorted) by the median spacing. Throws
// std::invalid_argument when the spacing is irregular (a line off its slot by more than a quarter
// spacing: the pitch cannot be fitted to these lines).
std::vector<LineObservation> IndexLines(const std::vector<double>& positions_px,
                                        const std::vector<double>& sigmas_px, int image = 0);

}  // namespace clogscope::calib
