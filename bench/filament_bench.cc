// clogscope_bench filament VIDEO [--pi]: the filament path on a video of one's own.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "bench/decode_timing.h"
#include "bench/pi_budget.h"
#include "common/robust.h"
#include "pipeline/band.h"
#include "vision/io/frame_source.h"
#include "vision/scene/batch.h"
#include "vision/scene/strand_measure.h"

using clogscope::Median;
using clogscope::bench::DecodeOnlyFps;
using clogscope::bench::PiCells;
using clogscope::bench::TableHead;
using clogscope::vision::StrandMeasureOptions;
using Clock = std::chrono::steady_clock;

// The filament path (`measure --target filament`) on a video of one's own (issue 26 quotes
// Greeff's, ../shared/real/greeff/): tracked frames per second on one core, as `measure` reads it,
// against decoding alone on one core (the passes alternate; medians).
void BenchFilament(const std::string& path) {
  namespace vision = clogscope::vision;
  cv::setNumThreads(1);
  StrandMeasureOptions opt;
  opt.target = vision::MeasureTarget::kFilament;
  clogscope::pipeline::ApplyBandPx(clogscope::pipeline::BandRequest{}, std::nullopt, &opt);
  constexpr int kRounds = 3;
  std::vector<double> fps, decode_fps;
  int n = 0, valid = 0;
  double sum = 0;
  for (int r = 0; r < kRounds; ++r) {
    decode_fps.push_back(DecodeOnlyFps(path, 1));
    auto src = vision::FrameSource::Open(path);
    valid = 0;
    sum = 0;
    const auto t0 = Clock::now();
    n = vision::MeasureFrames(*src, opt, [&](vision::InputFrame&, vision::StrandMeasurement& m) {
      if (!m.valid()) return;
      ++valid;
      sum += m.width_px;
    });
    fps.push_back(n / std::chrono::duration<double>(Clock::now() - t0).count());
  }
  const double measure = Median(fps), decode = Median(decode_fps);
  fmt::print("\n## Filament path on {} (one core, median of {})\n\n{}", path, kRounds,
             TableHead("| pass | frames/s |", "|---|---|"));
  fmt::print("| decode only (clogscope reader, one thread) | {:.0f} |{}\n", decode,
             PiCells(decode));
  fmt::print("| decode + measure: {} of {} valid, mean width {:.3f} px | {:.0f} |{}\n", valid, n,
             valid ? sum / valid : 0.0, measure, PiCells(measure));
  // On two cores `measure` decodes on a thread of its own: the measuring alone then sets the pace.
  const double gap_s = 1.0 / measure - 1.0 / decode;
  const double measuring_alone = gap_s > 0 ? 1.0 / gap_s : std::numeric_limits<double>::infinity();
  fmt::print(
      "\nmeasure / decode-only: **{:.2f}** on one core; with the decoding on a core of its own "
      "(as `measure` runs on two), at most {:.2f} (measuring alone: {:.0f} frames/s)\n",
      measure / decode, std::min(1.0, measuring_alone / decode), measuring_alone);
}
