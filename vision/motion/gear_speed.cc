#include "vision/motion/gear_speed.h"

#include <fmt/format.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/motion/profile_shift.h"

namespace clogscope::vision {

bool GearSpeedOptions::Validate(std::string* why) const {
  if (roi.width < 16 || roi.height < 16)
    *why = "the gear ROI must be at least 16×16 px";
  else if (!(angle_samples >= 64 && angle_samples <= 16384))
    *why = "angle samples must be in 64…16384";
  else if (!(inner_radius_fraction >= 0 && inner_radius_fraction < 0.95))
    *why = "inner radius fraction must be in [0, 0.95)";
  else if (!(max_rotation_deg > 0 && max_rotation_deg <= 180))
    *why = "maximum rotation must be in (0, 180]°";
  else if (outer_radius_px && !(*outer_radius_px >= 8))
    *why = "the gear's radius must be at least 8 px";
  else if (!(min_correlation > 0 && min_correlation < 1))
    *why = "minimum correlation must be in (0, 1)";
  else
    return true;
  return false;
}

std::vector<double> GearAngularProfile(const cv::Mat& grey, const GearSpeedOptions& o) {
  if ((o.roi & cv::Rect(0, 0, grey.cols, grey.rows)) != o.roi) return {};
  const cv::Point2d c = o.centre_px.value_or(
      cv::Point2d(o.roi.x + 0.5 * (o.roi.width - 1), o.roi.y + 0.5 * (o.roi.height - 1)));
  // The largest circle about the centre inside the ROI.
  double r_max = std::min({c.x - o.roi.x, o.roi.x + o.roi.width - 1 - c.x, c.y - o.roi.y,
                           o.roi.y + o.roi.height - 1 - c.y});
  if (o.outer_radius_px) r_max = std::min(r_max, *o.outer_radius_px);
  if (r_max < 8) return {};
  cv::Mat region, polar;
  grey(o.roi).convertTo(region, CV_32F);
  const int radii = static_cast<int>(std::ceil(r_max));
  // Rows: angle from 0 to 2π (clockwise in the image, y down); columns: radius 0…r_max.
  cv::warpPolar(region, polar, cv::Size(radii, o.angle_samples),
                cv::Point2f(static_cast<float>(c.x - o.roi.x), static_cast<float>(c.y - o.roi.y)),
                r_max, cv::INTER_LINEAR | cv::WARP_POLAR_LINEAR);
  const int c0 = static_cast<int>(o.inner_radius_fraction * radii);
  std::vector<double> profile(o.angle_samples);
  for (int row = 0; row < o.angle_samples; ++row) {
    const float* p = polar.ptr<float>(row);
    double sum = 0;
    for (int col = c0; col < radii; ++col) sum += p[col];
    profile[row] = sum / std::max(1, radii - c0);
  }
  return profile;
}

GearSpeedTracker::GearSpeedTracker(const GearSpeedOptions& options) : options_(options) {
  std::string why;
  if (!options_.Validate(&why)) throw std::invalid_argument("gear speed: " + why);
}

GearSpeedSample GearSpeedTracker::Next(const cv::Mat& frame, double time_s) {
  GearSpeedSample out;
  cv::Mat grey = frame;
  if (!frame.empty() && frame.channels() != 1) {
    cv::cvtColor(frame, grey, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  }
  std::vector<double> current =
      grey.empty() ? std::vector<double>{} : GearAngularProfile(grey, options_);
  const double step_rad = 2 * M_PI / options_.angle_samples;
  if (time_s < 0) {
    out.reason = SpeedReason::kNoTime;
    out.detail = "still images have no frame times";
  } else if (current.empty()) {
    out.reason = SpeedReason::kNoGear;
    out.detail = "the gear ROI does not lie inside the frame";
  } else if (previous_.empty() || previous_t_ < 0) {
    out.reason = SpeedReason::kFirstFrame;
    out.detail = "no frame before it";
  } else if (!(time_s > previous_t_)) {
    out.reason = SpeedReason::kBadTime;
    out.detail = fmt::format("timestamp {:g} s does not follow {:g} s", time_s, previous_t_);
  } else {
    out.dt_s = time_s - previous_t_;
    // The mean is the same whatever the rotation: correlate what varies around the turn.
    std::vector<double> a = previous_, b = current;
    double ma = 0, mb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      ma += a[i] / a.size();
      mb += b[i] / b.size();
    }
    for (size_t i = 0; i < a.size(); ++i) {
      a[i] -= ma;
      b[i] -= mb;
    }
    const int limit = static_cast<int>(options_.max_rotation_deg / 360 * options_.angle_samples);
    // A flat ring has nothing to follow: say so before searching it.
    const bool flat = StdDev(a) < 1e-6;
    const WholeShift whole = flat ? WholeShift{} : BestWholeShift(a, b, limit, /*circular=*/true);
    if (flat) {
      out.reason = SpeedReason::kNoGear;
      out.detail = "nothing varies around the gear's centre";
    } else if (whole.correlation < options_.min_correlation || std::abs(whole.samples) >= limit) {
      out.reason = SpeedReason::kTooFast;
      out.detail =
          fmt::format("no match of the gear within ±{:g}° between frames (best correlation {:.2f})",
                      options_.max_rotation_deg, whole.correlation);
    } else {
      const FineShift fine = RefineShift(a, b, whole.samples, /*circular=*/true);
      out.valid = true;
      out.rotation_rad = fine.samples * step_rad;
      out.sigma_rad = fine.sigma * step_rad;
    }
  }
  previous_ = std::move(current);
  previous_t_ = time_s;
  return out;
}

GearAndSlip GearAndSlipOf(const FeedSpeedSample& filament, const GearSpeedSample& gear,
                          double mm_per_px, double radius_mm) {
  GearAndSlip g;
  if (!gear.valid) return g;
  const double vg = std::abs(gear.RadPerS()) * radius_mm;
  g.gear_mm_s = vg;
  g.gear_sigma_mm_s = gear.SigmaRadPerS() * radius_mm;
  // A gear that does not turn measurably (under 3σ) has no slip to speak of.
  if (!filament.valid || !(vg > 3 * *g.gear_sigma_mm_s && vg > 1e-9)) return g;
  const double vf = filament.SpeedPxPerS() * mm_per_px, sf = filament.SigmaPxPerS() * mm_per_px;
  g.slip_pct = 100 * (1 - vf / vg);
  g.slip_sigma_pct = 100 * std::hypot(sf / vg, vf * *g.gear_sigma_mm_s / (vg * vg));
  return g;
}

}  // namespace clogscope::vision
