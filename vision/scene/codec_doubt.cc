#include "vision/scene/codec_doubt.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace clogscope::vision {
namespace {

constexpr int kMacroblockPx = 16;
// Beyond the outer edges: the calipers' windows and the outside's self-check, at any blur.
constexpr double kMarginPx = 16.0;
constexpr double kMarginBlurs = 4.0;
constexpr int kMinPairedCalipers = 5;  // fewer: the shift's noise is not known
constexpr double kSamePlacePx = 0.5;   // calipers this close along the axis are the same place

// The frame's region around the strand from its tip to the band's end, widened to whole
// macroblocks: the second pass's blocks then lie where the stream's did.
cv::Rect StrandRegion(const StrandMeasurement& m, const cv::Size& frame) {
  const double margin = kMarginPx + kMarginBlurs * m.blur_px;
  const double s0 = std::min(0.0, m.band_start_px) - margin, s1 = m.band_end_px + margin;
  double x0 = 1e18, y0 = 1e18, x1 = -1e18, y1 = -1e18;
  for (const double s : {s0, s1}) {
    for (const double u :
         {m.left_u0_px + m.edge_slope * s - margin, m.right_u0_px + m.edge_slope * s + margin}) {
      const double x = m.tip_x_px + s * m.axis_dx + u * m.axis_dy;
      const double y = m.tip_y_px + s * m.axis_dy - u * m.axis_dx;
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  auto down = [](double v, int limit) {
    return std::clamp(static_cast<int>(std::floor(v / kMacroblockPx)) * kMacroblockPx, 0, limit);
  };
  auto up = [](double v, int limit) {
    return std::clamp(static_cast<int>(std::ceil(v / kMacroblockPx)) * kMacroblockPx, 0, limit);
  };
  const int left = down(x0, frame.width), top = down(y0, frame.height);
  // 4:2:0 wants even sizes: a frame of odd size loses its last column or row.
  const int width = (up(x1, frame.width) - left) & ~1, height = (up(y1, frame.height) - top) & ~1;
  return {left, top, width, height};
}

// One second pass of `region` through the round trip, measured afresh and compared with `first`.
CodecCheck SecondPass(const cv::Mat& frame, const StrandMeasureOptions& options,
                      const StrandMeasurement& first, const cv::Rect& region,
                      X264RoundTrip* round_trip) {
  CodecCheck out;
  cv::Mat second = frame.clone();
  // x264 given its own decoded luma leaves it nearly where it was (its coefficients quantise to
  // where they did), and the pass would say the codec moved nothing: limited-range luma goes in
  // stretched to the full range, which it quantises afresh, as the first pass did. (Matrix seed
  // 109, a lit strand with a third of its noise: 0.34 px narrow at σ 0.08; the pass on the luma as
  // stored moved it 0.03-0.05 px, stretched 0.15-0.38.)
  if (options.luma_range == LumaRange::kLimited && frame.channels() == 1) {
    const double gain = 255.0 / (kLimitedWhite8 - kLimitedBlack8);
    cv::Mat full;
    frame(region).convertTo(full, CV_8U, gain, -kLimitedBlack8 * gain);
    round_trip->Apply(full).convertTo(second(region), CV_8U, 1 / gain, kLimitedBlack8);
  } else {
    round_trip->Apply(frame(region)).copyTo(second(region));
  }
  // Found and measured afresh, as the first: a codec that tips the choice of object, channel or
  // tip moves the width by that choice, and that is doubt too.
  const StrandMeasurement again = MeasureStrand(second, options);
  out.second_pass_status = again.status;
  if (!again.gave_width()) {
    out.outcome = CodecCheck::Outcome::kLostInSecondPass;
    return out;
  }
  out.outcome = CodecCheck::Outcome::kDone;
  out.shift_px = again.width_px - first.width_px;
  // Calipers in both, paired by their place along the axis (a tip that moved moves the band).
  double sum = 0, sum2 = 0;
  int n = 0;
  size_t j = 0;
  for (const Caliper& a : first.calipers) {
    while (j < again.calipers.size() && again.calipers[j].s_px < a.s_px - kSamePlacePx) ++j;
    if (j == again.calipers.size()) break;
    const Caliper& b = again.calipers[j];
    if (std::abs(b.s_px - a.s_px) > kSamePlacePx || !a.inlier || !b.inlier) continue;
    const double d = b.width_px - a.width_px;
    sum += d, sum2 += d * d, ++n;
  }
  if (n >= kMinPairedCalipers)
    out.shift_sigma_px = std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1)) / n);
  return out;
}

}  // namespace

