#include "vision/strand_measure.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "vision/edge_fit.h"

namespace clogscope::vision {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int kGridStride = 4;  // rows of the coarse search, px apart
constexpr int kRunStride = 2;   // pixels along a coarse row, px apart
constexpr int kHistStride = 8;  // grid of the grey-level histogram, px
constexpr int kMinRunPx = 3;    // shorter object runs are noise

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
  return m;
}

double Mad(const std::vector<double>& v, double median) {
  std::vector<double> dev;
  dev.reserve(v.size());
  for (double x : v) dev.push_back(std::abs(x - median));
  return Median(std::move(dev));
}

// Grey view of the ROI: single channel, 8 or 16 bit.
cv::Mat GreyRoi(const cv::Mat& frame, const cv::Rect& roi) {
  if (frame.depth() != CV_8U && frame.depth() != CV_16U) {
    throw std::invalid_argument("frame: unsupported pixel depth (need 8- or 16-bit integer)");
  }
  const cv::Mat view = frame(roi);
  switch (frame.channels()) {
    case 1:
      return view;
    case 3: {
      cv::Mat grey;
      cv::cvtColor(view, grey, cv::COLOR_BGR2GRAY);
      return grey;
    }
    case 4: {
      cv::Mat grey;
      cv::cvtColor(view, grey, cv::COLOR_BGRA2GRAY);
      return grey;
    }
    default:
      throw std::invalid_argument(
          fmt::format("frame: unsupported channel count {} (need 1, 3 or 4)", frame.channels()));
  }
}

// Pixel access for both depths.
struct GreyImage {
  const cv::Mat& m;
  bool is16;
  float At(int x, int y) const {
    return is16 ? static_cast<float>(m.ptr<uint16_t>(y)[x])
                : static_cast<float>(m.ptr<uint8_t>(y)[x]);
  }
  // Bilinear, inside the image only (caller checks).
  float Bilinear(double x, double y) const {
    const int x0 = static_cast<int>(std::floor(x));
    const int y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    const double v00 = At(x0, y0), v10 = At(x0 + 1, y0);
    const double v01 = At(x0, y0 + 1), v11 = At(x0 + 1, y0 + 1);
    return static_cast<float>((v00 * (1 - fx) + v10 * fx) * (1 - fy) +
                              (v01 * (1 - fx) + v11 * fx) * fy);
  }
  bool InsideForBilinear(double x, double y) const {
    return x >= 0 && y >= 0 && x <= m.cols - 1.001 && y <= m.rows - 1.001;
  }
};

// Global two-class split of the sub-sampled frame (Otsu): background and object levels.
struct Levels {
  double background = 0;
  double object = 0;
  double threshold = 0;
  Polarity polarity = Polarity::kBrightOnDark;
};

bool SplitLevels(const GreyImage& img, Polarity forced, double full_scale, Levels* out) {
  std::array<double, 256> hist{};
  const int shift = img.is16 ? 8 : 0;
  double total = 0;
  for (int y = kHistStride / 2; y < img.m.rows; y += kHistStride) {
    for (int x = kHistStride / 2; x < img.m.cols; x += kHistStride) {
      hist[static_cast<int>(img.At(x, y)) >> shift] += 1;
      total += 1;
    }
  }
  if (total < 16) return false;
  double sum_all = 0;
  for (int i = 0; i < 256; ++i) sum_all += i * hist[i];
  double w0 = 0, sum0 = 0, best = -1;
  int best_t = 0;
  for (int t = 0; t < 255; ++t) {
    w0 += hist[t];
    sum0 += t * hist[t];
    const double w1 = total - w0;
    if (w0 == 0 || w1 == 0) continue;
    const double m0 = sum0 / w0, m1 = (sum_all - sum0) / w1;
    const double between = w0 * w1 * (m0 - m1) * (m0 - m1);
    if (between > best) {
      best = between;
      best_t = t;
    }
  }
  double n_lo = 0, s_lo = 0;
  for (int i = 0; i <= best_t; ++i) {
    n_lo += hist[i];
    s_lo += i * hist[i];
  }
  const double n_hi = total - n_lo;
  if (n_lo == 0 || n_hi == 0) return false;
  const double scale = full_scale / 255.0;
  const double m_lo = s_lo / n_lo * scale;
  const double m_hi = (sum_all - s_lo) / n_hi * scale;
  Polarity pol = forced;
  // The background fills most of a side view; the strand, nozzle and bed are the minority class.
  if (pol == Polarity::kAuto)
    pol = n_lo >= n_hi ? Polarity::kBrightOnDark : Polarity::kDarkOnBright;
  out->polarity = pol;
  out->background = pol == Polarity::kBrightOnDark ? m_lo : m_hi;
  out->object = pol == Polarity::kBrightOnDark ? m_hi : m_lo;
  out->threshold = 0.5 * (m_lo + m_hi);
  return true;
}

