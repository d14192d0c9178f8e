#pragma once

// Mean and standard deviation of errors accumulated one at a time, for tests that compare a
// scatter with a truth or a reported σ.
#include <algorithm>
#include <cmath>

namespace clogscope::testing {

struct RunningStats {
  int n = 0;
  double s1 = 0, s2 = 0;
  void Add(double e) {
    ++n;
    s1 += e;
    s2 += e * e;
  }
  double mean() const { return s1 / n; }
  double sd() const { return std::sqrt(std::max(0.0, s2 / n - mean() * mean())); }
};

}  // namespace clogscope::testing
