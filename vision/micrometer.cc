#include "vision/micrometer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/edge_fit.h"
#include "vision/strand_measure.h"

namespace clogscope::vision {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int kStripRows = 12;

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// Column means of rows [y0, y0 + kStripRows).
std::vector<double> StripProfile(const cv::Mat& grey, int y0) {
  cv::Mat strip;
  cv::reduce(grey.rowRange(y0, y0 + kStripRows), strip, 0, cv::REDUCE_AVG, CV_64F);
  return std::vector<double>(strip.ptr<double>(0), strip.ptr<double>(0) + strip.cols);
}

// Line centres in a profile: local extrema of the line polarity that stand out from the profile's
// median by at least min_depth, refined by a parabola through the extremum and its neighbours.
std::vector<double> ProfileLines(const std::vector<double>& prof, bool dark_lines,
                                 double min_depth) {
  const double med = Median(prof);
  std::vector<double> out;
  const int n = static_cast<int>(prof.size());
  for (int i = 2; i + 2 < n; ++i) {
    const double v = dark_lines ? med - prof[i] : prof[i] - med;
    if (v < min_depth) continue;
    auto sign = [&](int k) { return dark_lines ? -prof[k] : prof[k]; };
    if (!(sign(i) > sign(i - 1) && sign(i) >= sign(i + 1))) continue;
    const double a = sign(i - 1), b = sign(i), c = sign(i + 1);
    const double den = a - 2 * b + c;
    out.push_back(i + (den != 0 ? 0.5 * (a - c) / den : 0.0));
  }
  return out;
}

}  // namespace

bool MicrometerOptions::Validate(std::string* why) const {
  if (roi.x < 0 || roi.y < 0 || roi.width < 0 || roi.height < 0) {
    *why = "roi must have non-negative x, y, width and height";
    return false;
  }
  if (!(max_tilt_deg > 0 && max_tilt_deg < 45)) {
    *why = "max tilt must be in (0, 45) degrees";
    return false;
  }
  if (!(min_contrast_fraction > 0 && min_contrast_fraction < 1)) {
    *why = "min contrast fraction must be in (0, 1)";
    return false;
  }
  return true;
}