struct Run {
  int x0 = 0, x1 = 0;  // inclusive
  int width() const { return x1 - x0 + 1; }
  double centre() const { return 0.5 * (x0 + x1); }
};

struct RowRun {
  int y;
  Run run;
};

// The longest object run of each sampled row; runs touching the left or right border are skipped
// unless allow_border (a strand is never cut by the border when it can be measured).
template <typename Pixel>
std::vector<RowRun> LongestRunsT(const cv::Mat& m, const Levels& lv, bool allow_border) {
  std::vector<RowRun> rows;
  const bool bright = lv.polarity == Polarity::kBrightOnDark;
  // Integer compare against the threshold: v > thr <=> v >= floor(thr) + 1.
  const int above = static_cast<int>(std::floor(lv.threshold)) + 1;
  const int last = (m.cols - 1) / kRunStride * kRunStride;  // last sampled column
  for (int y = kGridStride / 2; y < m.rows; y += kGridStride) {
    const Pixel* row = m.ptr<Pixel>(y);
    Run best;
    int best_w = 0;
    int x = 0;
    while (x <= last) {
      // Skip background, then object: two tight loops instead of a per-pixel state machine.
      while (x <= last && ((row[x] >= above) != bright)) x += kRunStride;
      if (x > last) break;
      const int start = x;
      while (x <= last && ((row[x] >= above) == bright)) x += kRunStride;
      // The run covers samples start .. x - kRunStride; its width is known to ±kRunStride px.
      const bool at_border = start == 0 || x > last;
      if (x - start > best_w && (allow_border || !at_border)) {
        best_w = x - start;
        best = {start, x - 1};
      }
    }
    if (best_w >= kMinRunPx) rows.push_back({y, best});
  }
  return rows;
}

std::vector<RowRun> LongestRuns(const GreyImage& img, const Levels& lv, bool allow_border) {
  return img.is16 ? LongestRunsT<uint16_t>(img.m, lv, allow_border)
                  : LongestRunsT<uint8_t>(img.m, lv, allow_border);
}

// The strand: the narrowest stretch of consecutive sampled rows whose object run keeps its width
// and drifts smoothly. Nozzle flanks change width row to row; a bed fills the row.
bool FindStrandRows(const std::vector<RowRun>& rows, int roi_width, double max_tilt_deg,
                    std::vector<RowRun>* best) {
  std::vector<RowRun> current;
  double best_width = 1e30;
  const double max_drift = std::tan(max_tilt_deg / kRadToDeg) * kGridStride;
  auto close_segment = [&]() {
    // A strand hangs down: its centre drifts at most max_drift per sampled row on average.
    const bool steep = current.size() >= 3 &&
                       std::abs(current.back().run.centre() - current.front().run.centre()) <=
                           max_drift * (current.size() - 1) + 2.0;
    if (steep) {
      std::vector<double> widths;
      for (const auto& r : current) widths.push_back(r.run.width());
      const double w = Median(widths);
      if (w < best_width - 1e-9 ||
          (std::abs(w - best_width) < 1e-9 && current.size() > best->size())) {
        best_width = w;
        *best = current;
      }
    }
    current.clear();
  };
  for (const auto& r : rows) {
    const bool narrow_enough = r.run.width() < 0.7 * roi_width;
    if (!current.empty()) {
      const RowRun& prev = current.back();
      const double w = prev.run.width();
      const bool adjacent = r.y - prev.y == kGridStride;
      const bool same_width = std::abs(r.run.width() - w) <= std::max(0.05 * w, 2.5);
      const bool smooth = std::abs(r.run.centre() - prev.run.centre()) <= max_drift + 3.0;
      if (!(adjacent && same_width && smooth && narrow_enough)) close_segment();
    }
    if (narrow_enough) current.push_back(r);
  }
  close_segment();
  return !best->empty();
}

