#include "vision/feed_speed.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace clogscope::vision {
namespace {

template <typename T>
double Bilinear(const cv::Mat& img, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  const T* r0 = img.ptr<T>(y0);
  const T* r1 = img.ptr<T>(y0 + 1);
  return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) +
         fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

// Removes what varies slower than sigma (illumination along the axis): the value minus its
// Gaussian-weighted local mean, normalised near the ends so they are not pulled toward zero.
std::vector<double> HighPass(const std::vector<double>& v, double sigma) {
  const int n = static_cast<int>(v.size());
  const int size = 2 * static_cast<int>(std::ceil(3 * sigma)) + 1;
  cv::Mat values(1, n, CV_64F, const_cast<double*>(v.data())), ones(1, n, CV_64F, cv::Scalar(1));
  cv::Mat mean, weight;
  cv::GaussianBlur(values, mean, cv::Size(size, 1), sigma, 0, cv::BORDER_CONSTANT);
  cv::GaussianBlur(ones, weight, cv::Size(size, 1), sigma, 0, cv::BORDER_CONSTANT);
  std::vector<double> out(n);
  for (int i = 0; i < n; ++i) out[i] = v[i] - mean.at<double>(i) / weight.at<double>(i);
  return out;
}

// Catmull–Rom interpolation and its derivative at x (1 ≤ x < n − 2).
void Cubic(const std::vector<double>& v, double x, double* value, double* slope) {
  const int i = static_cast<int>(std::floor(x));
  const double t = x - i;
  const double p0 = v[i - 1], p1 = v[i], p2 = v[i + 1], p3 = v[i + 2];
  const double a = -0.5 * p0 + 1.5 * p1 - 1.5 * p2 + 0.5 * p3;
  const double b = p0 - 2.5 * p1 + 2 * p2 - 0.5 * p3;
  const double c = -0.5 * p0 + 0.5 * p2;
  *value = ((a * t + b) * t + c) * t + p1;
  *slope = (3 * a * t + 2 * b) * t + c;
}

double StdDev(const std::vector<double>& v) {
  double m = 0, q = 0;
  for (double x : v) m += x / v.size();
  for (double x : v) q += (x - m) * (x - m);
  return v.size() > 1 ? std::sqrt(q / (v.size() - 1)) : 0.0;
}

}  // namespace

bool FeedSpeedOptions::Validate(std::string* why) const {
  if (!(inner_fraction > 0 && inner_fraction <= 1))
    *why = "inner fraction must be in (0, 1]";
  else if (!(max_shift_px >= 1 && max_shift_px <= 2000))
    *why = "maximum shift must be in [1, 2000] px";
  else if (!(min_texture_ratio > 0) || !(min_correlation > 0 && min_correlation < 1))
    *why = "texture ratio must be positive and correlation in (0, 1)";
  else if (!(highpass_sigma_px >= 2))
    *why = "high-pass scale must be at least 2 px";
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
  std::vector<double> even, odd;
  const bool wide = grey.depth() == CV_16U;
  // The whole visible stretch, from the measurement origin (the tip, or the stretch's top) until
  // the axis leaves the frame: the longer the profile, the finer the shift.
  const double s_end = m.band_end_px + std::hypot(grey.cols, grey.rows);
  for (int s = std::max(0, static_cast<int>(std::ceil(m.band_start_px))); s <= s_end; ++s) {
    const double uc = 0.5 * (m.left_u0_px + m.right_u0_px) + m.edge_slope * s;
    double sum[2] = {0, 0};
    int count[2] = {0, 0};
    bool inside = true;
    for (int j = 0; j < lines && inside; ++j) {
      const double u = uc - half + 2 * half * j / (lines - 1);
      const double x = m.tip_x_px + s * dx + u * dy, y = m.tip_y_px + s * dy - u * dx;
      inside = x >= 0 && y >= 0 && x < grey.cols - 1 && y < grey.rows - 1;
      if (!inside) break;
      sum[j % 2] += wide ? Bilinear<uint16_t>(grey, x, y) : Bilinear<uint8_t>(grey, x, y);
      ++count[j % 2];
    }
    if (!inside) {  // the band leaves the frame here: keep the stretch sampled so far
      if (!p.values.empty()) break;
      continue;
    }
    if (p.values.empty()) p.start_s_px = s;
    p.values.push_back((sum[0] + sum[1]) / (count[0] + count[1]));
    even.push_back(sum[0] / count[0]);
    odd.push_back(sum[1] / count[1]);
  }
  if (p.values.size() < 32) return {};
  // Interleaved halves of the width see the same surface and independent noise: the σ of one
  // value is half the σ of their difference (what the surface does across the width counts as
  // noise, which errs on the safe side).
  std::vector<double> diff(even.size());
  for (size_t i = 0; i < diff.size(); ++i) diff[i] = even[i] - odd[i];
  p.noise = 0.5 * StdDev(HighPass(diff, o.highpass_sigma_px));
  return p;
}

