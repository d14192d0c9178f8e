#include "vision/scene/edge_segments.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <opencv2/imgproc.hpp>

#include "common/angle.h"
#include "common/robust.h"

namespace clogscope::vision {
namespace {

constexpr double kStraightTolPx = 1.0;  // a piece deviates less than this from its line

// Links edge points of consecutive sampled rows into chains (same sign, continuing the chain's
// direction), allowing one missed row.
std::vector<std::vector<EdgePoint>> LinkChains(const Detection& d, double max_tilt_deg) {
  struct Chain {
    std::vector<EdgePoint> pts;
    int last_row = 0;
  };
  std::vector<Chain> active;
  std::vector<std::vector<EdgePoint>> done;
  const double tan_max = std::tan(max_tilt_deg * kDegToRad);
  struct Link {
    float dist;
    int chain, point;
  };
  std::vector<Link> links;
  for (int r = 0; r < static_cast<int>(d.rows.size()); ++r) {
    const auto& pts = d.rows[r];
    // Close chains that missed two rows.
    for (size_t c = 0; c < active.size();) {
      if (active[c].last_row < r - 2) {
        done.push_back(std::move(active[c].pts));
        active[c] = std::move(active.back());
        active.pop_back();
      } else {
        ++c;
      }
    }
    links.clear();
    for (int c = 0; c < static_cast<int>(active.size()); ++c) {
      const auto& cp = active[c].pts;
      const EdgePoint& last = cp.back();
      const double y = pts.empty() ? 0 : pts.front().y;
      double pred = last.x, tol;
      if (cp.size() >= 2) {
        const EdgePoint& first = cp[cp.size() >= 6 ? cp.size() - 6 : 0];
        const double slope = (last.x - first.x) / std::max(1e-6f, last.y - first.y);
        pred = last.x + slope * (y - last.y);
        tol = 1.5;
      } else {
        tol = (y - last.y) * tan_max + 1.5;
      }
      // Points are sorted by x: look only in [pred − tol, pred + tol].
      auto it = std::lower_bound(pts.begin(), pts.end(), pred - tol,
                                 [](const EdgePoint& p, double v) { return p.x < v; });
      for (; it != pts.end() && it->x <= pred + tol; ++it) {
        if (it->sign != last.sign) continue;
        links.push_back(
            {static_cast<float>(std::abs(it->x - pred)), c, static_cast<int>(it - pts.begin())});
      }
    }
    std::sort(links.begin(), links.end(),
              [](const Link& a, const Link& b) { return a.dist < b.dist; });
    std::vector<char> point_used(pts.size(), 0), chain_used(active.size(), 0);
    for (const Link& l : links) {
      if (point_used[l.point] || chain_used[l.chain]) continue;
      point_used[l.point] = chain_used[l.chain] = 1;
      active[l.chain].pts.push_back(pts[l.point]);
      active[l.chain].last_row = r;
    }
    for (size_t i = 0; i < pts.size(); ++i) {
      if (!point_used[i]) active.push_back({{pts[i]}, r});
    }
  }
  for (auto& c : active) done.push_back(std::move(c.pts));
  return done;
}

// Splits a chain into straight pieces (recursively at the point farthest from the fitted line).
void SplitStraight(const std::vector<EdgePoint>& pts, size_t lo, size_t hi,
                   std::vector<Piece>* out) {
  if (hi - lo + 1 < kMinPiecePoints) return;
  Piece p;
  p.pts.assign(pts.begin() + lo, pts.begin() + hi + 1);
  p.sign = pts[lo].sign;
  p.Fit();
  if (p.max_residual <= kStraightTolPx) {
    out->push_back(std::move(p));
    return;
  }
  size_t worst = lo;
  double worst_r = -1;
  const double c = 1.0 / std::sqrt(1 + p.b * p.b);
  for (size_t i = lo; i <= hi; ++i) {
    const double r = std::abs(pts[i].x - p.X(pts[i].y)) * c;
    if (r > worst_r) {
      worst_r = r;
      worst = i;
    }
  }
  // Keep the split point on the side where it is not the end, so that the recursion shrinks.
  if (worst == lo) {
    SplitStraight(pts, lo + 1, hi, out);
  } else if (worst == hi) {
    SplitStraight(pts, lo, hi - 1, out);
  } else {
    SplitStraight(pts, lo, worst - 1, out);
    SplitStraight(pts, worst + 1, hi, out);
  }
}

// Joins collinear pieces of the same sign along one line (an edge broken by a blob, a reflection
// or a weak stretch).
void MergeCollinear(std::vector<Piece>* pieces, int row_step) {
  std::sort(pieces->begin(), pieces->end(),
            [](const Piece& a, const Piece& b) { return a.y0() < b.y0(); });
  bool merged = true;
  while (merged) {
    merged = false;
    for (size_t i = 0; i < pieces->size() && !merged; ++i) {
      for (size_t j = i + 1; j < pieces->size(); ++j) {
        Piece& p = (*pieces)[i];
        Piece& q = (*pieces)[j];
        if (p.sign != q.sign) continue;
        if (q.y0() < p.y1() - row_step + 0.5) continue;  // overlapping rows: parallel, not one
        const double gap = q.y0() - p.y1();
        if (gap > std::max(30.0, 0.5 * ((p.y1() - p.y0()) + (q.y1() - q.y0())))) continue;
        if (std::abs(std::atan(p.b) - std::atan(q.b)) > 3.0 * kDegToRad) continue;
        if (std::abs(p.X(q.y0()) - q.pts.front().x) > 1.5 ||
            std::abs(q.X(p.y1()) - p.pts.back().x) > 1.5)
          continue;
        Piece m;
        m.pts = p.pts;
        m.pts.insert(m.pts.end(), q.pts.begin(), q.pts.end());
        m.sign = p.sign;
        m.Fit();
        if (m.max_residual > 1.5 * kStraightTolPx) continue;
        p = std::move(m);
        pieces->erase(pieces->begin() + j);
        merged = true;
        break;
      }
    }
  }
}

// Sums of 8-bit pixels in 16-bit integers (twice the lanes of floats), of others in floats: both
// exact for the masks here (|sum| ≤ 16·255), so the results are the same to the bit.
template <typename T>
struct SumOf {
  using type = float;
};
template <>
struct SumOf<uint8_t> {
  using type = int16_t;
};

// The 3×3 Sobel gradients (scaled by 1/8) about one row of a CV_8U or CV_32F image, the border
// replicated: only the sampled rows' gradients are needed, and their |∂/∂y| only where |∂/∂x|
// peaks. Integer-valued data gives the same sums, exactly, in any order.
template <typename T>
class SobelRows {
 public:
  using Sum = typename SumOf<T>::type;
  SobelRows(const cv::Mat& img, int y)
      : above_(img.ptr<T>(std::max(0, y - 1))),
        row_(img.ptr<T>(y)),
        below_(img.ptr<T>(std::min(img.rows - 1, y + 1))),
        last_(img.cols - 1) {}
  // `column` holds cols values: each column's vertical [1 2 1] sum, from which ∂/∂x is a
  // difference (the 3×3 mask is separable; the integer-valued sums are the same either way).
  void GradientX(Sum* column, float* out) const {
    for (int x = 0; x <= last_; ++x)  // vectorised
      column[x] = static_cast<Sum>(Sum(above_[x]) + 2 * Sum(row_[x]) + Sum(below_[x]));
    out[0] = Scaled(column[std::min(1, last_)] - column[0]);
    for (int x = 1; x < last_; ++x) out[x] = Scaled(column[x + 1] - column[x - 1]);
    if (last_ > 0) out[last_] = Scaled(column[last_] - column[last_ - 1]);
  }
  float GradientY(int x) const {
    const int l = std::max(0, x - 1), r = std::min(last_, x + 1);
    const Sum sum = static_cast<Sum>((Sum(below_[l]) + 2 * Sum(below_[x]) + Sum(below_[r])) -
                                     (Sum(above_[l]) + 2 * Sum(above_[x]) + Sum(above_[r])));
    return static_cast<float>(sum) * 0.125f;
  }

