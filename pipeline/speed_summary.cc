#include "pipeline/speed_summary.h"

#include <algorithm>
#include <cmath>

#include "pipeline/statistics.h"

namespace clogscope::pipeline {

const char* SpeedUseName(SpeedUse u) {
  switch (u) {
    case SpeedUse::kUsed:
      return "used";
    case SpeedUse::kNoSpeed:
      return "no_speed";
    case SpeedUse::kShortBaseline:
      return "short_baseline";
    case SpeedUse::kOutlier:
      return "outlier";
  }
  return "?";
}

FeedSpeedSummary SummariseFeedSpeeds(const std::vector<vision::FeedSpeedSample>& samples) {
  FeedSpeedSummary s;
  s.use.assign(samples.size(), SpeedUse::kNoSpeed);
  bool any_full = false;
  for (const vision::FeedSpeedSample& v : samples) {
    if (v.reason != vision::SpeedReason::kFirstFrame && v.reason != vision::SpeedReason::kNoTime)
      ++s.pairs;
    if (!v.valid) continue;
    ++s.with_speed;
    any_full = any_full || v.baseline_frames >= v.wanted_baseline_frames;
  }
  std::vector<size_t> rows;
  std::vector<double> speeds;
  for (size_t i = 0; i < samples.size(); ++i) {
    const vision::FeedSpeedSample& v = samples[i];
    if (!v.valid) continue;
    if (any_full && v.baseline_frames < v.wanted_baseline_frames) {
      s.use[i] = SpeedUse::kShortBaseline;
      ++s.short_baseline;
      continue;
    }
    rows.push_back(i);
    speeds.push_back(v.SpeedPxPerS());
  }
  if (speeds.empty()) return s;
  const SampleStats st = RobustStats(speeds);
  double sum_sigma2 = 0;  // of the used rows' own σ, px²/s²
  for (size_t j = 0; j < rows.size(); ++j) {
    s.use[rows[j]] = st.used[j] ? SpeedUse::kUsed : SpeedUse::kOutlier;
    if (!st.used[j]) continue;
    const vision::FeedSpeedSample& v = samples[rows[j]];
    s.baseline_frames = std::max(s.baseline_frames, v.baseline_frames);
    sum_sigma2 += std::pow(v.SigmaPxPerS(), 2);
  }
  s.used = st.n_used;
  s.outliers = st.n_rejected;
  s.mean_px_per_s = st.mean;
  s.std_px_per_s = st.std;
  if (s.used < 2) return s;
  // Rows k frames apart overlap. Along a run of consecutive used rows with baseline k the sum of
  // their shifts telescopes to (the run's last k frames' positions − its first k frames'), so a
  // run of L rows adds at most min(L, k)²·sd² to the variance of the sum: when the k frames at
  // either end err together, as codecs make them (an H.264 frame's texture is its reference
  // frame's, moved by quantised motion vectors). Were the frames' errors independent it would add
  // min(L, k)·sd², under the L·sd² the plain formula assumes. The interval takes the larger of
  // n·sd² and the worst case summed over the runs (a run ends where a row is left out, e.g. where
  // the tracker renewed its reference axis); the worst case wins at slow feeds in short videos.
  double worst_case = 0;
  for (size_t i = 0; i < samples.size();) {
    if (s.use[i] != SpeedUse::kUsed) {
      ++i;
      continue;
    }
    int run = 0, k = 1;
    for (; i < samples.size() && s.use[i] == SpeedUse::kUsed; ++i, ++run)
      k = std::max(k, samples[i].baseline_frames);
    worst_case += std::pow(std::min(run, k), 2);
  }
  const double n = s.used;
  const double sem = s.std_px_per_s * std::sqrt(std::max(n, worst_case)) / n;
  s.ci95_px_per_s = StudentT975(s.used - 1) * sem;
  // The rows' own σ (from the residuals of each comparison) misses what a codec does to a whole
  // frame (an H.264 frame's texture sits where its motion vectors put it): when the used rows
  // scatter more than their σ say, the σ are scaled up to that scatter.
  const double rms_sigma = std::sqrt(sum_sigma2 / n);
  if (rms_sigma > 0) s.sigma_scale = std::max(1.0, s.std_px_per_s / rms_sigma);
  return s;
}

}  // namespace clogscope::pipeline
