#include "vision/edges/caliper_samples.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "common/robust.h"

namespace clogscope::vision {

namespace {

// Whether the pixel (x, y) lies in the slab s0 <= s < s1, u0 <= u <= u1.
inline bool InSlab(const AxisFrame& f, int x, int y, double s0, double s1, double u0, double u1) {
  const double s = f.S(x, y), u = f.U(x, y);
  return s >= s0 && s < s1 && u >= u0 && u <= u1;
}

// The x interval where a·(x − ox) + c lies in [lo, hi], widened by more than the rounding of
// this estimate and of InSlab's own arithmetic can move its ends (a pixel, or more where a is
// nearly 0); all of x when a is 0 or nearly (the ends' tests then decide).
void Interval(double a, double c, double ox, double lo, double hi, double* from, double* to) {
  constexpr double kEps = std::numeric_limits<double>::epsilon();
  if (std::abs(a) < 1e-12) {
    *from = -std::numeric_limits<double>::infinity();
    *to = std::numeric_limits<double>::infinity();
    return;
  }
  const double p = ox + (lo - c) / a, q = ox + (hi - c) / a;
  const double slack = 1.0 + 16.0 * kEps *
                                 (std::abs(p) + std::abs(q) + std::abs(ox) +
                                  (std::abs(lo) + std::abs(hi) + std::abs(c)) / std::abs(a));
  *from = std::min(p, q) - slack;
  *to = std::max(p, q) + slack;
}

}  // namespace

bool SlabBounds(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                double u1, int* x_lo, int* x_hi, int* y_lo, int* y_hi) {
  double xmin = 1e30, xmax = -1e30, ymin = 1e30, ymax = -1e30;
  for (double s : {s0, s1}) {
    for (double u : {u0, u1}) {
      xmin = std::min(xmin, f.ImageX(s, u));
      xmax = std::max(xmax, f.ImageX(s, u));
      ymin = std::min(ymin, f.ImageY(s, u));
      ymax = std::max(ymax, f.ImageY(s, u));
    }
  }
  *x_lo = static_cast<int>(std::ceil(xmin));
  *x_hi = static_cast<int>(std::floor(xmax));
  *y_lo = static_cast<int>(std::ceil(ymin));
  *y_hi = static_cast<int>(std::floor(ymax));
  return *x_lo >= 0 && *y_lo >= 0 && *x_hi < img.m.cols && *y_hi < img.m.rows;
}

// Along a row s and u are monotone, even as rounded, so the row's pixels in the slab are one run:
// it lies within the lines' estimate (widened beyond its rounding), whose ends are walked in to
// the first and last pixel InSlab takes; the pixels between need no test (every band of every
// frame passes here).
void SlabRow(const AxisFrame& f, int y, int x_lo, int x_hi, double s0, double s1, double u0,
             double u1, int* first, int* last) {
  const double ry = y - f.oy;
  double sa, sb, ua, ub;
  Interval(f.dx, ry * f.dy, f.ox, s0, s1, &sa, &sb);
  Interval(f.dy, -ry * f.dx, f.ox, u0, u1, &ua, &ub);
  // Clamped to the row before the conversion to int.
  const double from = std::clamp(std::max(sa, ua), x_lo - 1.0, x_hi + 1.0);
  const double to = std::clamp(std::min(sb, ub), x_lo - 1.0, x_hi + 1.0);
  int a = std::max(x_lo, static_cast<int>(std::floor(from)));
  int b = std::min(x_hi, static_cast<int>(std::ceil(to)));
  while (a <= b && !InSlab(f, a, y, s0, s1, u0, u1)) ++a;
  while (b >= a && !InSlab(f, b, y, s0, s1, u0, u1)) --b;
  *first = a;
  *last = b;
}

ClipLevels FindClipLevels(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                          double u1, const DataLevels& levels) {
  const double data_max = levels.max;
  ClipLevels clip{0.0f, static_cast<float>(data_max)};
  // 256 bins over the data's range; only its ends are looked at (below).
  constexpr int kBins = 256, kEdgeBins = 10, kBelow = 4;
  constexpr double kNearWhiteFraction = 0.01;  // of black to white
  using Histogram = std::array<int, kBins>;
  Histogram h{};
  const double scale = (kBins - 1) / data_max;
  int n = 0;
  // Every band of every frame passes here: the values are never negative, so rounding is a
  // truncation of v + 0.5.
  const auto bin_of = [&](float v) {
    return std::min(static_cast<int>(v * scale + 0.5), kBins - 1);
  };
  if (!ForEachSlabPixel(img, f, s0, s1, u0, u1, [&](double, float v) {
        ++h[bin_of(v)];
        ++n;
      }))
    return clip;
  // A spike: the fullest bin of a window, well above the bins just inside it, with little
  // beyond it (a codec's ringing): an unclipped plateau has its noise on both sides. A spike
  // twice as sharp may have as much beyond it as in it: x264's clipped white in one key frame
  // (296 pixels at 235, 180 above it, 23 a bin in the four below), while a plateau of noise
  // σ 1 has at most 5.3 times its neighbours. One with almost nothing beyond it is a wall, not
  // noise, however much ringing lies inside it: x264's clipped white beside a dark strand at a
  // low rate (488 at 235, a mean of 115 a bin in the four below, 85 above). And a codec may split
  // a clipped level over two bins (374 at 235, 334 at 236, 70 above, 16 a bin below). Either
  // form also takes a plateau of noise σ 0.8 or less about a level between two bins for a clip
  // (as the first two take one of σ 0.7 on a level): a plateau that flat by white is refused as
  // clipped; σ 1 is not (0.21 of a pair beyond it).
  const auto spike = [&](const Histogram& hist, int count, int from, int to, int inward) {
    int best = -1;
    for (int b = from; b != to; b += inward) {
      if (best < 0 || hist[b] > hist[best]) best = b;
    }
    double inside = 0;
    for (int k = 1; k <= kBelow; ++k) inside += hist[std::clamp(best + inward * k, 0, kBins - 1)];
    const double inside_per_bin = std::max(1.0, inside / kBelow);
    const int next = best - inward;  // the bin beyond the fullest
    const double split = next >= 0 && next < kBins ? hist[next] : 0.0;
    double beyond = 0;
    for (int b = next; b >= 0 && b < kBins; b -= inward) beyond += hist[b];
    const double sharpness = hist[best] / inside_per_bin;
    const double pair = hist[best] + split, beyond_pair = beyond - split;
    const bool is_spike = hist[best] >= 0.02 * count && hist[best] > 8 &&
                          ((sharpness >= 5.0 && beyond <= 0.5 * hist[best]) ||
                           (sharpness >= 10.0 && beyond <= hist[best]) ||
                           (sharpness >= 3.0 && beyond <= 0.2 * hist[best]) ||
                           (split >= 0.5 * hist[best] && split <= 2.0 * hist[best] &&
                            pair / inside_per_bin >= 10.0 && beyond_pair <= 0.15 * pair));
    return is_spike ? best : -1;
  };
  // Where a clip lands: at the data's white (black), or a level or two inside it where a codec
  // moves a flat area (x264's clipped white in limited range decodes at 233-235), and anywhere in
  // the data's outer 4 % (JPEG's clipped white at 252-254; full range's, and a limited-range
  // frame's whose range was misjudged). Not elsewhere beyond white: a camera's superwhite plateau
  // is no clip (one at the data's end counts anyway, below). Not lower in limited range: Greeff's
  // MPEG-4 background, unclipped, peaks at 231.
  const int white_bin = std::min(kBins - 1, static_cast<int>(std::lround(levels.white * scale)));
  const int black_bin = std::max(0, static_cast<int>(std::lround(levels.black * scale)));
  const int near_bins =
      static_cast<int>(std::lround(kNearWhiteFraction * (levels.white - levels.black) * scale));
  // Each end's windows, searched in turn from `from` toward `to` (not included): by the frame's
  // white (black), then the data's outer bins where those are not the data's end.
  // (On the stack: every band of every frame passes here.)
  struct Window {
    int from, to, inward;
  };
  struct Windows {
    std::array<Window, 2> w;
    int size;
    const Window* begin() const { return w.data(); }
    const Window* end() const { return w.data() + size; }
  };
  const Windows top_windows = {
      {{{white_bin, std::min(kBins - 1 - kEdgeBins, white_bin - near_bins - 1), -1},
        {kBins - 1, kBins - 1 - kEdgeBins, -1}}},
      white_bin < kBins - 1 ? 2 : 1};
  const Windows bottom_windows = {
      {{{black_bin, std::max(kEdgeBins, black_bin + near_bins + 1), +1}, {0, kEdgeBins, +1}}},
      black_bin > 0 ? 2 : 1};
  const auto find = [&](const Windows& windows, const Histogram& hist, int count) {
    for (const Window& w : windows) {
      const int b = spike(hist, count, w.from, w.to, w.inward);
      if (b >= 0) return b;
    }
    return -1;
  };
  int top = find(top_windows, h, n), bottom = find(bottom_windows, h, n);
  // A slab beside an object holds little of a clipped plateau, and a codec's ringing there may
  // hide its spike (x264 at a low rate: 9986 and 6715 pixels four and three levels below the
  // clip's 235 in one slab, where the frame has 736 454 at 235). Where the slab holds 2 % of its
  // pixels in the levels searched for a clip but shows none, the clip, a property of the camera
  // and codec, is looked for over the whole image (every 4th pixel of every 4th row), when that
  // is more than the slab, and taken where the slab holds 2 % of its pixels at it too (a clip
  // elsewhere, a lamp's, says nothing of a slab that does not reach it).
  const auto slab_holds = [&](const Windows& windows) {
    for (const Window& w : windows) {
      int k = 0;
      for (int b = w.from; b != w.to; b += w.inward) k += h[b];
      if (k >= 0.02 * n) return true;
    }
    return false;
  };
  const bool look_top = top < 0 && slab_holds(top_windows);
  const bool look_bottom = bottom < 0 && slab_holds(bottom_windows);
  constexpr int kStride = 4;
  if ((look_top || look_bottom) && img.m.total() >= 4.0 * std::max(n, 1)) {
    Histogram frame{};
    int frame_n = 0;
    const auto sample_row = [&](const auto* row) {
      for (int x = 0; x < img.m.cols; x += kStride, ++frame_n) ++frame[bin_of(row[x])];
    };
    for (int y = 0; y < img.m.rows; y += kStride) {
      if (img.is16)
        sample_row(img.m.ptr<uint16_t>(y));
      else
        sample_row(img.m.ptr<uint8_t>(y));
    }
    const auto held = [&](int b) { return b >= 0 && h[b] >= 0.02 * n ? b : -1; };
    if (look_top) top = held(find(top_windows, frame, frame_n));
    if (look_bottom) bottom = held(find(bottom_windows, frame, frame_n));
  }
  // Half a bin inward, so that every value of the spike's bin counts.
  if (top >= 0) clip.high = static_cast<float>((top - 0.5) / scale);
  if (bottom >= 0) clip.low = static_cast<float>((bottom + 0.5) / scale);
  int low = 0, high = 0;
  for (int b = 0; b < kBins; ++b) {
    const double v = b / scale;
    if (v <= clip.low) low += h[b];
    if (v >= clip.high) high += h[b];
  }
  clip.clipped_low_fraction = n > 0 ? static_cast<double>(low) / n : 0.0;
  clip.clipped_high_fraction = n > 0 ? static_cast<double>(high) / n : 0.0;
  return clip;
}

bool GatherEdgeSamples(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                       double u1, const ClipLevels& clip, std::vector<EdgeSample>* out,
                       int* saturated) {
  out->clear();
  return ForEachSlabPixel(img, f, s0, s1, u0, u1, [&](double u, float v) {
    if (saturated && Clipped(v, clip)) ++*saturated;
    out->push_back({static_cast<float>(u), v});
  });
}

namespace {
// The indices 0..n−1 in order of the samples' u, ties in their own order (std::stable_sort's
// result). A slab's samples come a row at a time, each row in order of u: the runs already in
// order are merged pairwise, which costs n·log(runs) against the sort's n·log(n).
void SortStablyByU(const std::vector<EdgeSample>& samples, std::vector<int>* order) {
  const size_t n = samples.size();
  std::vector<int>& a = *order;
  a.resize(n);
  for (size_t i = 0; i < n; ++i) a[i] = static_cast<int>(i);
  std::vector<size_t> starts;  // where each run begins, and n
  for (size_t i = 0; i < n; ++i)
    if (i == 0 || samples[i].u_px < samples[i - 1].u_px) starts.push_back(i);
  starts.push_back(n);
  const auto by_u = [&](int x, int y) { return samples[x].u_px < samples[y].u_px; };
  std::vector<int> b(n);
  while (starts.size() > 2) {
    std::vector<size_t> merged;
    size_t r = 0;
    for (; r + 2 < starts.size(); r += 2) {
      // std::merge takes the first range's element on a tie: stable.
      std::merge(a.begin() + starts[r], a.begin() + starts[r + 1], a.begin() + starts[r + 1],
                 a.begin() + starts[r + 2], b.begin() + starts[r], by_u);
      merged.push_back(starts[r]);
    }
    if (r + 1 < starts.size()) {  // an odd run out: copied as it is
      std::copy(a.begin() + starts[r], a.begin() + starts[r + 1], b.begin() + starts[r]);
      merged.push_back(starts[r]);
    }
    merged.push_back(n);
    a.swap(b);
    starts.swap(merged);
  }
}
}  // namespace

PixelGroups GroupByU(const std::vector<EdgeSample>& samples, double span_px, double interior_lo_px,
                     double interior_hi_px, double interior_span_px) {
  PixelGroups out;
  const size_t n = samples.size();
  SortStablyByU(samples, &out.pixels);
  out.offset_px.resize(n);
  out.end.reserve(n);
  out.mean_u_px.reserve(n);
  for (size_t begin = 0; begin < n;) {
    const double first = samples[out.pixels[begin]].u_px;
    const bool inside = first >= interior_lo_px && first < interior_hi_px;
    const double last =
        inside ? std::min(first + interior_span_px, interior_hi_px) : first + span_px;
    size_t end = begin + 1;
    while (end < n && samples[out.pixels[end]].u_px <= last) ++end;
    double mean = 0;
    for (size_t k = begin; k < end; ++k) mean += samples[out.pixels[k]].u_px;
    mean /= static_cast<double>(end - begin);
    for (size_t k = begin; k < end; ++k)
      out.offset_px[k] = static_cast<float>(samples[out.pixels[k]].u_px - mean);
    out.end.push_back(static_cast<int>(end));
    out.mean_u_px.push_back(mean);
    begin = end;
  }
  return out;
}

ClippedCount CountClippedNear(const std::vector<EdgeSample>& samples, const ClipLevels& clip,
                              double edge_u, double half_px) {
  ClippedCount n;
  for (const EdgeSample& smp : samples) n.Add(smp, clip, edge_u, half_px);
  return n;
}

double InnerEdgeDistance(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                         double edge_u, int inward, double max_depth_px, double min_step,
                         double* beyond_px, double beyond_depth_px) {
  constexpr double kStepPx = 0.5, kBehindPx = 4.0, kStepReachPx = 3.0;
  constexpr int kRows = 12;
  const int reach = static_cast<int>(kStepReachPx / kStepPx);
  const int n_first = static_cast<int>((max_depth_px + kBehindPx) / kStepPx) + 1;
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (beyond_px) *beyond_px = kNone;
  if (n_first < 8 || n_first > 4096) return kNone;
  // A stripe's far side is sought as deep as beyond_depth_px, where the image allows.
  const int n_deep =
      beyond_px
          ? std::max(n_first,
                     std::min(4096, static_cast<int>((beyond_depth_px + kBehindPx) / kStepPx) + 1))
          : n_first;
  // The median over rows: a blob over part of the band is not an edge along the object. And,
  // within max_depth_px, the rows' spread about it, which at a place along the profile is noise
  // (and texture), not the object's structure across it. Sampled as far as `until`, or until the
  // rows leave the image (the profile ends there).
  std::vector<double> profile, spread;
  const BandRows<kRows> rows(f, s0, s1);
  // The middle value (the upper of two) of a column: of a whole one through a median network
  // (robust.h), of one cut short by the image's side through nth_element. The same value either
  // way.
  static_assert(kRows == 12);
  const auto middle = [](double* v, int n) {
    if (n == kRows) return UpperMedianOf12(v);
    std::nth_element(v, v + n / 2, v + n);
    return v[n / 2];
  };
  double column[kRows];
  bool ended = false;
  const auto extend = [&](int until) {
    for (int i = static_cast<int>(profile.size()); i < until && !ended; ++i) {
      const double u = edge_u + inward * (i * kStepPx - kBehindPx);
      int n = 0;
      for (int r = 0; r < kRows; ++r) {
        const double x = rows.X(r, u), y = rows.Y(r, u);
        if (img.InsideForBilinear(x, y)) column[n++] = img.Bilinear(x, y);
      }
      if (n < kRows / 2) {
        ended = true;
        break;
      }
      profile.push_back(middle(column, n));
      if (i < n_first) {
        for (int k = 0; k < n; ++k) column[k] = std::abs(column[k] - profile[i]);
        spread.push_back(middle(column, n));
      }
    }
  };
  extend(n_first);
  if (ended) return kNone;
  // The first edge's test reads up to `reach` samples past its depth; the rest of a deep profile
  // only once there is an inner edge whose far side to seek.
  extend(std::min(n_deep, n_first + reach + 1));
  // The gradient along the inward direction, over 1 px, signed like the silhouette's: an inner
  // edge turns back (a bright stripe or core in a dark strand, a lens's core after its rim). A lit
  // strand's shading ramp, brightening inward like its silhouette, never does.
  const int edge_i = static_cast<int>(kBehindPx / kStepPx);
  const double sign =
      profile[std::min(n_first - 1, edge_i + 6)] >= profile[std::max(0, edge_i - 6)] ? 1.0 : -1.0;
  std::vector<double> along;
  const auto gradients = [&]() {  // along[i] for the profile as it stands, 0 at its ends
    const int n = static_cast<int>(profile.size());
    const int from = std::max(1, static_cast<int>(along.size()) - 1);
    along.resize(n, 0.0);
    for (int i = from; i + 1 < n; ++i) along[i] = sign * (profile[i + 1] - profile[i - 1]);
  };
  gradients();
  // The profile's own noise (medians of noisy rows): an inner edge stands well above it.
  // Differences 1 px apart, their median: the few across real edges do not move it. But inside
  // a narrow object most of them may cross a stripe's blurred sides: the rows' spread about the
  // median at each place (its median, as the σ of a median of the rows) bounds it from there.
  std::vector<double> diffs;
  for (int i = edge_i + reach; i + 2 < n_first; ++i)
    diffs.push_back(std::abs(profile[i + 2] - profile[i]));
  double noise = 0;
  if (diffs.size() >= 5) {
    std::nth_element(diffs.begin(), diffs.begin() + diffs.size() / 2, diffs.end());
    noise = kMadToSigma * diffs[diffs.size() / 2] / std::sqrt(2.0);
    if (spread.size() >= 5) {
      std::nth_element(spread.begin(), spread.begin() + spread.size() / 2, spread.end());
      // A median of kRows values: 1.25σ/√kRows.
      noise = std::min(noise, kMadToSigma * spread[spread.size() / 2] * 1.25 / std::sqrt(kRows));
    }
  }
  min_step = std::max(min_step, 8.0 * noise);
  // The edge's own peak near the edge; then an edge in its own right past it: a peak of
  // turn·along (turn −1: the gradient turned back; +1: back to the silhouette's sign) of at
  // least a quarter of the silhouette's gradient, with a step of min_step across it.
  int peak = edge_i;
  for (int i = std::max(1, edge_i - 6); i <= std::min(n_first - 2, edge_i + 6); ++i)
    if (along[i] > along[peak]) peak = i;
  const auto edge_at = [&](int i, double turn) {
    const int n = static_cast<int>(profile.size());
    const double a = turn * along[i];
    if (!(a > 0 && a >= turn * along[i - 1] && a >= turn * along[i + 1]) || a < 0.25 * along[peak])
      return false;
    return std::abs(profile[std::min(n - 1, i + reach)] - profile[std::max(0, i - reach)]) >=
           min_step;
  };
  // Past the silhouette's own step (the ±3 px the step is read over).
  for (int i = peak + reach + 1; i + 1 < n_first; ++i) {
    if (!edge_at(i, -1.0)) continue;
    if (beyond_px) {
      // And the edge after it, turning back to the silhouette's sign.
      extend(n_deep);
      gradients();
      for (int k = i + 1; k + 1 < static_cast<int>(profile.size()); ++k) {
        if (edge_at(k, 1.0)) {
          *beyond_px = (k - edge_i) * kStepPx;
          break;
        }
      }
    }
    return (i - edge_i) * kStepPx;
  }
  return kNone;
}

double RefineEdgeGuess(const GreyImage& img, const AxisFrame& f, double s, double u_guess,
                       double half, double min_step, int sign) {
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
    if (sign != 0 && (v[i + 1] > v[i]) != (sign > 0)) continue;
    const double u = u_guess - half + (i + (mid - v[i]) / (v[i + 1] - v[i])) * kStep;
    if (std::abs(u - u_guess) < best_dist) {
      best_dist = std::abs(u - u_guess);
      best = u;
    }
  }
  return best;
}

}  // namespace clogscope::vision
