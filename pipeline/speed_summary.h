#pragma once

// A video's feed speed from its rows (one FeedSpeedSample per frame): which rows the summary uses
// and why it leaves the others out, their mean and its 95 % interval. `measure` logs it and marks
// the rows of its table with it.
#include <vector>

#include "vision/motion/feed_speed.h"

namespace clogscope::pipeline {

enum class SpeedUse {
  kUsed,
  kNoSpeed,        // the row has no speed (its reason says why; the first frame has none)
  kShortBaseline,  // compared with a frame nearer than its speed wants (early in a video, or just
                   // after the filament moved): the codec's fixed-pattern pull is not yet divided
  kOutlier,        // over 3.5 robust σ from the median of the others
};
const char* SpeedUseName(SpeedUse u);  // "used", "no_speed", "short_baseline", "outlier"

struct FeedSpeedSummary {
  std::vector<SpeedUse> use;  // one per sample, in order
  int pairs = 0;              // samples that compare two frames (not first_frame or no_time)
  int with_speed = 0;         // … that have a speed
  int used = 0, short_baseline = 0, outliers = 0;
  int baseline_frames = 0;   // the longest baseline among the used rows
  double mean_px_per_s = 0;  // exactly the mean of the used rows' speeds
  double std_px_per_s = 0;   // their standard deviation (0 under 2 rows)
  double ci95_px_per_s = 0;  // half-width of the mean's 95 % interval (0 under 2 rows)
  // What the rows' own σ are multiplied by to match the used rows' scatter (1 when they already
  // cover it).
  double sigma_scale = 1;
  // A row's σ as the summary sees it: its own, times sigma_scale.
  double RowSigmaPxPerS(const vision::FeedSpeedSample& row) const {
    return row.SigmaPxPerS() * sigma_scale;
  }
};

// Rows with a speed whose baseline is shorter than they want are left out when any row reaches
// its own; of the rest, outliers (median ± 3.5·1.4826·MAD) are left out. The interval is Student's
// t (n − 1) on the used rows' scatter, allowing for the overlap of their baselines (see .cc).
FeedSpeedSummary SummariseFeedSpeeds(const std::vector<vision::FeedSpeedSample>& samples);

}  // namespace clogscope::pipeline
