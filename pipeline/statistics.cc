#include "pipeline/statistics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/robust.h"

namespace clogscope::pipeline {

double StudentT975(int dof) {
  static const double kTable[] = {0, 12.7062047, 4.30265273, 3.18244631, 2.77644511, 2.57058184};
  if (dof < 1) return NAN;
  if (dof <= 5) return kTable[dof];
  const double z = kZ95, v = dof;
  const double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z, z9 = z7 * z * z;
  return z + (z3 + z) / (4 * v) + (5 * z5 + 16 * z3 + 3 * z) / (96 * v * v) +
         (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * v * v * v) +
         (79 * z9 + 776 * z7 + 1482 * z5 - 1920 * z3 - 945 * z) / (92160 * v * v * v * v);
}

SampleStats RobustStats(const std::vector<double>& values, double k, double min_mad) {
  SampleStats s;
  s.used.assign(values.size(), false);
  if (values.empty()) return s;
  const double med = Median(values);
  std::vector<double> dev;
  for (double v : values) dev.push_back(std::abs(v - med));
  const double mad = std::max(Median(dev), min_mad);
  double sum = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    s.used[i] = values.size() < 3 || std::abs(values[i] - med) <= k * kMadToSigma * mad;
    if (s.used[i]) {
      sum += values[i];
      ++s.n_used;
    }
  }
  s.n_rejected = static_cast<int>(values.size()) - s.n_used;
  s.mean = sum / s.n_used;
  double ss = 0;
  for (size_t i = 0; i < values.size(); ++i) {
    if (s.used[i]) ss += (values[i] - s.mean) * (values[i] - s.mean);
  }
  if (s.n_used >= 2) {
    s.std = std::sqrt(ss / (s.n_used - 1));
    s.sem = s.std / std::sqrt(s.n_used);
    s.ci95_half_width = StudentT975(s.n_used - 1) * s.sem;
  }
  return s;
}

WidthStats RobustWidthStats(const FrameWidths& frames, double k, double min_mad) {
  WidthStats out;
  static_cast<SampleStats&>(out) = RobustStats(frames.width, k, min_mad);
  if (out.n_used == 0) return out;
  std::vector<double> model, noise;
  for (size_t i = 0; i < frames.width.size(); ++i) {
    if (!out.used[i]) continue;
    const double m = std::min(frames.model_sigma[i], frames.width_sigma[i]);
    model.push_back(m);
    noise.push_back(std::sqrt(frames.width_sigma[i] * frames.width_sigma[i] - m * m));
  }
  out.model_sigma = Median(model);
  out.noise_sigma = Median(noise);
  // Under independence the sample σ of n ≥ 20 frames falls below half the frames' own noise with
  // a probability below 4e-4 (χ² with n − 1 degrees of freedom; 2e-8 at 50): the frames repeat
  // each other.
  out.frames_repeat = out.n_used >= kMinRepeatFrames && out.std < 0.5 * out.noise_sigma;
  if (out.frames_repeat) out.sem = out.noise_sigma;
  if (out.n_used >= 2) {
    out.ci95_half_width = std::hypot(StudentT975(out.n_used - 1) * out.sem, kZ95 * out.model_sigma);
  }
  return out;
}

std::string RepeatDetail(const WidthStats& st) {
  return fmt::format(
      "the frames repeat each other (widths scatter {:.4f} px against their noise {:.4f} px): "
      "their mean counts as one frame",
      st.std, st.noise_sigma);
}

std::vector<HoldSegment> FindHolds(const std::vector<TemperatureSample>& log, double tol,
                                   double settle_s, double min_hold_s) {
  std::vector<HoldSegment> out;
  size_t i = 0;
  while (i < log.size()) {
    // Grow a run while each reading stays within ±tol of the run's median (robust to a lone spike
    // at the start of a run).
    std::vector<double> temps = {log[i].temperature_c};
    size_t j = i + 1;
    while (j < log.size()) {
      const double med = Median(temps);
      if (std::abs(log[j].temperature_c - med) > tol) break;
      temps.push_back(log[j].temperature_c);
      ++j;
    }
    const double start = log[i].time_s + settle_s;
    const double end = log[j - 1].time_s;
    if (end - start >= min_hold_s) {
      double sum = 0;
      int n = 0;
      for (size_t k = i; k < j; ++k) {
        if (log[k].time_s >= start) {
          sum += log[k].temperature_c;
          ++n;
        }
      }
      out.push_back({start, end, n ? sum / n : Median(temps)});
    }
    i = j;
  }
  return out;
}

}  // namespace clogscope::pipeline
