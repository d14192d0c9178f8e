#include "vision/scene/micrometer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/edges/edge_fit.h"
#include "vision/io/data_range.h"

namespace clogscope::vision {
namespace {

constexpr int kStripRows = 12;

// The centre row of strip j (rows [j·kStripRows, (j + 1)·kStripRows)).
double StripY(int j) { return j * kStripRows + 0.5 * (kStripRows - 1); }

// Column means of rows [y0, y0 + kStripRows).
std::vector<double> StripProfile(const cv::Mat& grey, int y0) {
  cv::Mat strip;
  cv::reduce(grey.rowRange(y0, y0 + kStripRows), strip, 0, cv::REDUCE_AVG, CV_64F);
  return std::vector<double>(strip.ptr<double>(0), strip.ptr<double>(0) + strip.cols);
}

// Line centres in a profile: local extrema of the line polarity that stand out from the profile's
// median `med` by at least min_depth, refined by a parabola through the extremum and its
// neighbours.
std::vector<double> ProfileLines(const std::vector<double>& prof, double med, bool dark_lines,
                                 double min_depth) {
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

// The index of the element of `sorted` (ascending by key) nearest to x: one of the two around x's
// insertion point; -1 when there is none.
template <class T, class Key>
int Nearest(const std::vector<T>& sorted, double x, Key key) {
  const auto at = std::lower_bound(sorted.begin(), sorted.end(), x,
                                   [&](const T& e, double v) { return key(e) < v; });
  int best = -1;
  double best_d = 1e300;
  for (auto it : {at, at == sorted.begin() ? at : at - 1}) {
    if (it == sorted.end() || std::abs(key(*it) - x) >= best_d) continue;
    best_d = std::abs(key(*it) - x);
    best = static_cast<int>(it - sorted.begin());
  }
  return best;
}

// A mark: line centres followed through consecutive strips.
struct Track {
  int first = 0;
  std::vector<double> x;  // one per strip from `first` on
  double y(size_t i) const { return StripY(first + static_cast<int>(i)); }
};

// Centres (sorted, per strip) followed from strip to strip, each to the nearest in the next strip
// when that one's nearest is it too and it moved at most max_shift_px. A gap of a strip ends a
// mark: a tick and the numeral above it, or the two ends of a tick under a speck of dust, are
// separate marks.
std::vector<Track> FollowMarks(const std::vector<std::vector<double>>& found, double max_shift_px) {
  std::vector<Track> tracks;
  const auto x_of_centre = [](double v) { return v; };
  const auto x_of_open = [](const std::pair<double, int>& e) { return e.first; };
  std::vector<std::pair<double, int>> open;  // (last x, track) of marks reaching the last strip
  for (int j = 0; j < static_cast<int>(found.size()); ++j) {
    const std::vector<double>& f = found[j];
    std::vector<std::pair<double, int>> next;
    for (size_t i = 0; i < f.size(); ++i) {
      const int o = Nearest(open, f[i], x_of_open);
      int t = -1;
      if (o >= 0 && std::abs(open[o].first - f[i]) <= max_shift_px &&
          Nearest(f, open[o].first, x_of_centre) == static_cast<int>(i)) {
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
  return tracks;
}

// Sums for the least-squares slope of x against y.
struct SlopeSums {
  double n = 0, sy = 0, sx = 0, syy = 0, sxy = 0;
  void Add(double y, double x) {
    n += 1;
    sy += y;
    sx += x;
    syy += y * y;
    sxy += x * y;
  }
  double det() const { return n * syy - sy * sy; }
  double numerator() const { return n * sxy - sx * sy; }  // slope = numerator() / det()
};

// The frame across the lines at tilt θ: u along the normal (cos θ, −sin θ) from the image centre.
struct Across {
  double cx, cy, nx, ny;
  Across(const cv::Mat& grey, double theta)
      : cx(0.5 * (grey.cols - 1)),
        cy(0.5 * (grey.rows - 1)),
        nx(std::cos(theta)),
        ny(-std::sin(theta)) {}
  double U(double x, double y) const { return (x - cx) * nx + (y - cy) * ny; }
};

// The pixels of rows [y0, y0 + kStripRows) within ±half_px of u_guess across the lines, at their
// u; false when the window leaves the image on one of the rows.
bool StripSamples(const cv::Mat& grey, int y0, const Across& a, double u_guess, double half_px,
                  std::vector<EdgeSample>* samples) {
  for (int y = y0; y < y0 + kStripRows; ++y) {
    const float* row = grey.ptr<float>(y);
    // Columns where u is within the window on this row.
    const double ry = (y - a.cy) * a.ny;
    const double xa = (u_guess - half_px - ry) / a.nx + a.cx;
    const double xb = (u_guess + half_px - ry) / a.nx + a.cx;
    const int x0 = static_cast<int>(std::ceil(std::min(xa, xb)));
    const int x1 = static_cast<int>(std::floor(std::max(xa, xb)));
    if (x0 < 0 || x1 >= grey.cols) return false;
    for (int x = x0; x <= x1; ++x)
      samples->push_back({static_cast<float>((x - a.cx) * a.nx + ry), row[x]});
  }
  return true;
}

// One strip's fit of a mark's profile.
struct StripFit {
  double centre_px, sigma_px, depth, y_px;
  int samples;
};

// A mark's centre from its strips' fits: the σ-weighted mean of the strips that agree with their
// median (dust on a line, or a numeral joined to it, moves a few strips' centres); its σ grows
// with their scatter when that exceeds what their σ explain. Nothing when fewer than two strips
// agree (a speck, or a line cut by the border). With three or more, the kept centres' drift along
// the mark (du/dy) is added to *drifts.
std::optional<MicrometerLine> CombineStrips(const std::vector<StripFit>& strips, double theta,
                                            std::vector<double>* drifts) {
  std::vector<double> centres;
  for (const StripFit& f : strips) centres.push_back(f.centre_px);
  const double med = UpperMedian(centres);
  std::vector<double> dev;
  for (double c : centres) dev.push_back(std::abs(c - med));
  const double keep = std::max(3 * kMadToSigma * UpperMedian(dev), 0.05);
  SlopeSums drift;
  double sw = 0, swc = 0;
  int samples = 0;
  std::vector<double> kept_depths;
  for (size_t i = 0; i < strips.size(); ++i) {
    if (dev[i] > keep) continue;
    drift.Add(strips[i].y_px, strips[i].centre_px);
    const double w = 1 / (strips[i].sigma_px * strips[i].sigma_px);
    sw += w;
    swc += w * strips[i].centre_px;
    samples += strips[i].samples;
    kept_depths.push_back(strips[i].depth);
  }
  const double n = drift.n;
  if (n < 2) return std::nullopt;
  const double det = drift.det();
  if (n >= 3 && det > 0) drifts->push_back(drift.numerator() / det);
  const double centre = swc / sw;
  double chi2 = 0;
  for (size_t i = 0; i < strips.size(); ++i)
    if (dev[i] <= keep) chi2 += std::pow((strips[i].centre_px - centre) / strips[i].sigma_px, 2);
  const double sigma = std::sqrt(1 / sw) * std::sqrt(std::max(1.0, chi2 / (n - 1)));
  return MicrometerLine{centre, sigma, UpperMedian(kept_depths), n * kStripRows / std::cos(theta),
                        samples};
}

// Each mark's centre from the pixels within ±0.4 spacing of it on its own rows, at their distance
// across the lines at tilt θ: fitted strip by strip, then combined (CombineStrips). One fit over
// all the strips would share their background, but from a poor start it can settle on a broad
// bump instead. The strips' centres also tell how far θ is off: they drift along a line by
// du/dy = sin(θ_true − θ) / cos θ_true, added to *drifts.
std::vector<MicrometerLine> FitMarks(const cv::Mat& grey, const std::vector<Track>& tracks,
                                     double theta, double spacing0_px, bool dark_lines,
                                     double min_depth, std::vector<double>* drifts) {
  std::vector<MicrometerLine> lines;
  const Across across(grey, theta);
  const double spacing = spacing0_px * std::cos(theta);
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
    for (size_t i = 0; i < t.x.size(); ++i) u_guess += across.U(t.x[i], t.y(i));
    u_guess /= t.x.size();
    std::vector<StripFit> strips;
    for (size_t i = 0; i < t.x.size(); ++i) {
      std::vector<EdgeSample> samples;
      const int y0 = (t.first + static_cast<int>(i)) * kStripRows;
      if (!StripSamples(grey, y0, across, u_guess, half, &samples)) continue;
      const EdgeFit fit = FitLineProfile(samples, u_guess, width_guess);
      if (!line_fit_ok(fit, u_guess)) continue;
      strips.push_back({fit.edge_px, std::max(fit.edge_sigma_px, 1e-3), std::abs(fit.step), t.y(i),
                        fit.samples});
    }
    if (strips.empty()) continue;
    if (auto line = CombineStrips(strips, theta, drifts)) lines.push_back(*line);
  }
  return lines;
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

  // 1. Polarity: the marks are the minority in every strip they cross (ticks of several lengths
  // and numerals need not cross the middle), so the strips' reach below and above their medians.
  std::vector<std::vector<double>> profiles(n_strips);
  std::vector<double> medians(n_strips);
  double below = 0, above = 0;
  for (int j = 0; j < n_strips; ++j) {
    profiles[j] = StripProfile(grey, j * kStripRows);
    const auto [lo, hi] = std::minmax_element(profiles[j].begin(), profiles[j].end());
    medians[j] = UpperMedian(profiles[j]);
    below += medians[j] - *lo;
    above += *hi - medians[j];
  }
  const bool dark_lines = below > above;

  // 2. Line centres in every strip, and their spacing: the median gap between neighbours.
  std::vector<std::vector<double>> found(n_strips);
  std::vector<double> gaps;
  size_t centres = 0;
  for (int j = 0; j < n_strips; ++j) {
    found[j] = ProfileLines(profiles[j], medians[j], dark_lines, min_depth);
    std::sort(found[j].begin(), found[j].end());
    for (size_t i = 1; i < found[j].size(); ++i) gaps.push_back(found[j][i] - found[j][i - 1]);
    centres += found[j].size();
  }
  if (gaps.empty()) {
    out.reason = fmt::format(
        "no strip of the image holds two line centres ({} in all); need at least 3", centres);
    return out;
  }
  const double spacing0 = UpperMedian(gaps);

  // 3. Marks: centres followed from strip to strip while they move less than 0.4 spacing (a tilt
  // of max_tilt_deg moves a line 12·tan(max_tilt) px per strip).
  const std::vector<Track> tracks = FollowMarks(found, 0.4 * spacing0);

  // 4. Tilt: the median slope of x against y over the marks crossing three strips or more; marks
  // leaning more than max_tilt_deg (a fibre) have no say.
  const double max_slope = std::tan(opt.max_tilt_deg / kRadToDeg);
  std::vector<double> slopes;
  for (const Track& t : tracks) {
    if (t.x.size() < 3) continue;
    SlopeSums sums;
    for (size_t i = 0; i < t.x.size(); ++i) sums.Add(t.y(i), t.x[i]);
    const double det = sums.det();
    if (det > 0 && std::abs(sums.numerator()) <= max_slope * det)
      slopes.push_back(sums.numerator() / det);
  }
  const double slope = slopes.empty() ? 0.0 : UpperMedian(slopes);

  // 5. Each mark's centre across the lines (FitMarks). The tracked slope comes from centres found
  // to a tenth of a pixel; one more round from the fitted centres' drift (a tenth of that error is
  // already below the centres' own).
  double theta = std::atan(slope);
  std::vector<double> drifts;
  out.lines = FitMarks(grey, tracks, theta, spacing0, dark_lines, min_depth, &drifts);
  if (!drifts.empty()) {
    const double drift = UpperMedian(drifts);
    const double dtheta = std::asin(std::clamp(drift * std::cos(theta), -0.5, 0.5));
    if (std::abs(dtheta) > 1e-5) {
      theta += dtheta;
      drifts.clear();
      out.lines = FitMarks(grey, tracks, theta, spacing0, dark_lines, min_depth, &drifts);
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