struct Frame2D {
  double ox, oy;  // origin (image px)
  double dx, dy;  // axis direction, unit, pointing down the strand
  double ImageX(double s, double u) const { return ox + s * dx + u * dy; }
  double ImageY(double s, double u) const { return oy + s * dy - u * dx; }
};
// In this frame the across-axis unit vector is n = (dy, -dx), so u grows to the right of a
// downward axis; s grows down the strand.

// Where a walk along a line parallel to the axis stopped: at object pixels (hit) or where it left
// the image.
struct ScanEnd {
  double s = NAN;
  bool hit = false;
};

// Walks along a line parallel to the axis at offset u from s_from in steps of dir (±1 px) until it
// reaches object pixels (interpolated crossing) or leaves the image.
ScanEnd ScanForObject(const GreyImage& img, const Frame2D& f, const Levels& lv, double u,
                      double s_from, double dir) {
  const bool bright = lv.polarity == Polarity::kBrightOnDark;
  const double thr = lv.threshold;
  double prev_v = NAN;
  for (int i = 0;; ++i) {
    const double s = s_from + dir * i;
    const double x = f.ImageX(s, u), y = f.ImageY(s, u);
    if (!img.InsideForBilinear(x, y)) return {s - dir, false};
    const double v = img.Bilinear(x, y);
    if ((v > thr) == bright) {
      if (std::isnan(prev_v)) return {};  // started inside an object: no clean crossing
      const double frac = (thr - prev_v) / (v - prev_v);
      return {s - dir + dir * frac, true};
    }
    prev_v = v;
  }
}

// Sub-pixel start for an edge fit: along the normal at s, from u_guess - half to u_guess + half in
// half-pixel steps, the crossing of the local mid-level (between the profile's extremes) nearest to
// u_guess. Returns u_guess when the profile has no clear step.
double RefineEdgeGuess(const GreyImage& img, const Frame2D& f, double s, double u_guess,
                       double half, double min_step) {
  constexpr double kStep = 0.5;
  const int n = static_cast<int>(2 * half / kStep) + 1;
  std::array<float, 128> v;
  if (n > static_cast<int>(v.size())) return u_guess;
  float lo = 1e30f, hi = -1e30f;
  for (int i = 0; i < n; ++i) {
    const double u = u_guess - half + i * kStep;
    const double x = f.ImageX(s, u), y = f.ImageY(s, u);
    if (!img.InsideForBilinear(x, y)) return u_guess;
    v[i] = img.Bilinear(x, y);
    lo = std::min(lo, v[i]);
    hi = std::max(hi, v[i]);
  }
  if (hi - lo < min_step) return u_guess;
  const float mid = 0.5f * (lo + hi);
  double best = u_guess, best_dist = 1e30;
  for (int i = 0; i + 1 < n; ++i) {
    if ((v[i] < mid) == (v[i + 1] < mid)) continue;
    const double u = u_guess - half + (i + (mid - v[i]) / (v[i + 1] - v[i])) * kStep;
    if (std::abs(u - u_guess) < best_dist) {
      best_dist = std::abs(u - u_guess);
      best = u;
    }
  }
  return best;
}

struct CaliperFit {
  EdgeFit left, right;
  bool inside_roi = true;
  int saturated = 0;
  int samples = 0;
};

// Gathers the pixels of one caliper slab near one edge, in (u, value) form. Returns false when
// the window leaves the image.
bool GatherEdgeSamples(const GreyImage& img, const Frame2D& f, double s0, double s1, double u0,
                       double u1, double full_scale, std::vector<EdgeSample>* out, int* saturated) {
  out->clear();
  double xmin = 1e30, xmax = -1e30, ymin = 1e30, ymax = -1e30;
  for (double s : {s0, s1}) {
    for (double u : {u0, u1}) {
      xmin = std::min(xmin, f.ImageX(s, u));
      xmax = std::max(xmax, f.ImageX(s, u));
      ymin = std::min(ymin, f.ImageY(s, u));
      ymax = std::max(ymax, f.ImageY(s, u));
    }
  }
  const int x_lo = static_cast<int>(std::ceil(xmin)), x_hi = static_cast<int>(std::floor(xmax));
  const int y_lo = static_cast<int>(std::ceil(ymin)), y_hi = static_cast<int>(std::floor(ymax));
  if (x_lo < 0 || y_lo < 0 || x_hi >= img.m.cols || y_hi >= img.m.rows) return false;
  const float top = static_cast<float>(full_scale);
  for (int y = y_lo; y <= y_hi; ++y) {
    const double ry = y - f.oy;
    for (int x = x_lo; x <= x_hi; ++x) {
      const double rx = x - f.ox;
      const double s = rx * f.dx + ry * f.dy;
      if (s < s0 || s >= s1) continue;
      const double u = rx * f.dy - ry * f.dx;
      if (u < u0 || u > u1) continue;
      const float v = img.At(x, y);
      if (v <= 0.0f || v >= top) ++*saturated;
      out->push_back({static_cast<float>(u), v});
    }
  }
  return true;
}