CodecCheck CheckCodec(const cv::Mat& frame, const StrandMeasureOptions& options,
                      X264RoundTrip* round_trip) {
  CodecCheck out;
  if (frame.depth() != CV_8U || (frame.channels() != 1 && frame.channels() != 3)) return out;
  const StrandMeasurement first = MeasureStrand(frame, options);
  if (!first.gave_width() || !first.has_geometry) return out;
  const cv::Rect region = StrandRegion(first, frame.size());
  if (region.width < kMacroblockPx || region.height < kMacroblockPx) return out;
  out = SecondPass(frame, options, first, region, round_trip);
  if (!out.done()) return out;
  // And on a grid half a macroblock off the stream's. On its own grid x264 may repeat what it
  // quantised there and leave the width where it was: matrix scene plain 4787 (H.264, a lit
  // 31.8 px strand) came out 0.31 px narrow in all four frames, 0.2 px of it the codec's; the
  // pass on the stream's grid moved frames 0-3 by 0.24, 0.27, 0.02 and 0.00 px, and the last two
  // went out valid at σ 0.06. Off the grid: 0.23, 0.07, 0.20, 0.21.
  constexpr int kHalfBlockPx = kMacroblockPx / 2;
  cv::Rect off(region.x - kHalfBlockPx, region.y - kHalfBlockPx, region.width + kHalfBlockPx,
               region.height + kHalfBlockPx);
  off &= cv::Rect(0, 0, frame.cols, frame.rows);
  off.width &= ~1;  // 4:2:0 wants even sizes
  off.height &= ~1;
  const CodecCheck shifted = SecondPass(frame, options, first, off, round_trip);
  if (shifted.done()) out.off_grid_doubt_px = shifted.DoubtPx();
  return out;
}

double CodecCheck::DoubtPx() const {
  if (!done()) return 0;
  const double on_grid =
      shift_sigma_px < 0
          ? std::abs(shift_px)
          : std::sqrt(std::max(0.0, shift_px * shift_px - shift_sigma_px * shift_sigma_px));
  return std::max(on_grid, off_grid_doubt_px);
}

CodecDoubt::CodecDoubt(const X264Settings& encoder, int check_every_frames)
    : round_trip_(encoder), every_(check_every_frames) {
  if (check_every_frames < 1)
    throw std::invalid_argument("codec doubt: check_every_frames must be at least 1");
}

void CodecDoubt::Reset() {
  until_check_ = failed_ = attempts_ = checks_ = 0;
  sum2_px2_ = 0;
}

void CodecDoubt::Apply(const cv::Mat& frame, const StrandMeasureOptions& options,
                       StrandMeasurement* m) {
  if (!m->gave_width()) return;
  if (until_check_ > 0) {
    --until_check_;
  } else {
    ++attempts_;
    const CodecCheck check = CheckCodec(frame, options, &round_trip_);
    if (check.done()) {
      sum2_px2_ += check.DoubtPx() * check.DoubtPx();
      ++checks_;
      failed_ = 0;
      until_check_ = every_ - 1;
    } else {
      // Tried again soon, but not every frame: a check costs two searches and an encode.
      ++failed_;
      until_check_ = std::min(1 << std::min(failed_ - 1, 20), every_) - 1;
    }
  }
  if (checks_ == 0) return;
  m->codec_sigma_px = doubt_px();
  CombineSigmas(m);
  JudgePrecision(options, m);
}

}  // namespace clogscope::vision
