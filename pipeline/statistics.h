#pragma once

#include <string>
#include <vector>

namespace clogscope::pipeline {

// Two-sided 95 % quantile of Student's t with `dof` degrees of freedom (exact table to 5, then a
// Cornish–Fisher expansion, within 1e-4 of the exact value).
double StudentT975(int dof);

// A step's widths after robust outlier rejection.
struct SampleStats {
  int n_used = 0;
  int n_rejected = 0;
  double mean = 0;
  double std = 0;              // sample standard deviation (n − 1)
  double sem = 0;              // std / √n
  double ci95_half_width = 0;  // t(0.975, n − 1) · sem
  std::vector<bool> used;      // per input value
};

// Rejects values farther than k·1.4826·MAD from the median (with MAD floored at min_mad so
// identical values do not make every tiny difference an outlier), then summarises the rest.
SampleStats RobustStats(const std::vector<double>& values, double k = 3.5, double min_mad = 0.0);

// Frames of one scene, summarised with what their own σ say beside their scatter (mrcal's honest
// uncertainty for a mean):
// - the edge model's doubt (each frame's model_sigma_px: shading, structure, tip) is the scene's,
//   the same in every frame, and does not average down: it adds to the mean's σ as it is;
// - frames whose widths scatter far less than their own noise predicts are not independent
//   draws (a codec's skipped blocks repeat one frame's noise and edges on a still scene): their
//   mean is worth one frame, so its standard error is one frame's noise.
struct FrameWidths {
  std::vector<double> width;        // each frame's width
  std::vector<double> width_sigma;  // its whole σ
  std::vector<double> model_sigma;  // the model part of it (≤ width_sigma)
  void Add(double width_px, double sigma_px, double model_sigma_px) {
    width.push_back(width_px);
    width_sigma.push_back(sigma_px);
    model_sigma.push_back(model_sigma_px);
  }
};
struct WidthStats : SampleStats {
  double model_sigma = 0;      // median model σ of the used frames
  double noise_sigma = 0;      // median of the used frames' σ without their model part
  bool frames_repeat = false;  // the scatter is below half of noise_sigma (n ≥ kMinRepeatFrames)
};
inline constexpr int kMinRepeatFrames = 20;
// RobustStats on the widths, then the above: sem is noise_sigma when the frames repeat, and
// ci95_half_width is t·sem ⊕ 1.96·model_sigma.
WidthStats RobustWidthStats(const FrameWidths& frames, double k = 3.5, double min_mad = 0.0);
// Says so when they repeat: "the frames repeat each other (widths scatter 0.004 px against their
// noise 0.070 px): their mean counts as one frame".
std::string RepeatDetail(const WidthStats& st);

// One reading of the printer's temperature log.
struct TemperatureSample {
  double time_s = 0;
  double temperature_c = 0;
};

// A stretch of the log where the temperature holds.
struct HoldSegment {
  double start_s = 0;  // after the settle time
  double end_s = 0;
  double temperature_c = 0;  // mean over the held part
};

// Cuts the log into holds: maximal runs where every reading stays within ±tolerance_c of the run's
// running median, minus the first settle_s; runs shorter than min_hold_s after settling are
// dropped. The log must be sorted by time.
std::vector<HoldSegment> FindHolds(const std::vector<TemperatureSample>& log, double tolerance_c,
                                   double settle_s, double min_hold_s);

}  // namespace clogscope::pipeline