 private:
  // A difference of two column sums (exact in Sum: at most 4·255 for 8-bit data), scaled by 1/8.
  static float Scaled(Sum difference) { return static_cast<float>(difference) * 0.125f; }
  const T *above_, *row_, *below_;
  int last_;
};

// |Immerkær's mask| at every inner column of row y (the rows above and below it too). The mask
// is [1 −2 1] across of [1 −2 1] down: `column` (cols values) holds each column's second
// difference down, whose second difference across is the response (integer-valued, the same
// either way).
template <typename T>
void NoiseMaskRow(const cv::Mat& img, int y, typename SumOf<T>::type* column, float* response) {
  using Sum = typename SumOf<T>::type;
  const T* a = img.ptr<T>(y - 1);
  const T* b = img.ptr<T>(y);
  const T* c = img.ptr<T>(y + 1);
  for (int x = 0; x < img.cols; ++x)  // vectorised
    column[x] = static_cast<Sum>(Sum(a[x]) - 2 * Sum(b[x]) + Sum(c[x]));
  for (int x = 1; x + 1 < img.cols; ++x) {  // every column: vectorised; every other one used
    const Sum sum = static_cast<Sum>(column[x - 1] - 2 * column[x] + column[x + 1]);
    response[x] = std::abs(static_cast<float>(sum));
  }
}

// Every sampled row's local maxima of |∂/∂x| above the threshold, within tan_max of upright.
template <typename T>
void FindEdgePoints(const cv::Mat& img, float threshold, float tan_max, Detection* d) {
  const int cols = img.cols;
  std::vector<float> gx(cols);
  std::vector<typename SobelRows<T>::Sum> column(cols);
  // Which columns rise above the threshold: found in one vectorised pass, then looked at 8 at a
  // time, skipping the words with none (most of a row is below it).
  const int words = (cols + 7) / 8;
  std::vector<uint8_t> above(8 * words, 0);
  for (int y = d->row_step / 2; y < img.rows; y += d->row_step) {
    const SobelRows<T> rows(img, y);
    rows.GradientX(column.data(), gx.data());
    const float* g = gx.data();
    for (int x = 0; x < cols; ++x) above[x] = std::abs(g[x]) >= threshold;
    std::vector<EdgePoint> pts;
    for (int w = 0; w < words; ++w) {
      uint64_t any;
      std::memcpy(&any, &above[8 * w], sizeof any);
      if (any == 0) continue;
      for (int x = std::max(1, 8 * w); x < std::min(cols - 1, 8 * w + 8); ++x) {
        if (!above[x]) continue;
        const float a = std::abs(g[x]);
        const float l = std::abs(g[x - 1]), r = std::abs(g[x + 1]);
        if (a < l || a <= r) continue;
        if (std::abs(rows.GradientY(x)) > a * tan_max) continue;  // too far from an upright edge
        // Sub-pixel position: centroid of the peak above half its height. A parabola through
        // three samples is as good on sharp edges and far less noisy on blurred, broad ones.
        const float half = 0.5f * a;
        double sw = 0, sx = 0;
        for (int k = x; k >= std::max(0, x - 12); --k) {
          const float wk = std::abs(g[k]) - half;
          if (wk <= 0 || (k < x && (g[k] > 0) != (g[x] > 0))) break;
          sw += wk;
          sx += wk * k;
        }
        for (int k = x + 1; k <= std::min(cols - 1, x + 12); ++k) {
          const float wk = std::abs(g[k]) - half;
          if (wk <= 0 || (g[k] > 0) != (g[x] > 0)) break;
          sw += wk;
          sx += wk * k;
        }
        pts.push_back({static_cast<float>(sx / sw), static_cast<float>(y), a, g[x] > 0 ? 1 : -1});
      }
    }
    d->rows.push_back(std::move(pts));
    d->row_y.push_back(static_cast<float>(y));
  }
}

}  // namespace

void Piece::Fit() {
  double n = 0, sy = 0, sx = 0, syy = 0, sxy = 0;
  for (const auto& p : pts) {
    n += 1;
    sy += p.y;
    sx += p.x;
    syy += double(p.y) * p.y;
    sxy += double(p.y) * p.x;
  }
  const double var = n * syy - sy * sy;
  b = var > 1e-9 ? (n * sxy - sx * sy) / var : 0.0;
  a = (sx - b * sy) / n;
  const double c = 1.0 / std::sqrt(1 + b * b);
  max_residual = 0;
  for (const auto& p : pts) max_residual = std::max(max_residual, std::abs(p.x - X(p.y)) * c);
}

Detection DetectEdgePoints(const cv::Mat& channel, const SceneOptions& o) {
  Detection d;
  d.factor = std::min(channel.cols, channel.rows) >= 240 ? 2 : 1;
  d.row_step = std::max(1, 4 / d.factor);
  cv::Mat small;
  if (d.factor == 2) {
    cv::resize(channel, small, cv::Size(channel.cols / 2, channel.rows / 2), 0, 0, cv::INTER_AREA);
  } else {
    small = channel;
  }
  // 8-bit data at the detection scale is whole grey levels (INTER_AREA rounds) and is searched
  // as it is; other depths as floats.
  const bool whole_levels = small.depth() == CV_8U;
  cv::Mat img = small;
  if (!whole_levels) small.convertTo(img, CV_32F);
  d.image = img;

  // Pixel noise by Immerkær's mask [1 −2 1; −2 4 −2; 1 −2 1] (σ of its response is 6σ for white
  // noise), robustly through the median: a second difference hardly sees smooth texture or
  // straight edges, whereas a median gradient would count a textured scene as noise. The Sobel
  // gradient scaled by 1/8 carries 0.433σ of it.
  // On 8-bit data the mask's responses are integers up to 16·255 and their median is read off
  // their counts: a selection over 57 600 of them was most of a 720p frame's search.
  constexpr int kLevels = 16 * 255 + 1, kLanes = 4;  // lanes: no wait on the last count's store
  std::vector<double> lap;
  std::vector<int> lane_counts(whole_levels ? kLanes * kLevels : 0, 0);
  long long counted = 0;
  std::vector<float> response(img.cols, 0.0f);
  std::vector<SumOf<uint8_t>::type> column8(whole_levels ? img.cols : 0);
  std::vector<SumOf<float>::type> column32(whole_levels ? 0 : img.cols);
  for (int y = std::max(1, d.row_step / 2); y + 1 < img.rows; y += d.row_step) {
    if (whole_levels)
      NoiseMaskRow<uint8_t>(img, y, column8.data(), response.data());
    else
      NoiseMaskRow<float>(img, y, column32.data(), response.data());
    // Every other inner column (x = 1, 3, …, x + 1 < cols); on 8-bit data four at a time, one
    // to a lane. The responses are whole numbers.
    int x = 1;
    if (whole_levels) {
      int* const c = lane_counts.data();
      for (; x + 7 < img.cols; x += 8) {
        ++c[static_cast<int>(response[x])];
        ++c[kLevels + static_cast<int>(response[x + 2])];
        ++c[2 * kLevels + static_cast<int>(response[x + 4])];
        ++c[3 * kLevels + static_cast<int>(response[x + 6])];
      }
      for (; x + 1 < img.cols; x += 2) ++c[static_cast<int>(response[x])];
      counted += (img.cols - 1) / 2;
    } else {
      for (; x + 1 < img.cols; x += 2) lap.push_back(response[x]);
    }
  }
  static_assert(kLanes == 4, "the loop above and the sum below name each lane");
  const auto lanes_at = [&](size_t k) {
    return lane_counts[k] + lane_counts[kLevels + k] + lane_counts[2 * kLevels + k] +
           lane_counts[3 * kLevels + k];
  };
  const double pixel_noise =
      (whole_levels ? MedianOfCounts(kLevels, counted, lanes_at) : Median(std::move(lap))) /
      (0.6745 * 6.0);
  d.noise = std::max(0.433 * pixel_noise, o.min_contrast / 60.0);
  // An edge of the weakest accepted step at the largest blur still rises above this.
  const float threshold = static_cast<float>(std::max(5.0 * d.noise, o.min_contrast / 8.0));
  const float tan_max =
      static_cast<float>(std::tan(std::min(85.0, o.max_tilt_deg + 10) * kDegToRad));

  if (whole_levels)
    FindEdgePoints<uint8_t>(img, threshold, tan_max, &d);
  else
    FindEdgePoints<float>(img, threshold, tan_max, &d);
  return d;
}

std::vector<Piece> StraightPieces(const Detection& d, double max_tilt_deg) {
  std::vector<Piece> pieces;
  for (const auto& chain : LinkChains(d, max_tilt_deg))
    SplitStraight(chain, 0, chain.size() - 1, &pieces);
  MergeCollinear(&pieces, d.row_step);
  return pieces;
}

EdgeSegment ToSegment(const Piece& p, const Detection& d) {
  const double f = d.factor, off = 0.5 * (d.factor - 1);
  EdgeSegment s;
  s.top = {p.X(p.y0()) * f + off, p.y0() * f + off};
  s.bottom = {p.X(p.y1()) * f + off, p.y1() * f + off};
  s.sign = p.sign;
  std::vector<double> g;
  for (const auto& e : p.pts) g.push_back(e.g);
  s.strength = Median(g) / f;
  s.coverage = std::min(1.0, p.pts.size() / ((p.y1() - p.y0()) / d.row_step + 1.0));
  return s;
}

}  // namespace clogscope::vision
