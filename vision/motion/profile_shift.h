#pragma once

// The shift between two sampled 1-D profiles of the same surface, b(x + d) = a(x): whole samples
// by normalised cross-correlation, then a fraction of a sample by Gauss–Newton on both profiles
// interpolated half-way (interpolating cubic B-splines: their phase error is small enough that
// a fractional shift repeated frame after frame, as at a slow feed, leaves no bias to speak of).
// Open profiles compare where they overlap; circular ones (an angle around a gear) wrap.
#include <vector>

namespace clogscope::vision {

struct WholeShift {
  int samples = 0;          // the best whole-sample shift
  double correlation = -1;  // its normalised cross-correlation
};
// Searches [-limit, limit]; an open profile needs at least half of it to overlap.
WholeShift BestWholeShift(const std::vector<double>& a, const std::vector<double>& b, int limit,
                          bool circular);

struct FineShift {
  double samples = 0;
  double sigma = 0;  // from the residuals and the profiles' gradient energy; NaN when undefined
};
FineShift RefineShift(const std::vector<double>& a, const std::vector<double>& b, double start,
                      bool circular);

// Removes what varies slower than sigma samples (three box passes, O(n)); the ends use the samples
// inside.
std::vector<double> HighPass(const std::vector<double>& v, double sigma);
// Gaussian smoothing over ±3.5σ, renormalised where the kernel runs past an end; σ ≤ 0: a copy.
std::vector<double> Smooth(const std::vector<double>& v, double sigma);
double StdDev(const std::vector<double>& v);

}  // namespace clogscope::vision
