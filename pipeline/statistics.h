#pragma once

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