// The two edges as lines u = u0 + slope·s with a shared slope (parallel edges), least squares over
// the calipers whose width agrees with the median (an occluded or damaged caliper must not tilt the
// lines: the width's tilt correction depends on the slope).
struct EdgeLines {
  double left_u0 = 0, right_u0 = 0, slope = 0;
  int calipers = 0;
};

EdgeLines FitEdgeLines(const std::vector<CaliperFit>& fits, double band_s0, double spacing) {
  std::vector<double> widths;
  for (const auto& cf : fits) {
    if (cf.left.converged && cf.right.converged)
      widths.push_back(cf.right.edge_px - cf.left.edge_px);
  }
  EdgeLines out;
  if (widths.size() < 2) return out;
  const double med = Median(widths);
  const double tol = std::max(4.0 * 1.4826 * Mad(widths, med), 0.1);
  double n = 0, ss = 0, sss = 0, sl = 0, sr = 0, sls = 0, srs = 0;
  for (size_t k = 0; k < fits.size(); ++k) {
    const CaliperFit& cf = fits[k];
    if (!cf.left.converged || !cf.right.converged) continue;
    if (std::abs(cf.right.edge_px - cf.left.edge_px - med) > tol) continue;
    const double s = band_s0 + (k + 0.5) * spacing;
    n += 1;
    ss += s;
    sss += s * s;
    sl += cf.left.edge_px;
    sr += cf.right.edge_px;
    sls += cf.left.edge_px * s;
    srs += cf.right.edge_px * s;
  }
  if (n < 2) return out;
  const double var_s = sss - ss * ss / n;
  out.slope = var_s > 1e-9 ? ((sls - sl * ss / n) + (srs - sr * ss / n)) / (2 * var_s) : 0.0;
  out.left_u0 = (sl - out.slope * ss) / n;
  out.right_u0 = (sr - out.slope * ss) / n;
  out.calipers = static_cast<int>(n);
  return out;
}

}  // namespace

const char* FrameStatusName(FrameStatus status) {
  switch (status) {
    case FrameStatus::kValid:
      return "";
    case FrameStatus::kUnreadable:
      return "unreadable";
    case FrameStatus::kNoStrand:
      return "no_strand";
    case FrameStatus::kNoTip:
      return "no_tip";
    case FrameStatus::kTouchesBorder:
      return "touches_border";
    case FrameStatus::kBandOutsideFrame:
      return "band_outside_frame";
    case FrameStatus::kLowContrast:
      return "low_contrast";
    case FrameStatus::kOutOfFocus:
      return "out_of_focus";
    case FrameStatus::kSaturated:
      return "saturated";
    case FrameStatus::kOccluded:
      return "occluded";
    case FrameStatus::kWidthOutlier:
      return "width_outlier";
  }
  return "?";
}

bool StrandMeasureOptions::Validate(std::string* why) const {
  auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  if (roi.x < 0 || roi.y < 0 || roi.width < 0 || roi.height < 0)
    return fail("roi must have non-negative x, y, width and height");
  if (!roi.empty() && (roi.width < 16 || roi.height < 16))
    return fail("roi must be at least 16x16 px");
  if (!(band_start_px >= 0)) return fail("band start must not be negative");
  if (!(band_height_px >= 4)) return fail("band height must be at least 4 px");
  if (!(caliper_spacing_px >= 1 && caliper_spacing_px <= band_height_px))
    return fail("caliper spacing must be between 1 px and the band height");
  if (!(min_contrast_fraction > 0 && min_contrast_fraction < 1))
    return fail("min contrast fraction must be in (0, 1)");
  if (!(max_blur_px > 0)) return fail("max blur must be positive");
  if (!(max_tilt_deg > 0 && max_tilt_deg < 80)) return fail("max tilt must be in (0, 80) degrees");
  if (!(min_caliper_fraction > 0 && min_caliper_fraction <= 1))
    return fail("min caliper fraction must be in (0, 1]");
  if (!(max_saturated_fraction >= 0 && max_saturated_fraction <= 1))
    return fail("max saturated fraction must be in [0, 1]");
  return true;
}

