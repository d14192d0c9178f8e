#pragma once

// The reference experiment's diameter series (../shared/spec/README.md) and predictor.md §6's
// measured amplitudes, shared by the model tests.
#include <vector>

#include "model/fit.h"
#include "model/predictor.h"

namespace clogscope::model::testing {

inline std::vector<StepInput> ReferenceSteps() {
  const double t[] = {220, 210, 200, 190, 180, 170};
  const double d_mm[] = {0.4000, 0.3969, 0.3901, 0.3813, 0.3659, 0.3454};
  std::vector<StepInput> steps;
  for (int i = 0; i < 6; ++i) steps.push_back({i + 1, t[i], d_mm[i] * 1e-3, 0, std::nullopt});
  return steps;
}

inline std::vector<Measurement> ExampleAmplitudes() {
  const double a[] = {0.6479, 0.6554, 0.6848, 0.7414, 0.8769, 1.1128};
  std::vector<Measurement> m;
  for (int i = 0; i < 6; ++i) {
    Measurement x;
    x.step = i + 1;
    x.amplitude_m_s2 = a[i];
    m.push_back(x);
  }
  return m;
}

}  // namespace clogscope::model::testing
