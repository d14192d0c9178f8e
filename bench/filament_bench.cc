// clogscope_bench filament VIDEO [--pi]: the filament path on a video of one's own.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "bench/pi_budget.h"
#include "pipeline/band.h"
#include "vision/io/frame_source.h"
#include "vision/scene/batch.h"
#include "vision/scene/strand_measure.h"

using clogscope::bench::PiCells;
using clogscope::bench::TableHead;
using clogscope::vision::StrandMeasureOptions;
using Clock = std::chrono::steady_clock;

// The filament path (`measure --target filament`) on a video of one's own (issue 26 quotes
// Greeff's, ../shared/real/greeff/): tracked frames per second on one core, as `measure` reads it.
void BenchFilament(const std::string& path) {
  namespace vision = clogscope::vision;
  cv::setNumThreads(1);
  StrandMeasureOptions opt;
  opt.target = vision::MeasureTarget::kFilament;
  clogscope::pipeline::ApplyBandPx(clogscope::pipeline::BandRequest{}, std::nullopt, &opt);
  constexpr int kRounds = 3;
  std::vector<double> fps;
  int n = 0, valid = 0;
  double sum = 0;
  for (int r = 0; r < kRounds; ++r) {
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
  std::sort(fps.begin(), fps.end());
  fmt::print("\n## Filament path on {} (decode + measure, one core, median of {})\n\n{}", path,
             kRounds, TableHead("| frames | frames/s |", "|---|---|"));
  fmt::print("| {} of {} valid, mean width {:.3f} px | {:.0f} |{}\n", valid, n,
             valid ? sum / valid : 0.0, fps[kRounds / 2], PiCells(fps[kRounds / 2]));
}