StrandMeasurement MeasureStrand(const cv::Mat& frame, const StrandMeasureOptions& opt) {
  std::string why;
  if (!opt.Validate(&why)) throw std::invalid_argument("measure options: " + why);
  if (frame.empty()) throw std::invalid_argument("frame: empty image");
  cv::Rect roi = opt.roi.empty() ? cv::Rect(0, 0, frame.cols, frame.rows) : opt.roi;
  if ((roi & cv::Rect(0, 0, frame.cols, frame.rows)) != roi) {
    throw std::invalid_argument(fmt::format("--roi {},{},{},{} lies outside the {}x{} frame", roi.x,
                                            roi.y, roi.width, roi.height, frame.cols, frame.rows));
  }
  const cv::Mat grey = GreyRoi(frame, roi);
  const GreyImage img{grey, grey.depth() == CV_16U};
  const double full_scale = img.is16 ? 65535.0 : 255.0;
  const double min_contrast = opt.min_contrast_fraction * full_scale;

  StrandMeasurement m;
  auto fail = [&](FrameStatus st, std::string detail) {
    m.status = st;
    m.detail = std::move(detail);
    return m;
  };

  // 1. Background and object levels, polarity.
  Levels lv;
  if (!SplitLevels(img, opt.polarity, full_scale, &lv))
    return fail(FrameStatus::kNoStrand, "uniform frame");
  m.polarity = lv.polarity;
  if (std::abs(lv.object - lv.background) < min_contrast)
    return fail(FrameStatus::kNoStrand,
                fmt::format("no object: contrast {:.1f} below {:.1f}",
                            std::abs(lv.object - lv.background), min_contrast));

  // 2. Coarse strand: rows of constant width; its axis by a line fit through the run centres. In
  // auto mode the other polarity is tried too: a bed can fill more of the frame than the
  // background.
  std::vector<RowRun> strand_rows;
  const bool auto_polarity = opt.polarity == Polarity::kAuto;
  if (!FindStrandRows(LongestRuns(img, lv, false), img.m.cols, opt.max_tilt_deg, &strand_rows) &&
      auto_polarity) {
    std::swap(lv.background, lv.object);
    lv.polarity =
        lv.polarity == Polarity::kBrightOnDark ? Polarity::kDarkOnBright : Polarity::kBrightOnDark;
    if (!FindStrandRows(LongestRuns(img, lv, false), img.m.cols, opt.max_tilt_deg, &strand_rows)) {
      std::swap(lv.background, lv.object);
      lv.polarity = lv.polarity == Polarity::kBrightOnDark ? Polarity::kDarkOnBright
                                                           : Polarity::kBrightOnDark;
    }
  }
  m.polarity = lv.polarity;
  if (strand_rows.empty()) {
    std::vector<RowRun> cut;
    if (FindStrandRows(LongestRuns(img, lv, true), img.m.cols, opt.max_tilt_deg, &cut))
      return fail(FrameStatus::kTouchesBorder, "strand touches the left or right border");
    return fail(FrameStatus::kNoStrand, "no object of constant width over 3 sampled rows");
  }
  double sy = 0, sx = 0, syy = 0, sxy = 0;
  std::vector<double> widths;
  for (const auto& r : strand_rows) {
    sy += r.y;
    sx += r.run.centre();
    syy += double(r.y) * r.y;
    sxy += r.y * r.run.centre();
    widths.push_back(r.run.width());
  }
  const double n_rows = static_cast<double>(strand_rows.size());
  const double slope = (n_rows * sxy - sx * sy) / (n_rows * syy - sy * sy);
  const double x_at = (sx - slope * sy) / n_rows;
  const double theta0 = std::atan(slope);
  const double width0 = Median(widths) * std::cos(theta0);
  const double y_top = strand_rows.front().y, y_bottom = strand_rows.back().y;
  Frame2D f{x_at + slope * y_top, y_top, std::sin(theta0), std::cos(theta0)};
  // Scans start from the middle of the strand rows: in the axis frame the nozzle face and a bed are
  // at constant s, so beside the strand at that s there is background even when the scene is
  // tilted.
  const double s_mid = 0.5 * (y_bottom - y_top) / std::cos(theta0);

  // 3. Tip: walk up beside the strand, on both sides, to the nozzle's face; walk down for a bed.
  const double side_u = 0.5 * width0 + std::max(4.0, 0.2 * width0);
  int n_tip = 0;
  double s_tip = 0, s_end = 1e30, s_top_edge = -1e30;
  for (int side = 0; side < 2; ++side) {
    const double u = side == 0 ? -side_u : side_u;
    const ScanEnd tip = ScanForObject(img, f, lv, u, s_mid, -1.0);
    const ScanEnd end = ScanForObject(img, f, lv, u, s_mid, +1.0);
    if (tip.hit) {
      s_tip += tip.s;
      ++n_tip;
    } else if (!std::isnan(tip.s)) {
      s_top_edge = std::max(s_top_edge, tip.s);
    }
    // Below the strand: a bed or obstacle, or the frame's edge, ends the band.
    if (!std::isnan(end.s)) s_end = std::min(s_end, end.s);
  }
  if (n_tip > 0) {
    s_tip /= n_tip;
  } else if (!opt.require_tip && s_top_edge > -1e29) {
    s_tip = s_top_edge;  // an object across the frame (a pin gauge): the band starts at the edge
  } else {
    return fail(FrameStatus::kNoTip, "no nozzle tip above the strand");
  }
  f.ox += s_tip * f.dx;
  f.oy += s_tip * f.dy;
  s_end -= s_tip;
  m.tip_x_px = f.ox + roi.x;
  m.tip_y_px = f.oy + roi.y;

  // 4. Band and calipers. Each caliper fits both edges on the pixels of its slab, taken at their
  // exact across-axis distance (no interpolation, which would blur and bias the edge).
  const double band_s0 = opt.band_start_px;
  double band_s1 = opt.band_start_px + opt.band_height_px;
  const double end_margin = 10.0;  // > 3 blur sigma + caliper window at the usual blur
  if (s_end - end_margin < band_s1) band_s1 = s_end - end_margin;
  const double min_band = opt.require_tip
                              ? std::max(3.0 * opt.caliper_spacing_px, 0.3 * opt.band_height_px)
                              : 3.0 * opt.caliper_spacing_px;
  if (band_s1 - band_s0 < min_band) {
    return fail(FrameStatus::kBandOutsideFrame,
                fmt::format("band {:.0f}-{:.0f} px below the tip runs into an object or the frame "
                            "edge {:.0f} px below the tip",
                            band_s0, band_s0 + opt.band_height_px, s_end));
  }
  const int n_cal = static_cast<int>((band_s1 - band_s0) / opt.caliper_spacing_px);
  m.band_start_px = band_s0;
  m.band_end_px = band_s0 + n_cal * opt.caliper_spacing_px;
  m.calipers_total = n_cal;

  const bool bright = lv.polarity == Polarity::kBrightOnDark;
  std::vector<CaliperFit> fits(n_cal);
  std::vector<EdgeSample> samples;
  samples.reserve(512);
  double sigma_guess = 1.5;
  double left_guess = -0.5 * width0, right_guess = 0.5 * width0, slope_guess = 0.0;
  {
    // Sub-pixel starting edges at the top and bottom of the band: most frames then need one pass.
    const double sa = band_s0 + 0.5 * opt.caliper_spacing_px;
    const double sb = band_s0 + (n_cal - 0.5) * opt.caliper_spacing_px;
    const double half = std::min(10.0, 0.25 * width0);
    const double la = RefineEdgeGuess(img, f, sa, left_guess, half, min_contrast);
    const double lb = RefineEdgeGuess(img, f, sb, left_guess, half, min_contrast);
    const double ra = RefineEdgeGuess(img, f, sa, right_guess, half, min_contrast);
    const double rb = RefineEdgeGuess(img, f, sb, right_guess, half, min_contrast);
    if (sb > sa) slope_guess = 0.5 * ((lb - la) + (rb - ra)) / (sb - sa);
    left_guess = 0.5 * (la + lb) - slope_guess * 0.5 * (sa + sb);
    right_guess = 0.5 * (ra + rb) - slope_guess * 0.5 * (sa + sb);
  }
  int total_samples = 0, total_saturated = 0;
  bool border = false;
  // Usually one pass. Another re-centres the windows on the fitted edge lines, or widens them to
  // the fitted blur; a badly blurred frame needs a few widenings before its fit sees the whole
  // edge.
  constexpr int kMaxPasses = 4;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    const double outer = std::max(6.5, 3.0 * sigma_guess + 2.5);
    const double inner = std::min(outer, std::max(4.0, 0.3 * width0));
    total_samples = total_saturated = 0;
    border = false;
    for (int k = 0; k < n_cal; ++k) {
      const double s0 = band_s0 + k * opt.caliper_spacing_px;
      const double s1 = s0 + opt.caliper_spacing_px;
      const double sc = 0.5 * (s0 + s1);
      CaliperFit& cf = fits[k];
      cf = CaliperFit{};
      for (int side = 0; side < 2; ++side) {
        const double e0 = (side == 0 ? left_guess : right_guess) + slope_guess * sc;
        const double u0 = side == 0 ? e0 - outer : e0 - inner;
        const double u1 = side == 0 ? e0 + inner : e0 + outer;
        if (!GatherEdgeSamples(img, f, s0, s1, u0, u1, full_scale, &samples, &cf.saturated)) {
          cf.inside_roi = false;
          break;
        }
        cf.samples += static_cast<int>(samples.size());
        EdgeFit fit = FitBlurredStep(samples, e0, sigma_guess, e0);
        // Reject fits that wandered out of their window or have the wrong sign of step.
        const bool in_window = fit.edge_px > u0 + 1.0 && fit.edge_px < u1 - 1.0;
        const bool rising = fit.step > 0;
        const bool sign_ok = ((side == 0) == rising) == bright;
        if (!(in_window && sign_ok)) fit.converged = false;
        (side == 0 ? cf.left : cf.right) = fit;
      }
      if (!cf.inside_roi) border = true;
      total_samples += cf.samples;
      total_saturated += cf.saturated;
    }
    const EdgeLines lines = FitEdgeLines(fits, band_s0, opt.caliper_spacing_px);
    if (lines.calipers < 2) {
      // No edge fitted: perhaps blur far wider than the window. Widen and look again.
      sigma_guess = std::max(2.5 * sigma_guess, 0.6 * outer);
      continue;
    }
    const double new_slope = lines.slope, new_left = lines.left_u0, new_right = lines.right_u0;
    std::vector<double> sigmas;
    for (const auto& cf : fits) {
      if (!cf.left.converged || !cf.right.converged) continue;
      sigmas.push_back(cf.left.sigma_px);
      sigmas.push_back(cf.right.sigma_px);
    }
    const double new_sigma = Median(sigmas);
    const double s_mid = 0.5 * (band_s0 + band_s1);
    const bool recentre =
        std::abs(new_left + new_slope * s_mid - (left_guess + slope_guess * s_mid)) > 1.0 ||
        std::abs(new_right + new_slope * s_mid - (right_guess + slope_guess * s_mid)) > 1.0;
    const bool widen = 3.0 * new_sigma + 2.5 > 1.25 * outer;
    left_guess = new_left;
    right_guess = new_right;
    slope_guess = new_slope;
    // A fit in a window too narrow for the edge underestimates its width: widen geometrically.
    sigma_guess = widen ? std::max(new_sigma, 0.6 * outer) : new_sigma;
    if (!(recentre || widen)) break;
  }
  if (border)
    return fail(FrameStatus::kTouchesBorder, "edge windows reach the frame or ROI border");
  if (total_samples > 0 && total_saturated > opt.max_saturated_fraction * total_samples) {
    return fail(FrameStatus::kSaturated,
                fmt::format("{} of {} edge pixels clipped", total_saturated, total_samples));
  }

  // 5. Per-caliper widths, robust combination.
  const double cos_d = 1.0 / std::sqrt(1.0 + slope_guess * slope_guess);
  std::vector<double> cal_widths, steps, blurs;
  m.calipers.resize(n_cal);
  for (int k = 0; k < n_cal; ++k) {
    Caliper& c = m.calipers[k];
    c.s_px = band_s0 + (k + 0.5) * opt.caliper_spacing_px;
    c.fitted = fits[k].left.converged && fits[k].right.converged;
    if (!c.fitted) continue;
    c.left_u_px = fits[k].left.edge_px;
    c.right_u_px = fits[k].right.edge_px;
    c.width_px = (c.right_u_px - c.left_u_px) * cos_d;
    cal_widths.push_back(c.width_px);
    steps.push_back(std::abs(fits[k].left.step));
    steps.push_back(std::abs(fits[k].right.step));
    for (const EdgeFit* e : {&fits[k].left, &fits[k].right}) {
      // The fitted width holds the PSF and the pixel footprint, whose variance across any straight
      // edge is 1/12 px² whatever its tilt.
      blurs.push_back(std::sqrt(std::max(0.0, e->sigma_px * e->sigma_px - 1.0 / 12.0)));
    }
  }
  m.has_geometry = true;
  m.axis_dx = f.dx;
  m.axis_dy = f.dy;
  m.left_u0_px = left_guess;
  m.right_u0_px = right_guess;
  m.edge_slope = slope_guess;
  // Report the refined axis: the edges' slope in the measurement frame tilts the first estimate.
  m.angle_deg = (theta0 + std::atan(slope_guess)) * kRadToDeg;
  if (cal_widths.empty()) return fail(FrameStatus::kOccluded, "no caliper found both edges");
  m.contrast = Median(steps);
  m.blur_px = Median(blurs);

  const double med = Median(cal_widths);
  const double mad = Mad(cal_widths, med);
  const double tol = std::max(4.0 * 1.4826 * mad, 0.1);
  double sum = 0, sum2 = 0;
  int used = 0;
  for (auto& c : m.calipers) {
    if (!c.fitted) continue;
    c.inlier = std::abs(c.width_px - med) <= tol;
    if (!c.inlier) continue;
    sum += c.width_px;
    sum2 += c.width_px * c.width_px;
    ++used;
  }
  m.calipers_used = used;
  m.width_px = sum / used;
  if (used >= 2) {
    const double var = std::max(0.0, (sum2 - sum * sum / used) / (used - 1));
    m.width_sigma_px = std::sqrt(var / used);
  } else {
    const auto& k = fits[0];
    m.width_sigma_px = std::hypot(k.left.edge_sigma_px, k.right.edge_sigma_px);
  }

  // The coarse width comes from every strand row, most of them outside the band: a blob covering
  // one edge over the band makes the band's edges agree with each other but not with the strand.
  if (std::abs(m.width_px - width0) > std::max(3.0, 0.04 * width0)) {
    return fail(
        FrameStatus::kOccluded,
        fmt::format("width in the band {:.1f} px disagrees with the strand's {:.1f} px elsewhere",
                    m.width_px, width0));
  }
  if (m.contrast < min_contrast)
    return fail(FrameStatus::kLowContrast,
                fmt::format("edge contrast {:.1f} below {:.1f}", m.contrast, min_contrast));
  if (m.blur_px > opt.max_blur_px)
    return fail(FrameStatus::kOutOfFocus,
                fmt::format("edge blur {:.2f} px above {:.2f} px", m.blur_px, opt.max_blur_px));
  if (used < opt.min_caliper_fraction * n_cal)
    return fail(FrameStatus::kOccluded, fmt::format("{} of {} calipers consistent", used, n_cal));
  m.status = FrameStatus::kValid;
  m.detail.clear();
  return m;
}

int FlagWidthOutliers(std::vector<StrandMeasurement>& frames, int half_window, double k,
                      double min_deviation_px) {
  const int n = static_cast<int>(frames.size());
  std::vector<bool> flag(n, false);
  std::vector<double> window;
  for (int i = 0; i < n; ++i) {
    if (!frames[i].valid()) continue;
    window.clear();
    for (int j = std::max(0, i - half_window); j <= std::min(n - 1, i + half_window); ++j) {
      if (frames[j].valid()) window.push_back(frames[j].width_px);
    }
    if (window.size() < 5) continue;
    const double med = Median(window);
    const double mad = Mad(window, med);
    const double dev = std::abs(frames[i].width_px - med);
    if (dev > k * 1.4826 * mad && dev > min_deviation_px) flag[i] = true;
  }
  int count = 0;
  for (int i = 0; i < n; ++i) {
    if (!flag[i]) continue;
    frames[i].status = FrameStatus::kWidthOutlier;
    frames[i].detail = fmt::format("width {:.2f} px far from its neighbours", frames[i].width_px);
    ++count;
  }
  return count;
}

}  // namespace clogscope::vision
