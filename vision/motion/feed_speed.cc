#include "vision/motion/feed_speed.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/motion/profile_shift.h"

namespace clogscope::vision {
bool FeedSpeedOptions::Validate(std::string* why) const {
  if (!(inner_fraction > 0 && inner_fraction <= 1))
    *why = "inner fraction must be in (0, 1]";
  else if (!(max_shift_px >= 1 && max_shift_px <= 2000))
    *why = "maximum shift must be in [1, 2000] px";
  else if (!(min_texture_ratio > 0) || !(min_correlation > 0 && min_correlation < 1))
    *why = "texture ratio must be positive and correlation in (0, 1)";
  else if (!(highpass_sigma_px >= 2))
    *why = "high-pass scale must be at least 2 px";
  else if (!(smooth_sigma_px >= 0 && smooth_sigma_px <= 10))
    *why = "smoothing scale must be in [0, 10] px";
  else if (!(baseline_shift_px >= 0 && baseline_shift_px <= 1000) ||
           !(max_baseline_frames >= 1 && max_baseline_frames <= 300))
    *why = "baseline shift must be in [0, 1000] px and its frames in [1, 300]";
  else
    return true;
  return false;
}

const char* FeedShiftStatusName(FeedShiftStatus s) {
  switch (s) {
    case FeedShiftStatus::kValid:
      return "valid";
    case FeedShiftStatus::kNoTexture:
      return "no_texture";
    case FeedShiftStatus::kTooFast:
      return "too_fast";
    case FeedShiftStatus::kNoStrand:
      return "no_strand";
  }
  return "?";
}

AxisProfile SampleAxisProfile(const cv::Mat& grey, const StrandMeasurement& m,
                              const FeedSpeedOptions& o) {
  if (grey.channels() != 1 || (grey.depth() != CV_8U && grey.depth() != CV_16U)) {
    throw std::invalid_argument("feed speed: expected a one-channel 8- or 16-bit frame");
  }
  AxisProfile p;
  if (!m.has_geometry) return p;
  const double dx = m.axis_dx, dy = m.axis_dy;
  const double half = 0.5 * (m.right_u0_px - m.left_u0_px) * o.inner_fraction;
  const int lines = std::max(2, static_cast<int>(std::floor(2 * half)) + 1);
  auto point = [&](double s, int j, double* x, double* y) {
    const double u =
        0.5 * (m.left_u0_px + m.right_u0_px) + m.edge_slope * s - half + 2 * half * j / (lines - 1);
    *x = m.tip_x_px + s * dx + u * dy;
    *y = m.tip_y_px + s * dy - u * dx;
  };
  auto inside = [&](double x, double y) {
    return x >= 0 && y >= 0 && x < grey.cols - 1 && y < grey.rows - 1;
  };
  // The whole visible stretch, from the measurement origin (the tip, or the stretch's top) until
  // the axis leaves the frame: the longer the profile, the finer the shift. A cross line is inside
  // when both its ends are.
  const double s_end = m.band_end_px + std::hypot(grey.cols, grey.rows);
  int s0 = std::max(0, static_cast<int>(std::ceil(m.band_start_px))), s1 = s0 - 1;
  double xmin = grey.cols, xmax = 0, ymin = grey.rows, ymax = 0;
  for (int s = s0; s <= s_end; ++s) {
    double xa, ya, xb, yb;
    point(s, 0, &xa, &ya);
    point(s, lines - 1, &xb, &yb);
    const bool in = inside(xa, ya) && inside(xb, yb);
    if (!in && s1 >= s0) break;  // the stretch ends here
    if (!in) {
      s0 = s + 1;
      continue;
    }
    s1 = s;
    xmin = std::min({xmin, xa, xb});
    xmax = std::max({xmax, xa, xb});
    ymin = std::min({ymin, ya, yb});
    ymax = std::max({ymax, ya, yb});
  }
  const int n = s1 - s0 + 1;
  if (n < 32) return p;
  // Bilinear samples of the float copy of the region the lines cover (remap on 8-bit output would
  // round each sample to a whole grey level).
  const cv::Rect box(static_cast<int>(xmin), static_cast<int>(ymin),
                     static_cast<int>(xmax) - static_cast<int>(xmin) + 2,
                     static_cast<int>(ymax) - static_cast<int>(ymin) + 2);
  cv::Mat region;
  grey(box & cv::Rect(0, 0, grey.cols, grey.rows)).convertTo(region, CV_32F);
  cv::Mat map_x(lines, n, CV_32F), map_y(lines, n, CV_32F), samples;
  for (int j = 0; j < lines; ++j) {
    float* mx = map_x.ptr<float>(j);
    float* my = map_y.ptr<float>(j);
    for (int i = 0; i < n; ++i) {
      double x, y;
      point(s0 + i, j, &x, &y);
      mx[i] = static_cast<float>(x - box.x);
      my[i] = static_cast<float>(y - box.y);
    }
  }
  cv::remap(region, samples, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  std::vector<double> even(n, 0.0), odd(n, 0.0);
  for (int j = 0; j < lines; ++j) {
    const float* row = samples.ptr<float>(j);
    std::vector<double>& acc = j % 2 ? odd : even;
    for (int i = 0; i < n; ++i) acc[i] += row[i];
  }
  const int n_even = (lines + 1) / 2, n_odd = lines / 2;
  p.start_s_px = s0;
  p.values.resize(n);
  std::vector<double> diff(n);
  for (int i = 0; i < n; ++i) {
    p.values[i] = (even[i] + odd[i]) / lines;
    diff[i] = even[i] / n_even - odd[i] / n_odd;
  }
  // Interleaved halves of the width see the same surface and independent noise: the σ of one
  // value is about half the σ of their difference (what the surface does across the width counts
  // as noise, which errs on the safe side).
  p.noise = 0.5 * StdDev(HighPass(diff, o.highpass_sigma_px));
  return p;
}

PreparedAxisProfile PrepareAxisProfile(const AxisProfile& p, const FeedSpeedOptions& o) {
  PreparedAxisProfile out;
  out.start_s_px = p.start_s_px;
  out.samples = p.values.size();
  out.noise = p.noise;
  if (p.values.empty()) return out;
  const std::vector<double> high_passed = HighPass(p.values, o.highpass_sigma_px);
  out.texture_sd_grey = StdDev(high_passed);
  // Near the ends the high-pass sees a truncated window, which distorts the texture at fixed
  // places in the frame: compared there, that part stays put and pulls the shift toward zero
  // (−0.006 px, −0.02 % at 25 px per frame). Only the inner part is compared.
  const int edge = std::min(static_cast<int>(std::lround(2 * o.highpass_sigma_px)),
                            static_cast<int>(high_passed.size()) / 4);
  const std::vector<double> smooth = Smooth(high_passed, o.smooth_sigma_px);
  out.inner.assign(smooth.begin() + edge, smooth.end() - edge);
  return out;
}

AxisShift EstimateAxisShift(const AxisProfile& pa, const AxisProfile& pb,
                            const FeedSpeedOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument("feed speed: " + why);
  return EstimateAxisShift(PrepareAxisProfile(pa, o), PrepareAxisProfile(pb, o), o);
}

AxisShift EstimateAxisShift(const PreparedAxisProfile& pa, const PreparedAxisProfile& pb,
                            const FeedSpeedOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument("feed speed: " + why);
  AxisShift out;
  if (pa.samples == 0 || pb.samples == 0) {
    out.detail = "no stretch of filament to sample";
    return out;
  }
  if (pa.start_s_px != pb.start_s_px || pa.samples != pb.samples) {
    throw std::invalid_argument("feed speed: the two profiles must share their sampling");
  }
  const double noise = std::max(0.5 * (pa.noise + pb.noise), 1e-9);
  out.texture_ratio = pa.texture_sd_grey / noise;
  if (out.texture_ratio < o.min_texture_ratio) {
    out.status = FeedShiftStatus::kNoTexture;
    out.detail = fmt::format("surface texture σ is {:.1f}× its noise (needs {:g}×)",
                             out.texture_ratio, o.min_texture_ratio);
    return out;
  }
  const std::vector<double>& a = pa.inner;
  const std::vector<double>& b = pb.inner;
  const int n = static_cast<int>(a.size());
  // Whole pixels: b(s + k) = a(s) when the surface moved k px down the axis. At least half the
  // profile must overlap.
  const int limit = std::min(static_cast<int>(std::floor(o.max_shift_px)), n / 2);
  const WholeShift whole = BestWholeShift(a, b, limit, /*circular=*/false);
  const int best_k = whole.samples;
  const double best = whole.correlation;
  out.correlation = best;
  out.search_limit_px = limit;
  // The texture is strong (checked above): no match inside the range means it moved further.
  if (best < o.min_correlation || std::abs(best_k) >= limit) {
    out.status = FeedShiftStatus::kTooFast;
    out.detail = fmt::format(
        "no match of the surface within ±{} px between frames (best correlation {:.2f} at {:+d} "
        "px): it moved further, or changed",
        limit, best, best_k);
    return out;
  }
  const FineShift fine = RefineShift(a, b, best_k, /*circular=*/false);
  out.shift_px = fine.samples;
  out.sigma_px = fine.sigma;
  out.status = FeedShiftStatus::kValid;
  return out;
}

AxisShift EstimateFeedShift(const cv::Mat& grey_a, const cv::Mat& grey_b,
                            const StrandMeasurement& geometry, const FeedSpeedOptions& o) {
  return EstimateAxisShift(SampleAxisProfile(grey_a, geometry, o),
                           SampleAxisProfile(grey_b, geometry, o), o);
}

FeedSpeedTracker::FeedSpeedTracker(const FeedSpeedOptions& options) : options_(options) {
  std::string why;
  if (!options_.Validate(&why)) throw std::invalid_argument("feed speed: " + why);
}

namespace {

// A point of the centre line at s, in image coordinates.
cv::Point2d CentreAt(const StrandMeasurement& m, double s) {
  const double u = 0.5 * (m.left_u0_px + m.right_u0_px) + m.edge_slope * s;
  return {m.tip_x_px + s * m.axis_dx + u * m.axis_dy, m.tip_y_px + s * m.axis_dy - u * m.axis_dx};
}

// Whether `m`'s centre line and width still match `ref` where ref's stretch begins and ends: the
// centre lines within 3 % of the width (at least 0.3 px), the widths within 1 px. Both profiles
// of a comparison are sampled along ref, so ref only has to stay well inside the filament's inner
// part; a tighter rule renews it on the measurement's own noise (through H.264 the measured
// centre line of a filament at rest wanders by up to 1.9 px at the far end of a 450 px stretch),
// and each renewal forgets the frames a longer baseline needs.
bool SameGeometry(const StrandMeasurement& ref, const StrandMeasurement& m, double stretch_px) {
  if (!ref.has_geometry || !m.has_geometry) return false;
  const double width_ref = ref.right_u0_px - ref.left_u0_px, width_m = m.right_u0_px - m.left_u0_px;
  if (std::abs(width_ref - width_m) > 1.0) return false;
  const double tolerance_px = std::max(0.3, 0.03 * width_ref);
  // m's centre line through two of its points; the distance of ref's centre from it.
  const cv::Point2d a = CentreAt(m, 0), b = CentreAt(m, 100);
  const cv::Point2d d = (b - a) / cv::norm(b - a);
  for (double s : {ref.band_start_px, ref.band_start_px + stretch_px}) {
    const cv::Point2d q = CentreAt(ref, s) - a;
    if (std::abs(q.x * d.y - q.y * d.x) > tolerance_px) return false;
  }
  return true;
}

// How many frames back a frame should be compared with when the texture moved shift_px since
// the frame before: enough for baseline_shift_px (at most half the search range, so the longer
// shift stays well inside it), at most max_baseline_frames.
int WantedBaselineFrames(double shift_px, const FeedSpeedOptions& o) {
  const double target_px = std::min(o.baseline_shift_px, 0.5 * o.max_shift_px);
  const double per_frame_px = std::abs(shift_px);
  if (per_frame_px >= target_px) return 1;
  if (per_frame_px * o.max_baseline_frames <= target_px) return o.max_baseline_frames;
  return std::clamp(static_cast<int>(std::ceil(target_px / per_frame_px)), 1,
                    o.max_baseline_frames);
}

// A frame pair's shift status as the frame's reason for having no speed.
SpeedReason ReasonOf(FeedShiftStatus status) {
  switch (status) {
    case FeedShiftStatus::kValid:
      return SpeedReason::kNone;
    case FeedShiftStatus::kNoTexture:
      return SpeedReason::kNoTexture;
    case FeedShiftStatus::kTooFast:
      return SpeedReason::kTooFast;
    case FeedShiftStatus::kNoStrand:
      return SpeedReason::kNoStrand;
  }
  return SpeedReason::kNoStrand;
}

}  // namespace

const char* SpeedReasonName(SpeedReason reason) {
  switch (reason) {
    case SpeedReason::kNone:
      return "none";
    case SpeedReason::kFirstFrame:
      return "first_frame";
    case SpeedReason::kNoTime:
      return "no_time";
    case SpeedReason::kBadTime:
      return "bad_time";
    case SpeedReason::kNoStrand:
      return "no_strand";
    case SpeedReason::kNoTexture:
      return "no_texture";
    case SpeedReason::kTooFast:
      return "too_fast";
    case SpeedReason::kNoGear:
      return "no_gear";
  }
  return "?";
}

FeedSpeedSample FeedSpeedTracker::Next(const cv::Mat& frame, double time_s,
                                       const StrandMeasurement& m) {
  FeedSpeedSample out;
  cv::Mat grey;
  if (!frame.empty()) {
    if (frame.channels() == 1) {
      grey = frame.clone();
    } else {
      cv::cvtColor(frame, grey, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    }
  }
  const bool have_previous = !previous_.empty() && previous_t_ >= 0;
  bool sampled = false;
  if (time_s < 0) {
    out.reason = SpeedReason::kNoTime;
    out.detail = "still images have no frame times";
  } else if (!have_previous) {
    out.reason = SpeedReason::kFirstFrame;
    out.detail = "no frame before it";
  } else if (grey.empty() || grey.size() != previous_.size()) {
    out.reason = SpeedReason::kNoStrand;
    out.detail = "the frame could not be read";
  } else if (!(time_s > previous_t_)) {
    out.reason = SpeedReason::kBadTime;
    out.detail = fmt::format("timestamp {:g} s does not follow {:g} s", time_s, previous_t_);
  } else if (!previous_m_.valid()) {
    out.reason = SpeedReason::kNoStrand;
    out.detail = "no filament measured in the frame before";
  } else {
    sampled = true;
    const size_t stretch = history_.empty() ? 0 : history_.back().profile.samples;
    if (stretch == 0 || !SameGeometry(reference_, previous_m_, stretch)) {
      // The filament moved (or this is the first pair): a new reference, the previous frame
      // sampled along it; frames before it are not on this axis.
      reference_ = previous_m_;
      history_.clear();
      history_.push_back(
          {PrepareAxisProfile(SampleAxisProfile(previous_, reference_, options_), options_),
           previous_t_});
    }
    const PreparedAxisProfile current =
        PrepareAxisProfile(SampleAxisProfile(grey, reference_, options_), options_);
    const PreparedAxisProfile& before = history_.back().profile;
    const AxisShift shift = current.samples == before.samples
                                ? EstimateAxisShift(before, current, options_)
                                : AxisShift{};
    out.dt_s = time_s - previous_t_;
    out.search_limit_px = shift.search_limit_px;
    out.valid = shift.valid();
    out.reason = ReasonOf(shift.status);
    out.detail =
        shift.detail.empty() ? "the filament's stretch could not be sampled" : shift.detail;
    out.shift_px = shift.shift_px;
    out.sigma_px = shift.sigma_px;
    if (out.valid) {
      CompareFurtherBack(current, time_s, shift.shift_px, &out);
      shift_per_frame_px_ = out.shift_px / out.baseline_frames;
    }
    history_.push_back({current, time_s});
    while (static_cast<int>(history_.size()) > options_.max_baseline_frames) history_.pop_front();
  }
  if (!sampled) history_.clear();  // the next pair samples the frame before it afresh
  previous_ = grey;
  previous_m_ = m;
  previous_t_ = time_s;
  return out;
}

void FeedSpeedTracker::CompareFurtherBack(const PreparedAxisProfile& current, double time_s,
                                          double pair_shift_px, FeedSpeedSample* out) {
  out->baseline_frames = 1;
  // The baseline follows the speed of the rows before (this pair's own shift only when there are
  // none), and holds while that speed stays within a quarter of it: chosen from this frame's own
  // shift, a frame that looks behind would get the longer baseline and one ahead the shorter, a
  // bias (−0.09 % at 1.33 px per frame through MJPEG); held, every frame ends one comparison and
  // starts another, and its own error cancels along the video.
  const int wanted = WantedBaselineFrames(
      std::isnan(shift_per_frame_px_) ? pair_shift_px : shift_per_frame_px_, options_);
  if (!(baseline_frames_ > 0 &&
        std::abs(wanted - baseline_frames_) <= std::max(1, baseline_frames_ / 4))) {
    baseline_frames_ = wanted;
  }
  out->wanted_baseline_frames = baseline_frames_;
  const int k = std::min(baseline_frames_, static_cast<int>(history_.size()));
  const PastFrame& far = history_[history_.size() - k];
  if (k <= 1 || far.profile.samples != current.samples) return;
  const AxisShift longer = EstimateAxisShift(far.profile, current, options_);
  // The two must agree on the movement (a loose check: a wrong whole-pixel match is several px
  // off, k times the frame pair's own error is a fraction of that).
  const double expected_px = k * pair_shift_px;
  if (!(longer.valid() &&
        std::abs(longer.shift_px - expected_px) <= 2 + 0.5 * std::abs(expected_px))) {
    return;
  }
  out->shift_px = longer.shift_px;
  out->sigma_px = longer.sigma_px;
  out->dt_s = time_s - far.time_s;
  out->baseline_frames = k;
}

}  // namespace clogscope::vision
