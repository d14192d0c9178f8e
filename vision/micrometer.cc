#include "vision/micrometer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
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
  const int n_strips = grey.rows / kStripRows;
  auto strip_y = [](int j) { return j * kStripRows + 0.5 * (kStripRows - 1); };

  // 1. Polarity: the marks are the minority in every strip they cross (ticks of several lengths
  // and numerals need not cross the middle), so the strips' reach below and above their medians.
  std::vector<std::vector<double>> profiles(n_strips);
  double below = 0, above = 0;
  for (int j = 0; j < n_strips; ++j) {
    profiles[j] = StripProfile(grey, j * kStripRows);
    const auto [lo, hi] = std::minmax_element(profiles[j].begin(), profiles[j].end());
    const double med = Median(profiles[j]);
    below += med - *lo;
    above += *hi - med;
  }
  const bool dark_lines = below > above;

  // 2. Line centres in every strip, and their spacing: the median gap between neighbours.
  std::vector<std::vector<double>> found(n_strips);
  std::vector<double> gaps;
  size_t centres = 0;
  for (int j = 0; j < n_strips; ++j) {
    found[j] = ProfileLines(profiles[j], dark_lines, min_depth);
    std::sort(found[j].begin(), found[j].end());
    for (size_t i = 1; i < found[j].size(); ++i) gaps.push_back(found[j][i] - found[j][i - 1]);
    centres += found[j].size();
  }
  if (gaps.empty()) {
    out.reason = fmt::format(
        "no strip of the image holds two line centres ({} in all); need at least 3", centres);
    return out;
  }
  const double spacing0 = Median(gaps);

  // 3. Marks: centres followed from strip to strip, each to the nearest in the next strip when
  // that one's nearest is it too and it moved less than 0.4 spacing (a tilt of max_tilt_deg moves
  // a line 12·tan(max_tilt) px per strip). A gap of a strip ends a mark: a tick and the numeral
  // above it, or the two ends of a tick under a speck of dust, are separate marks.
  struct Track {
    int first = 0;
    std::vector<double> x;  // one per strip from `first` on
  };
  std::vector<Track> tracks;
  const double max_shift = 0.4 * spacing0;
  std::vector<std::pair<double, int>> open;  // (last x, track) of marks reaching the last strip
  for (int j = 0; j < n_strips; ++j) {
    const std::vector<double>& f = found[j];
    auto nearest = [](const auto& sorted, double x, auto key) {
      const auto at = std::lower_bound(sorted.begin(), sorted.end(), x,
                                       [&](const auto& e, double v) { return key(e) < v; });
      int best = -1;
      double best_d = 1e300;
      for (auto it : {at, at == sorted.begin() ? at : at - 1}) {
        if (it == sorted.end() || std::abs(key(*it) - x) >= best_d) continue;
        best_d = std::abs(key(*it) - x);
        best = static_cast<int>(it - sorted.begin());
      }
      return best;
    };
    const auto x_of_centre = [](double v) { return v; };
    const auto x_of_open = [](const std::pair<double, int>& e) { return e.first; };
    std::vector<std::pair<double, int>> next;
    for (size_t i = 0; i < f.size(); ++i) {
      const int o = open.empty() ? -1 : nearest(open, f[i], x_of_open);
      int t = -1;
      if (o >= 0 && std::abs(open[o].first - f[i]) <= max_shift &&
          nearest(f, open[o].first, x_of_centre) == static_cast<int>(i)) {
        t = open[o].second;
      } else {
        t = static_cast<int>(tracks.size());
        tracks.push_back({j, {}});
      }
      tracks[t].x.push_back(f[i]);
      next.push_back({f[i], t});
    }
    open = std::move(next);  // sorted: f is
  }

  // 4. Tilt: the median slope of x against y over the marks crossing three strips or more; marks
  // leaning more than max_tilt_deg (a fibre) have no say.
  const double max_slope = std::tan(opt.max_tilt_deg / kRadToDeg);
  std::vector<double> slopes;
  for (const Track& t : tracks) {
    if (t.x.size() < 3) continue;
    double n = 0, sy = 0, sx = 0, syy = 0, sxy = 0;
    for (size_t i = 0; i < t.x.size(); ++i) {
      const double y = strip_y(t.first + static_cast<int>(i));
      n += 1;
      sy += y;
      sx += t.x[i];
      syy += y * y;
      sxy += t.x[i] * y;
    }
    const double det = n * syy - sy * sy;
    if (det > 0 && std::abs(n * sxy - sx * sy) <= max_slope * det)
      slopes.push_back((n * sxy - sx * sy) / det);
  }
  const double slope = slopes.empty() ? 0.0 : Median(slopes);

  // 5. Each mark's centre from the pixels within ±0.4 spacing of it on its own rows, at their
  // distance across the lines (u along the normal n = (cos θ, −sin θ), from the image centre):
  // fitted strip by strip, then the mean of the strips that agree with their median (dust on a
  // line, or a numeral joined to it, moves a few strips' centres). One fit over all the strips
  // would share their background, but from a poor start it can settle on a broad bump instead.
  // The strips' centres also tell how far θ is off: they drift along a line by
  // du/dy = sin(θ_true − θ) / cos θ_true.
  const double cx = 0.5 * (grey.cols - 1), cy = 0.5 * (grey.rows - 1);
  auto fit_marks = [&](double theta, std::vector<double>* drifts) {
    std::vector<MicrometerLine> lines;
    const double nx = std::cos(theta), ny = -std::sin(theta);
    const double spacing = spacing0 * std::cos(theta);
    const double half = 0.4 * spacing;
    // The fit takes its background from samples beyond 3 widths of the centre: keep some in the
    // window when the lines are close.
    const double width_guess = std::min(1.5, half / 3.5);
    auto line_fit_ok = [&](const EdgeFit& fit, double u_guess) {
      const bool sign_ok = dark_lines ? fit.step < 0 : fit.step > 0;
      return fit.converged && sign_ok && std::abs(fit.step) >= min_depth &&
             std::abs(fit.edge_px - u_guess) <= 0.25 * spacing && fit.sigma_px <= 0.5 * half;
    };
    for (const Track& t : tracks) {
      if (t.x.size() < 2) continue;  // a speck of dust, a numeral's bar
      double u_guess = 0;
      for (size_t i = 0; i < t.x.size(); ++i)
        u_guess += (t.x[i] - cx) * nx + (strip_y(t.first + static_cast<int>(i)) - cy) * ny;
      u_guess /= t.x.size();
      std::vector<double> centres, sigmas, depths, rows;
      std::vector<int> counts;
      for (size_t i = 0; i < t.x.size(); ++i) {
        const int y0 = (t.first + static_cast<int>(i)) * kStripRows;
        std::vector<EdgeSample> samples;
        bool cut = false;
        for (int y = y0; y < y0 + kStripRows && !cut; ++y) {
          const float* row = grey.ptr<float>(y);
          // Columns where u is within the window on this row.
          const double ry = (y - cy) * ny;
          const double xa = (u_guess - half - ry) / nx + cx, xb = (u_guess + half - ry) / nx + cx;
          const int x0 = static_cast<int>(std::ceil(std::min(xa, xb)));
          const int x1 = static_cast<int>(std::floor(std::max(xa, xb)));
          if (x0 < 0 || x1 >= grey.cols) {
            cut = true;  // the window leaves the image on this row: leave the strip out
            break;
          }
          for (int x = x0; x <= x1; ++x)
            samples.push_back({static_cast<float>((x - cx) * nx + ry), row[x]});
        }
        if (cut) continue;
        const EdgeFit fit = FitLineProfile(samples, u_guess, width_guess);
        if (!line_fit_ok(fit, u_guess)) continue;
        centres.push_back(fit.edge_px);
        sigmas.push_back(std::max(fit.edge_sigma_px, 1e-3));
        depths.push_back(std::abs(fit.step));
        counts.push_back(fit.samples);
        rows.push_back(strip_y(t.first + static_cast<int>(i)));
      }
      if (centres.empty()) continue;
      const double med = Median(centres);
      std::vector<double> dev;
      for (double c : centres) dev.push_back(std::abs(c - med));
      const double keep = std::max(3 * 1.4826 * Median(dev), 0.05);
      // The kept strips' centres, weighted by their σ; the σ of the mean grows with their scatter
      // when that exceeds what their σ explain.
      double n = 0, sy = 0, sc = 0, syy = 0, syc = 0, sw = 0, swc = 0;
      int samples = 0;
      std::vector<double> kept_depths;
      for (size_t i = 0; i < centres.size(); ++i) {
        if (dev[i] > keep) continue;
        n += 1;
        sy += rows[i];
        sc += centres[i];
        syy += rows[i] * rows[i];
        syc += rows[i] * centres[i];
        const double w = 1 / (sigmas[i] * sigmas[i]);
        sw += w;
        swc += w * centres[i];
        samples += counts[i];
        kept_depths.push_back(depths[i]);
      }
      if (n < 2) continue;  // seen on one strip only: a speck, or a line cut by the border
      const double det = n * syy - sy * sy;
      if (n >= 3 && det > 0) drifts->push_back((n * syc - sy * sc) / det);
      const double centre = swc / sw;
      double chi2 = 0;
      for (size_t i = 0; i < centres.size(); ++i)
        if (dev[i] <= keep) chi2 += std::pow((centres[i] - centre) / sigmas[i], 2);
      const double sigma = std::sqrt(1 / sw) * std::sqrt(std::max(1.0, chi2 / (n - 1)));
      lines.push_back(
          {centre, sigma, Median(kept_depths), n * kStripRows / std::cos(theta), samples});
    }
    return lines;
  };
  double theta = std::atan(slope);
  std::vector<double> drifts;
  out.lines = fit_marks(theta, &drifts);
  // The tracked slope comes from centres found to a tenth of a pixel; one more round from the
  // fitted centres (a tenth of that error is already below the centres' own).
  if (!drifts.empty()) {
    const double drift = Median(drifts);
    const double dtheta = std::asin(std::clamp(drift * std::cos(theta), -0.5, 0.5));
    if (std::abs(dtheta) > 1e-5) {
      theta += dtheta;
      drifts.clear();
      out.lines = fit_marks(theta, &drifts);
    }
  }
  out.angle_deg = theta * kRadToDeg;
  const double spacing = spacing0 * std::cos(theta);
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