AxisShift EstimateAxisShift(const AxisProfile& pa, const AxisProfile& pb,
                            const FeedSpeedOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument("feed speed: " + why);
  AxisShift out;
  if (pa.values.empty() || pb.values.empty()) {
    out.detail = "no stretch of filament to sample";
    return out;
  }
  if (pa.start_s_px != pb.start_s_px || pa.values.size() != pb.values.size()) {
    throw std::invalid_argument("feed speed: the two profiles must share their sampling");
  }
  const std::vector<double> a = HighPass(pa.values, o.highpass_sigma_px);
  const std::vector<double> b = HighPass(pb.values, o.highpass_sigma_px);
  const int n = static_cast<int>(a.size());
  const double noise = std::max(0.5 * (pa.noise + pb.noise), 1e-9);
  out.texture_ratio = StdDev(a) / noise;
  if (out.texture_ratio < o.min_texture_ratio) {
    out.status = FeedShiftStatus::kNoTexture;
    out.detail = fmt::format("surface texture σ is {:.1f}× its noise (needs {:g}×)",
                             out.texture_ratio, o.min_texture_ratio);
    return out;
  }
  // Whole pixels: b(s + k) = a(s) when the surface moved k px down the axis. At least half the
  // profile must overlap.
  const int limit = std::min(static_cast<int>(std::floor(o.max_shift_px)), n / 2);
  int best_k = 0;
  double best = -2;
  for (int k = -limit; k <= limit; ++k) {
    double ab = 0, aa = 0, bb = 0;
    for (int i = std::max(0, -k); i < std::min(n, n - k); ++i) {
      ab += a[i] * b[i + k];
      aa += a[i] * a[i];
      bb += b[i + k] * b[i + k];
    }
    const double ncc = aa > 0 && bb > 0 ? ab / std::sqrt(aa * bb) : 0;
    if (ncc > best) {
      best = ncc;
      best_k = k;
    }
  }
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
  // Sub-pixel: Gauss–Newton on r(s) = a(s − d/2) − b(s + d/2), both interpolated, so that the
  // interpolators' errors cancel to first order.
  double d = best_k, sum_r2 = 0, sum_g2 = 0;
  int used = 0;
  for (int iter = 0; iter < 20; ++iter) {
    double num = 0;
    sum_r2 = sum_g2 = 0;
    used = 0;
    for (int i = 0; i < n; ++i) {
      const double xa = i - 0.5 * d, xb = i + 0.5 * d;
      if (xa < 1 || xb < 1 || xa >= n - 2 || xb >= n - 2) continue;
      double va, ga, vb, gb;
      Cubic(a, xa, &va, &ga);
      Cubic(b, xb, &vb, &gb);
      const double r = va - vb, g = -0.5 * (ga + gb);  // dr/dd
      num += g * r;
      sum_g2 += g * g;
      sum_r2 += r * r;
      ++used;
    }
    if (!(sum_g2 > 0)) break;
    const double step = -num / sum_g2;
    d += std::clamp(step, -0.5, 0.5);
    if (std::abs(step) < 1e-5) break;
  }
  out.shift_px = d;
  out.sigma_px = used > 1 && sum_g2 > 0 ? std::sqrt(sum_r2 / (used - 1) / sum_g2) : NAN;
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
  if (time_s < 0) {
    out.reason = "no_time";
    out.detail = "still images have no frame times";
  } else if (previous_.empty() || previous_t_ < 0) {
    out.reason = "first_frame";
    out.detail = "no frame before it";
  } else if (grey.empty() || grey.size() != previous_.size()) {
    out.reason = "no_strand";
    out.detail = "the frame could not be read";
  } else if (!(time_s > previous_t_)) {
    out.reason = "bad_time";
    out.detail = fmt::format("timestamp {:g} s does not follow {:g} s", time_s, previous_t_);
  } else if (!previous_m_.valid()) {
    out.reason = "no_strand";
    out.detail = "no filament measured in the frame before";
  } else {
    const AxisShift shift = EstimateFeedShift(previous_, grey, previous_m_, options_);
    out.dt_s = time_s - previous_t_;
    out.search_limit_px = shift.search_limit_px;
    out.valid = shift.valid();
    out.reason = out.valid ? "" : FeedShiftStatusName(shift.status);
    out.detail = shift.detail;
    out.shift_px = shift.shift_px;
    out.sigma_px = shift.sigma_px;
  }
  previous_ = grey;
  previous_m_ = m;
  previous_t_ = time_s;
  return out;
}

}  // namespace clogscope::vision