MicrometerLines FindMicrometerLines(const cv::Mat& image, const MicrometerOptions& opt) {
  std::string why;
  if (!opt.Validate(&why)) throw std::invalid_argument("micrometer options: " + why);
  if (image.empty()) throw std::invalid_argument("micrometer image: empty");
  if (image.depth() != CV_8U && image.depth() != CV_16U)
    throw std::invalid_argument("micrometer image: unsupported pixel depth (need 8- or 16-bit)");
  const cv::Rect roi = opt.roi.empty() ? cv::Rect(0, 0, image.cols, image.rows) : opt.roi;
  if ((roi & cv::Rect(0, 0, image.cols, image.rows)) != roi)
    throw std::invalid_argument("--roi lies outside the image");
  cv::Mat grey;
  if (image.channels() == 1) {
    image(roi).convertTo(grey, CV_32F);
  } else {
    cv::Mat g;
    cv::cvtColor(image(roi), g, image.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
    g.convertTo(grey, CV_32F);
  }
  // 12-bit cameras write 16-bit files: contrast limits follow the data's range, not 65535.
  const double full_scale = DataMax(image);
  const double min_depth = opt.min_contrast_fraction * full_scale;
  MicrometerLines out;
  if (grey.rows < 3 * kStripRows || grey.cols < 32) {
    out.reason = "image or ROI too small";
    return out;
  }

  // 1. Polarity: lines are the minority, so the middle strip's median is the field.
  const int mid_y = grey.rows / 2 - kStripRows / 2;
  const std::vector<double> mid = StripProfile(grey, mid_y);
  const double med = Median(mid);
  const double lo = *std::min_element(mid.begin(), mid.end());
  const double hi = *std::max_element(mid.begin(), mid.end());
  const bool dark_lines = med - lo > hi - med;
  const std::vector<double> mid_lines = ProfileLines(mid, dark_lines, min_depth);
  if (mid_lines.size() < 3) {
    out.reason = fmt::format("found {} line(s) across the middle of the image; need at least 3",
                             mid_lines.size());
    return out;
  }
  std::vector<double> gaps;
  for (size_t i = 1; i < mid_lines.size(); ++i) gaps.push_back(mid_lines[i] - mid_lines[i - 1]);
  const double spacing0 = Median(gaps);

  // 2. Tilt: follow each line from the middle strip up and down through strips close enough that a
  // line moves less than half a spacing between them; slope of x against y, median over lines.
  const double max_shift = 0.4 * spacing0;
  const int step =
      std::max(kStripRows, static_cast<int>(max_shift / std::tan(opt.max_tilt_deg / kRadToDeg)));
  // Each strip's lines are found once (sorted by x) and shared by all the lines followed through
  // it: the search stays linear in the image size.
  std::map<int, std::vector<double>> strip_lines;
  auto lines_at = [&](int y0) -> const std::vector<double>& {
    auto it = strip_lines.find(y0);
    if (it == strip_lines.end()) {
      std::vector<double> found = ProfileLines(StripProfile(grey, y0), dark_lines, min_depth);
      std::sort(found.begin(), found.end());
      it = strip_lines.emplace(y0, std::move(found)).first;
    }
    return it->second;
  };
  std::vector<double> slopes;
  for (double x_mid : mid_lines) {
    std::vector<std::pair<double, double>> track = {{mid_y + 0.5 * kStripRows, x_mid}};
    for (int dir : {-1, 1}) {
      double x = x_mid;
      for (int y0 = mid_y + dir * step; y0 >= 0 && y0 + kStripRows <= grey.rows; y0 += dir * step) {
        const std::vector<double>& found = lines_at(y0);
        // The nearest line to x: one of the two around its insertion point.
        double best = 1e30, best_x = 0;
        const auto at = std::lower_bound(found.begin(), found.end(), x);
        for (auto it : {at, at == found.begin() ? at : at - 1}) {
          if (it == found.end() || std::abs(*it - x) >= best) continue;
          best = std::abs(*it - x);
          best_x = *it;
        }
        if (best > max_shift) break;
        x = best_x;
        track.push_back({y0 + 0.5 * kStripRows, x});
      }
    }
    if (track.size() < 3) continue;
    double n = 0, sy = 0, sx = 0, syy = 0, sxy = 0;
    for (const auto& [y, x] : track) {
      n += 1;
      sy += y;
      sx += x;
      syy += y * y;
      sxy += x * y;
    }
    const double det = n * syy - sy * sy;
    if (det > 0) slopes.push_back((n * sxy - sx * sy) / det);
  }
  const double slope = slopes.empty() ? 0.0 : Median(slopes);
  const double theta = std::atan(slope);
  out.angle_deg = theta * kRadToDeg;

  // 3. Each line's centre from all pixels within ±0.4 spacing of it, at their distance across the
  // lines (u along the normal n = (cos θ, −sin θ), from the image centre).
  const double cx = 0.5 * (grey.cols - 1), cy = 0.5 * (grey.rows - 1);
  const double nx = std::cos(theta), ny = -std::sin(theta);
  const double spacing = spacing0 * std::cos(theta);
  const double half = 0.4 * spacing;
  std::vector<EdgeSample> samples;
  for (double x_mid : mid_lines) {
    const double u_guess = (x_mid - cx) * nx + (mid_y + 0.5 * kStripRows - cy) * ny;
    samples.clear();
    bool cut = false;
    for (int y = 0; y < grey.rows && !cut; ++y) {
      const float* row = grey.ptr<float>(y);
      // Columns where u is within the window on this row.
      const double ry = (y - cy) * ny;
      const double xa = (u_guess - half - ry) / nx + cx, xb = (u_guess + half - ry) / nx + cx;
      const int x0 = static_cast<int>(std::ceil(std::min(xa, xb)));
      const int x1 = static_cast<int>(std::floor(std::max(xa, xb)));
      if (x0 < 0 || x1 >= grey.cols) {
        cut = true;  // the line's window leaves the image on this row: leave the line out
        break;
      }
      for (int x = x0; x <= x1; ++x) {
        samples.push_back({static_cast<float>((x - cx) * nx + ry), row[x]});
      }
    }
    if (cut) continue;
    const EdgeFit fit = FitLineProfile(samples, u_guess, 1.5);
    const bool sign_ok = dark_lines ? fit.step < 0 : fit.step > 0;
    if (!fit.converged || !sign_ok || std::abs(fit.step) < min_depth ||
        std::abs(fit.edge_px - u_guess) > 0.25 * spacing) {
      continue;
    }
    out.lines.push_back({fit.edge_px, fit.edge_sigma_px, std::abs(fit.step), fit.samples});
  }
  std::sort(out.lines.begin(), out.lines.end(),
            [](const MicrometerLine& a, const MicrometerLine& b) {
              return a.position_px < b.position_px;
            });
  out.spacing_px = spacing;
  if (out.lines.size() < 3) {
    out.reason = fmt::format("only {} line(s) could be fitted; need at least 3", out.lines.size());
    return out;
  }
  out.ok = true;
  return out;
}

}  // namespace clogscope::vision
