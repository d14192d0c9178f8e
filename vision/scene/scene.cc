#include "vision/scene/scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/scene/edge_segments.h"
#include "vision/scene/tip.h"

namespace clogscope::vision {

// Whether the nozzle's face shows on both sides of a pair clearly enough that its absence beside
// another object says that object does not hang from it: a reading of it steps by
// kDecisiveFaceContrast times the least contrast searched for. One just above that least contrast
// may be missed beside the next object, or be a background's slope taken for part of a step.
namespace {
constexpr double kDecisiveFaceContrast = 1.5;
}  // namespace

bool HangsFromFace(const StrandGeometry& g, const SceneOptions& o) {
  return g.tip_face_sides == 2 && g.tip_face_step >= kDecisiveFaceContrast * o.min_contrast;
}

namespace {

constexpr int kMaxCandidates = 40;       // pairs kept after scoring
constexpr int kMaxFollowed = 6;          // pairs followed along the full-resolution image
constexpr double kFollowOffsetPx = 3.0;  // edge contrast is read this far either side
constexpr double kMixedPenalty = 0.5;    // a pair brighter on one side only is less likely
constexpr double kParallelSine = 0.035;  // two axes within 2° of each other are parallel
// Objects of the other polarity on both sides of a pair, sharing its edges, make it a stripe or a
// gap as much as a strand when each scores this share of it: its edges are theirs, so a score
// short of the ambiguity ratio says little about which is the object.
constexpr double kFlankScoreRatio = 0.5;
constexpr double kSameEdgePx = 1.5;  // two pairs' edges this close at mid-stretch are one line
// Whether two pairs' axes are parallel (within kParallelSine).
bool Parallel(const PairCandidate& a, const PairCandidate& b) {
  return std::abs(a.axis.dx * b.axis.dy - a.axis.dy * b.axis.dx) < kParallelSine;
}
// The face read beside a pair, on one side or faintly on both, but not decisively.
bool FaceReadInPart(const StrandGeometry& g, const SceneOptions& o) {
  return g.tip_face_sides >= 1 && !HangsFromFace(g, o);
}
// A rival that scores less than this share of the best is no strand, even where the tip does not
// decide: the short pairs of clutter discs and blobs that held up scored 7-24 % of the strand's
// in the robustness scenes, while a long hair may score as well as the strand.
constexpr double kRivalScoreRatio = 0.5;
// An edge this many times the least contrast is an object's, not a background's texture.
constexpr double kFadedRivalContrast = 3.0;
// Whether `c` could be the strand as much as `b` where the tip does not decide. A score ranks by
// length and contrast, and a strand whose shaded side is faint scores little for it: a 111 px
// strand (its pair 109 px) scored 18-34 % of a 14 px hair from the nozzle's corner, which was
// measured alone. So a pair wider than `b` rivals it whatever its score where one of its edges is
// longer than the pair is wide (a disc's or blob's edges are all short): never the thinner object
// by default. The longer edge, not the common stretch: where a faint edge broke up, the stretch
// shrank to 80 px of that strand while its longer edge ran 250 px.
bool CouldRival(const PairCandidate& b, const PairCandidate& c) {
  return c.score >= kRivalScoreRatio * b.score ||
         (c.width_px > b.width_px && c.long_edge_px >= c.width_px);
}
// An edge walk that ends within this of its start began off the edge.
constexpr double kOffEdgeStartPx = 3.0;
constexpr double kEndFraction = 0.3;  // an edge ends where its contrast falls below this share

// The segment's line in an axis frame: u at s.
struct LineInAxis {
  double s0, s1, u0, u1;
  double U(double s) const { return s1 > s0 ? u0 + (u1 - u0) * (s - s0) / (s1 - s0) : u0; }
};
LineInAxis InAxis(const EdgeSegment& e, const AxisFrame& a) {
  return {a.S(e.top.x, e.top.y), a.S(e.bottom.x, e.bottom.y), a.U(e.top.x, e.top.y),
          a.U(e.bottom.x, e.bottom.y)};
}

Polarity PairPolarity(int left_sign, int right_sign) {
  if (left_sign > 0 && right_sign < 0) return Polarity::kBrightOnDark;
  if (left_sign < 0 && right_sign > 0) return Polarity::kDarkOnBright;
  return Polarity::kMixed;
}

// Two edges as a strand silhouette: geometry and score, or false when they are not parallel, too
// short together, too narrow or too wide. `left`/`right` in the result are 0 and 1 (a and b).
bool MakeCandidate(const EdgeSegment& a, const EdgeSegment& b, double noise_full, int roi_width,
                   double min_overlap, const SceneOptions& o, PairCandidate* out) {
  const cv::Point2d da = (a.bottom - a.top) / a.length_px();
  const cv::Point2d db = (b.bottom - b.top) / b.length_px();
  const double min_len = std::min(a.length_px(), b.length_px());
  const double dangle = std::abs(std::atan2(da.x, da.y) - std::atan2(db.x, db.y));
  if (dangle > std::max(3.0 * kDegToRad, std::atan(3.0 / min_len))) return false;
  cv::Point2d dir = a.length_px() * da + b.length_px() * db;
  dir /= cv::norm(dir);
  if (std::abs(std::atan2(dir.x, dir.y)) > o.max_tilt_deg * kDegToRad) return false;
  AxisFrame ax{0.25 * (a.top.x + a.bottom.x + b.top.x + b.bottom.x),
               0.25 * (a.top.y + a.bottom.y + b.top.y + b.bottom.y), dir.x, dir.y};
  LineInAxis la = InAxis(a, ax), lb = InAxis(b, ax);
  int li = 0, ri = 1;
  if (la.U(0.5 * (la.s0 + la.s1)) > lb.U(0.5 * (lb.s0 + lb.s1))) {
    std::swap(la, lb);
    std::swap(li, ri);
  }
  const double s0 = std::max(la.s0, lb.s0), s1 = std::min(la.s1, lb.s1);
  const double len = s1 - s0;
  if (len < min_overlap) return false;
  const double w0 = lb.U(s0) - la.U(s0), w1 = lb.U(s1) - la.U(s1);
  const double width = 0.5 * (w0 + w1);
  if (width < o.min_width_px || width > 0.9 * roi_width) return false;
  // Not parallel enough; a long pair may open by 0.6° (a curved end, such as a swell below the
  // nozzle, tilts a segment's fitted line).
  if (std::abs(w1 - w0) > std::max({2.0, 0.03 * width, 0.01 * len})) return false;
  const EdgeSegment& L = li == 0 ? a : b;
  const EdgeSegment& R = li == 0 ? b : a;
  const Polarity pol = PairPolarity(L.sign, R.sign);
  if (o.polarity != Polarity::kAuto && pol != o.polarity) return false;
  PairCandidate c;
  c.left = li;
  c.right = ri;
  c.polarity = pol;
  c.length_px = len;
  c.long_edge_px = std::max(a.length_px(), b.length_px());
  c.width_px = width;
  c.snr = std::min(L.strength, R.strength) / noise_full;
  // Length and continuity first; contrast with diminishing returns (a highlight stripe inside a
  // strand is as long as the strand but weaker).
  c.score = len * 0.5 * (L.coverage + R.coverage) * c.snr / (c.snr + 10.0) *
            (pol == Polarity::kMixed ? kMixedPenalty : 1.0);
  // Origin on the axis at the top of the common stretch.
  const double uc = 0.5 * (la.U(s0) + lb.U(s0));
  c.axis = {ax.ImageX(s0, uc), ax.ImageY(s0, uc), dir.x, dir.y};
  c.left_u0 = la.U(s0) - uc;
  c.right_u0 = lb.U(s0) - uc;
  c.edge_slope = 0.5 * ((la.U(s1) - la.U(s0)) + (lb.U(s1) - lb.U(s0))) / len;
  *out = c;
  return true;
}

// Re-counts a seed pair's support from every edge point near its two lines (same sign), not only
// the segments it came from: a jagged or broken edge (gear teeth, a reflection) arrives as many
// short pieces along one line. Keeps the longest run of rows where both edges are present (short
// gaps allowed) and refits both lines there. Returns the two edges, or false without a run.
bool ExtendPair(const Detection& d, const EdgeSegment& a, const EdgeSegment& b, EdgeSegment* ea,
                EdgeSegment* eb) {
  const double f = d.factor, off = 0.5 * (d.factor - 1);
  struct Line {
    double a, b;
    int sign;
  };
  auto to_small = [&](const EdgeSegment& e) {
    const double y0 = (e.top.y - off) / f, y1 = (e.bottom.y - off) / f;
    const double x0 = (e.top.x - off) / f, x1 = (e.bottom.x - off) / f;
    const double slope = y1 > y0 ? (x1 - x0) / (y1 - y0) : 0.0;
    return Line{x0 - slope * y0, slope, e.sign};
  };
  Line lines[2] = {to_small(a), to_small(b)};
  constexpr double kTolPx = 2.0;  // small px either side of the line
  constexpr int kMaxGapRows = 6;
  const int n = static_cast<int>(d.rows.size());
  std::vector<const EdgePoint*> hit[2];
  for (int pass = 0; pass < 2; ++pass) {
    for (int side = 0; side < 2; ++side) {
      hit[side].assign(n, nullptr);
      const Line& l = lines[side];
      for (int r = 0; r < n; ++r) {
        const double x = l.a + l.b * d.row_y[r];
        const auto& pts = d.rows[r];
        auto it = std::lower_bound(pts.begin(), pts.end(), x - kTolPx,
                                   [](const EdgePoint& p, double v) { return p.x < v; });
        double best = kTolPx;
        for (; it != pts.end() && it->x <= x + kTolPx; ++it) {
          if (it->sign == l.sign && std::abs(it->x - x) <= best) {
            best = std::abs(it->x - x);
            hit[side][r] = &*it;
          }
        }
      }
    }
    // Each side's runs of rows with support (gaps of up to kMaxGapRows); the pair of runs whose
    // stretches overlap most along the axis (a short, wide, tilted strand has its two edges on
    // different rows).
    struct RunRange {
      int lo, hi, count;
    };
    std::vector<RunRange> runs[2];
    for (int side = 0; side < 2; ++side) {
      int lo = -1, last = -1, count = 0;
      for (int r = 0; r <= n; ++r) {
        const bool here = r < n && hit[side][r];
        if (r == n || (here && last >= 0 && r - last - 1 > kMaxGapRows)) {
          if (count >= kMinPiecePoints) runs[side].push_back({lo, last, count});
          lo = -1;
          count = 0;
        }
        if (here) {
          if (lo < 0) lo = r;
          last = r;
          ++count;
        }
      }
    }
    // Along-axis position of a row on a side's line: the seed axis is close to both lines.
    const double ax = 0.5 * (lines[0].b + lines[1].b), norm = std::sqrt(1 + ax * ax);
    const auto s_of = [&](int side, int r) {
      const double y = d.row_y[r];
      return (lines[side].a + lines[side].b * y) * ax / norm + y / norm;
    };
    int best[2] = {-1, -1};
    double best_overlap = 0;
    for (size_t i = 0; i < runs[0].size(); ++i) {
      for (size_t j = 0; j < runs[1].size(); ++j) {
        const double lo = std::max(s_of(0, runs[0][i].lo), s_of(1, runs[1][j].lo));
        const double hi = std::min(s_of(0, runs[0][i].hi), s_of(1, runs[1][j].hi));
        if (hi - lo > best_overlap) {
          best_overlap = hi - lo;
          best[0] = static_cast<int>(i);
          best[1] = static_cast<int>(j);
        }
      }
    }
    if (best[0] < 0) return false;
    // Refit both lines on their runs' points.
    for (int side = 0; side < 2; ++side) {
      const RunRange& run = runs[side][best[side]];
      Piece p;
      p.sign = lines[side].sign;
      for (int r = run.lo; r <= run.hi; ++r)
        if (hit[side][r]) p.pts.push_back(*hit[side][r]);
      p.Fit();
      lines[side] = {p.a, p.b, p.sign};
      if (pass == 1) {
        EdgeSegment& e = side == 0 ? *ea : *eb;
        e = ToSegment(p, d);
        e.coverage = run.count / (run.hi - run.lo + 1.0);
      }
    }
  }
  return true;
}

// Scores pairs of long segments as strand silhouettes: every parallel, overlapping pair seeds two
// lines, whose support is then counted over all edge points (ExtendPair).
std::vector<PairCandidate> PairSegments(const Detection& d, const std::vector<EdgeSegment>& edges,
                                        double noise_full, int roi_width, const SceneOptions& o) {
  std::vector<PairCandidate> seeds;
  for (size_t i = 0; i < edges.size(); ++i) {
    for (size_t j = i + 1; j < edges.size(); ++j) {
      PairCandidate c;
      if (!MakeCandidate(edges[i], edges[j], noise_full, roi_width, 0.5 * o.min_length_px, o, &c))
        continue;
      c.left = c.left == 0 ? static_cast<int>(i) : static_cast<int>(j);
      c.right = c.right == 0 ? static_cast<int>(i) : static_cast<int>(j);
      seeds.push_back(c);
    }
  }
  std::sort(seeds.begin(), seeds.end(),
            [](const PairCandidate& a, const PairCandidate& b) { return a.score > b.score; });
  std::vector<PairCandidate> out;
  for (size_t k = 0; k < seeds.size() && k < 3 * kMaxCandidates; ++k) {
    EdgeSegment el, er;
    if (!ExtendPair(d, edges[seeds[k].left], edges[seeds[k].right], &el, &er)) continue;
    PairCandidate c;
    // Extended lines that are no longer parallel took in a curve (a strand swelling below the
    // nozzle): the seed's own segments stand.
    if (!MakeCandidate(el, er, noise_full, roi_width, o.min_length_px, o, &c) &&
        !MakeCandidate(edges[seeds[k].left], edges[seeds[k].right], noise_full, roi_width,
                       o.min_length_px, o, &c))
      continue;
    c.left = seeds[k].left;
    c.right = seeds[k].right;
    // Seeds along the same two lines end up as one candidate: keep it once.
    bool duplicate = false;
    for (const auto& e : out) {
      if (std::abs(e.width_px - c.width_px) < 1.0 &&
          std::abs(e.axis.U(c.axis.ox, c.axis.oy)) < 1.0 &&
          std::abs(e.axis.dx * c.axis.dy - e.axis.dy * c.axis.dx) < 0.01) {
        duplicate = true;
        break;
      }
    }
    if (!duplicate) out.push_back(c);
  }
  std::sort(out.begin(), out.end(),
            [](const PairCandidate& a, const PairCandidate& b) { return a.score > b.score; });
  if (out.size() > kMaxCandidates) out.resize(kMaxCandidates);
  return out;
}

// u-interval of a candidate in another candidate's frame, at the middle of its stretch.
std::pair<double, double> Interval(const PairCandidate& c, const AxisFrame& frame) {
  const double sm = 0.5 * c.length_px;
  const double xl = c.axis.ImageX(sm, c.left_u0 + c.edge_slope * sm);
  const double yl = c.axis.ImageY(sm, c.left_u0 + c.edge_slope * sm);
  const double xr = c.axis.ImageX(sm, c.right_u0 + c.edge_slope * sm);
  const double yr = c.axis.ImageY(sm, c.right_u0 + c.edge_slope * sm);
  return {frame.U(xl, yl), frame.U(xr, yr)};
}

// Two pairs with no edge in common, side by side (across b's axis at mid-stretch).
bool Disjoint(const PairCandidate& b, const PairCandidate& c) {
  if (c.left == b.left || c.left == b.right || c.right == b.left || c.right == b.right)
    return false;
  const auto [bl, br] = Interval(b, b.axis);
  const auto [cl, cr] = Interval(c, b.axis);
  return cr < bl || cl > br;
}

// A bright pair and a dark one.
bool OppositeKinds(const PairCandidate& a, const PairCandidate& b) {
  return (a.polarity == Polarity::kBrightOnDark && b.polarity == Polarity::kDarkOnBright) ||
         (a.polarity == Polarity::kDarkOnBright && b.polarity == Polarity::kBrightOnDark);
}

// Whether two pairs are both bright on dark or both dark on bright (not mixed).
bool SameKind(const PairCandidate& a, const PairCandidate& b) {
  return a.polarity == b.polarity && a.polarity != Polarity::kMixed;
}

// Whether `inner` lies across the axis inside `outer`, a wider pair, or shares one edge with it
// and lies inside with the other (half a highlight stripe with the strand's far edge; a shading
// ridge with the other silhouette).
bool Contains(const PairCandidate& outer, const PairCandidate& inner) {
  if (outer.width_px <= inner.width_px + 3.0) return false;
  const auto [l, r] = Interval(inner, outer.axis);
  const auto [ol, orr] = Interval(outer, outer.axis);
  return l >= ol - kSameEdgePx && r <= orr + kSameEdgePx;
}

// Whether `outer` contains `inner` and is comparable to it, so that the outer silhouette is the
// object.
bool Encloses(MeasureTarget target, const PairCandidate& outer, const PairCandidate& inner) {
  if (!Contains(outer, inner)) return false;
  // Inside an outer silhouette, edges of its own kind (a shading ridge, a clear strand's
  // internal lines) or, below a nozzle, of the opposite kind (a bright stripe or a lens's
  // core in a dark strand) never make the strand, whatever their contrast; a mixed pair
  // inside, or a mixed outer pair (brighter on one side, darker on the other), is a weaker
  // case. (Between a filament's gears and idler, a dark gap inside a bright outer pair is
  // often the better pair: there the opposite kind stays a weaker case.)
  const bool opposite = target == MeasureTarget::kStrand && OppositeKinds(outer, inner);
  const bool same_kind = outer.polarity == inner.polarity;
  return outer.score >= (same_kind || opposite ? 0.3 : 0.8) * inner.score;
}

// Whether `b` lies inside `c`, parallel to it, and `c` could rival it as the strand.
bool InsideARival(const PairCandidate& b, const PairCandidate& c) {
  return Contains(c, b) && CouldRival(b, c) && Parallel(b, c);
}

// Whether a strand pair `b` may be the inside of the wider pair `c` of the other kind, one that
// could rival it (a stripe or a lens's core inside a strand whose own pair is faint). Of its own
// kind, such a pair is as often the strand and a hair beside it, paired across both (over eight
// sets, 41 valid frames, each right, were doubted so).
bool MayBeInsideOf(const PairCandidate& b, const PairCandidate& c) {
  return OppositeKinds(b, c) && InsideARival(b, c);
}

// Rules out a pair lying inside a wider one, the object.
void JudgeInsideWider(const PairCandidate& outer, PairCandidate* inner) {
  inner->Judge(PairVerdict::kInsideWider,
               fmt::format("inside a wider pair ({:.1f} px)", outer.width_px));
}

// Marks pairs lying inside a comparable outer pair along half their stretch or more (a highlight
// stripe, a clear strand's internal lines): the outer silhouette is the object.
void SuppressNested(MeasureTarget target, std::vector<PairCandidate>* cands) {
  auto& c = *cands;
  for (size_t i = 0; i < c.size(); ++i) {
    for (size_t j = 0; j < c.size(); ++j) {
      if (i == j || c[j].verdict != PairVerdict::kNotExamined ||
          c[i].verdict != PairVerdict::kNotExamined)
        continue;
      const double sj = c[i].axis.S(c[j].axis.ox, c[j].axis.oy);
      const double overlap = std::min(sj + c[j].length_px, c[i].length_px) - std::max(sj, 0.0);
      if (overlap < 0.5 * c[j].length_px || !Encloses(target, c[i], c[j])) continue;
      JudgeInsideWider(c[i], &c[j]);
      c[j].suppressed_by = static_cast<int>(i);
    }
  }
}

// Whether a pair's inside is one object: a pair made of the outer edges of two strands side by
// side holds the background between them. Samples the inside at the detection scale and counts
// how much of it sits at the background's level (within a quarter of the step), and whether that
// makes a run clear of both rims (a gap). A transparent strand on a backlight is a lens: its core
// shows the backlight too, but as one band centred between two dark rims of equal width, and it
// is one object.
constexpr double kGapWidths = 0.1;  // a gap between two objects: this share of the width
bool InsideIsOneObject(const Detection& d, const PairCandidate& c) {
  const cv::Mat& img = d.image;  // CV_8U or CV_32F
  const double f = d.factor, off = 0.5 * (d.factor - 1), gap = 2.0 * d.factor + 2.0;
  std::vector<double> outside, rim;
  std::vector<std::vector<double>> rows(5);
  for (int i = 1; i <= 5; ++i) {
    const double s = c.length_px * i / 6.0;
    const double ul = c.left_u0 + c.edge_slope * s, ur = c.right_u0 + c.edge_slope * s;
    auto at = [&](double u, std::vector<double>* out) {
      const double x = (c.axis.ImageX(s, u) - off) / f, y = (c.axis.ImageY(s, u) - off) / f;
      if (x < 0 || y < 0 || x > img.cols - 1.001 || y > img.rows - 1.001) return;
      const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
      const double fx = x - x0, fy = y - y0;
      const auto px = [&](int yy, int xx) -> double {
        return img.depth() == CV_8U ? img.ptr<uint8_t>(yy)[xx] : img.ptr<float>(yy)[xx];
      };
      out->push_back((px(y0, x0) * (1 - fx) + px(y0, x0 + 1) * fx) * (1 - fy) +
                     (px(y0 + 1, x0) * (1 - fx) + px(y0 + 1, x0 + 1) * fx) * fy);
    };
    at(ul - gap, &outside);
    at(ur + gap, &outside);
    at(ul + gap, &rim);
    at(ur - gap, &rim);
    for (double u = ul + gap; u <= ur - gap; u += f) at(u, &rows[i - 1]);
  }
  size_t inside = 0;
  for (const auto& r : rows) inside += r.size();
  if (inside < 10 || outside.size() < 2 || rim.size() < 2) return true;
  // The object's level just inside its edges; the background's just outside them.
  const double background = Median(outside), body = Median(rim);
  const double step = std::abs(body - background);
  if (step <= 0) return true;
  const auto at_background_level = [&](double v) { return std::abs(v - background) < 0.25 * step; };
  int at_background = 0, lens_rows = 0, gap_rows = 0, gaps = 0;
  double gap_level_sum = 0;  // each gap's mean level
  // A dark pair's gap is a plateau at least 4 samples wide: a narrow bright stripe, blurred, peaks
  // near the background's level over 2 or 3 (a 6 px stripe 60 levels above a dark 33 px strand
  // at a blur of 2.2 px).
  const double min_gap_samples = c.polarity == Polarity::kDarkOnBright ? 4.0 : 2.0;
  for (const auto& r : rows) {
    const int n_row = static_cast<int>(r.size());
    const double min_gap = std::max(min_gap_samples, kGapWidths * n_row);
    int first = -1, last = -1, here = 0, run = 0;
    double run_sum = 0;
    bool gap = false;
    for (int k = 0; k < n_row; ++k) {
      if (!at_background_level(r[k])) {
        // A run of background ended here: a gap when clear of the left rim too (one still open at
        // the row's end touches the right rim).
        if (run >= min_gap && k - run > 0) {
          gap = true;
          gap_level_sum += run_sum / run;
          ++gaps;
        }
        run = 0;
        run_sum = 0;
        continue;
      }
      ++run;
      run_sum += r[k];
      ++here;
      if (first < 0) first = k;
      last = k;
    }
    at_background += here;
    gap_rows += gap;
    // A lens's core: one band (nearly all of it at the backlight's level), centred (rims of
    // equal width within a tenth of the width), 10–70 % of the width.
    const double n = static_cast<double>(r.size());
    if (first >= 0 && here >= 0.8 * (last - first + 1) &&
        std::abs(first - (n - 1 - last)) <= 0.1 * n && (last - first + 1) >= 0.1 * n &&
        (last - first + 1) <= 0.7 * n)
      ++lens_rows;
  }
  // Only a dark silhouette on a backlight can be a lens (its core transmits the backlight).
  if (c.polarity == Polarity::kDarkOnBright && lens_rows >= 4) return true;
  // A lit object shows no background through itself: a run of background between its rims a
  // tenth of its width wide, in most rows, is a gap between two objects, though short of a fifth
  // of the inside. (A 10 px hair 30 px beside a 112 px strand made one 152 px object, its gap
  // 19.7 % of the inside, and was measured so.) A dark object's highlight may come near the
  // background's level (a fifth of the step above it, clipped), and a lens's core lies 0.08–0.11
  // of the step below it (what its surfaces reflect): there the gap must be the background's own
  // level, within a twentieth of the step over its rows. (A 10 px hair 36 px beside a dark 137 px
  // strand made one 184 px object, its gap within 0.14 of the step in each row and 0.01 over
  // them.)
  if (c.polarity == Polarity::kBrightOnDark && gap_rows >= 3) return false;
  if (c.polarity == Polarity::kDarkOnBright && gap_rows >= 3 &&  // (then gaps >= gap_rows)
      std::abs(gap_level_sum / gaps - background) <= 0.05 * step)
    return false;
  return at_background < 0.2 * inside;
}

// Edge contrast across the line u(s) at s, read kFollowOffsetPx either side.
bool ContrastAt(const GreyImage& img, const AxisFrame& a, double s, double u, int sign, double* c) {
  return ContrastAcross(img, a, s, u, sign, kFollowOffsetPx, c);
}

struct EdgeEnd {
  double s = 0;
  bool at_object = false;  // the edge stopped inside the image (tip, bed); else it left the image
};

// Walks along one edge line from s_from in direction dir (±1) until the edge's contrast stays
// below half its reference for three steps, or the line leaves the image. An edge that comes back
// (five strong steps within max_gap_px) was only hidden by a blob or a reflection, and the walk
// goes on.
EdgeEnd WalkEdge(const GreyImage& img, const AxisFrame& a, double u0, double slope, int sign,
                 double reference, double s_from, double dir, double max_gap_px) {
  double prev_c = reference, c = 0;
  int weak = 0, strong_again = 0;
  double first_weak = 0, before_weak_c = reference;
  bool in_gap = false;
  EdgeEnd candidate;
  for (int i = 0;; ++i) {
    const double s = s_from + dir * i;
    if (!ContrastAt(img, a, s, u0 + slope * s, sign, &c)) {
      return in_gap ? candidate : EdgeEnd{s - dir, false};
    }
    if (in_gap) {
      strong_again = std::abs(c) >= kEndFraction * reference ? strong_again + 1 : 0;
      if (strong_again >= 5) {
        in_gap = false;
        weak = 0;
      } else if (std::abs(s - candidate.s) > max_gap_px) {
        return candidate;
      }
      prev_c = c;
      continue;
    }
    // |c|: an object behind the strand may turn the edge's sign without ending it.
    if (std::abs(c) < kEndFraction * reference) {
      if (weak++ == 0) {
        first_weak = s;
        before_weak_c = prev_c;
      }
      if (weak >= 3) {
        // Interpolate the half-contrast crossing between the last strong and the first weak step.
        double c_weak = 0;
        ContrastAt(img, a, first_weak, u0 + slope * first_weak, sign, &c_weak);
        before_weak_c = std::abs(before_weak_c);
        c_weak = std::abs(c_weak);
        const double t = std::clamp(
            (before_weak_c - 0.5 * reference) / std::max(1e-9, before_weak_c - c_weak), 0.0, 1.0);
        candidate = {first_weak - dir + dir * t, true};
        in_gap = true;
        strong_again = 0;
      }
    } else {
      weak = 0;
    }
    prev_c = c;
  }
}

// Median contrast of an edge over the candidate's stretch.
double ReferenceContrast(const GreyImage& img, const AxisFrame& a, double u0, double slope,
                         int sign, double length) {
  std::vector<double> cs;
  for (double s = 0; s <= length; s += 2.0) {
    double c;
    if (ContrastAt(img, a, s, u0 + slope * s, sign, &c)) cs.push_back(c);
  }
  return Median(cs);
}

// For a pair of segments leaving the image at one border only, is it an object cut lengthwise by
// the ROI? (One long edge whose object side runs uniformly to the nearer side border.)
bool CutByBorder(const GreyImage& img, const std::vector<EdgeSegment>& edges, double min_length) {
  std::vector<double> levels;
  for (int y = 4; y < img.m.rows; y += 8)
    for (int x = 4; x < img.m.cols; x += 8) levels.push_back(img.At(x, y));
  const double background = Median(levels);
  for (const auto& e : edges) {
    // Cut lengthwise, the object runs along the side border; a steep edge (a nozzle flank) is not.
    if (e.length_px() < std::max(3.0 * min_length, 0.3 * img.m.rows)) continue;
    if (std::abs(e.bottom.x - e.top.x) > std::tan(15.0 * kDegToRad) * (e.bottom.y - e.top.y))
      continue;
    const cv::Point2d mid = 0.5 * (e.top + e.bottom);
    const int y = static_cast<int>(std::lround(mid.y));
    const bool to_left = mid.x < 0.5 * img.m.cols;
    const int x_from = static_cast<int>(std::lround(mid.x)) + (to_left ? -4 : 4);
    const int x_to = to_left ? 0 : img.m.cols - 1;
    if (x_from < 0 || x_from >= img.m.cols) continue;
    std::vector<double> v;
    for (int x = x_from; to_left ? x >= x_to : x <= x_to; x += to_left ? -1 : 1)
      v.push_back(img.At(x, y));
    if (v.size() < 2) continue;
    const double level = Median(v);
    const double far_side = img.At(std::clamp(x_from + (to_left ? 8 : -8), 0, img.m.cols - 1), y);
    const double step = std::abs(level - far_side);
    if (step < 1e-9 || std::abs(level - background) < 0.5 * step) continue;
    double max_dev = 0;
    for (double x : v) max_dev = std::max(max_dev, std::abs(x - level));
    if (max_dev < 0.3 * step) return true;
  }
  return false;
}

std::string Describe(const PairCandidate& c) {
  return fmt::format("width {:.1f} px, {:.0f} px long, {:.1f}° tilt, edge SNR {:.0f}, score {:.0f}",
                     c.width_px, c.length_px, std::atan2(c.axis.dx, c.axis.dy) * kRadToDeg, c.snr,
                     c.score);
}

}  // namespace

bool FollowPair(const GreyImage& img, const SceneOptions& o, const PairCandidate& c, int left_sign,
                int right_sign, StrandGeometry* g, PairVerdict* failure, std::string* why) {
  const AxisFrame& a = c.axis;
  const double ref_l = ReferenceContrast(img, a, c.left_u0, c.edge_slope, left_sign, c.length_px);
  const double ref_r = ReferenceContrast(img, a, c.right_u0, c.edge_slope, right_sign, c.length_px);
  g->left_contrast = ref_l;
  g->right_contrast = ref_r;
  if (!(ref_l > 0.5 * o.min_contrast && ref_r > 0.5 * o.min_contrast)) {
    *failure = PairVerdict::kWeakEdges;
    *why = fmt::format("edge contrast {:.0f}/{:.0f} too weak along the pair", ref_l, ref_r);
    return false;
  }
  // Walks start inside the stretch: a segment's detected end already lies in the fading zone.
  const double inset = std::min(0.25 * c.length_px, 12.0);
  const double top = inset, bottom = c.length_px - inset;
  const double gap = std::max(20.0, 0.5 * c.width_px);
  // A segment can run on past its object's end (joined in noise or a codec's blocks to an edge
  // beyond): a walk that ends where it starts began off the edge, and starts again from the
  // middle of the stretch, which is on it.
  const auto walk = [&](double u0, int sign, double ref, double from, double dir) {
    const EdgeEnd end = WalkEdge(img, a, u0, c.edge_slope, sign, ref, from, dir, gap);
    if (dir * (end.s - from) >= kOffEdgeStartPx) return end;
    return WalkEdge(img, a, u0, c.edge_slope, sign, ref, 0.5 * (top + bottom), dir, gap);
  };
  const EdgeEnd up_l = walk(c.left_u0, left_sign, ref_l, top, -1);
  const EdgeEnd up_r = walk(c.right_u0, right_sign, ref_r, top, -1);
  const EdgeEnd dn_l = walk(c.left_u0, left_sign, ref_l, bottom, +1);
  const EdgeEnd dn_r = walk(c.right_u0, right_sign, ref_r, bottom, +1);
  double s_origin;
  g->has_tip = up_l.at_object && up_r.at_object;
  if (o.target == MeasureTarget::kStrand) {
    if (!g->has_tip) {
      *failure = PairVerdict::kNoTip;
      *why = up_l.at_object || up_r.at_object
                 ? "only one edge ends upward: no nozzle tip across the strand"
                 : "the edges run to the frame or ROI top: no nozzle tip in view";
      return false;
    }
    // The walk followed straight lines; the outline followed as curves ends at the nozzle also
    // when the strand swells below it (tip.h). It starts a little below where the walks ended.
    const double s_from = std::max(up_l.s, up_r.s) + std::max(4.0, 0.1 * c.width_px);
    const TipTrace trace =
        TraceToNozzle(img, a, c.left_u0, c.right_u0, c.edge_slope, left_sign, right_sign, ref_l,
                      ref_r, std::min(s_from, bottom), o.min_contrast);
    // Straight edges that end where the outline curves on: the straight stretch is the bent
    // part of a strand below its tip, which lies somewhere up the curve (a tip put where the
    // following stopped measured a 44 px strand 12 px narrow, across its bend).
    if (trace.runs_on) {
      *failure = PairVerdict::kNoTip;
      *why = "the outline curves on above the straight edges: a strand bending, no tip in line";
      return false;
    }
    // A nozzle face ends both edges together (a strand hanging up to ~8° off the nozzle axis).
    const double mismatch = std::abs(up_l.s - up_r.s);
    if (!trace.found && mismatch > MaxTipMismatchPx(c.width_px)) {
      *failure = PairVerdict::kNoTip;
      *why = fmt::format("the edges end {:.0f} px apart: no common nozzle tip", mismatch);
      return false;
    }
    s_origin = 0.5 * (up_l.s + up_r.s);
    // The traced end where it lies above the walks' (which stop where a swell's edges curve), or
    // wherever the nozzle's face or the object's own end confirmed it.
    const bool tip_traced = trace.found && (trace.s_tip_px < s_origin || trace.tip_sigma_px >= 0);
    if (tip_traced) s_origin = trace.s_tip_px;
    g->tip_width_px = trace.found ? trace.widest_px : c.width_px;
    g->tip_face_sides = trace.found ? trace.face_sides : 0;
    g->tip_face_step = trace.found ? trace.face_step : 0;
    g->tip_sigma_px = tip_traced ? trace.tip_sigma_px : -1;
  } else {
    // Where both edges are still there; but when one edge's walk stops at an object while the
    // other runs on to the border, where the other ends: an object beside the filament (a gear's
    // rim) cuts a walk short although the edge goes on. Calipers where it does not are not
    // fitted, or rough, and the width comes from the straight part (straight_run.h).
    const EdgeEnd& lower = up_l.s >= up_r.s ? up_l : up_r;
    const EdgeEnd& higher = up_l.s >= up_r.s ? up_r : up_l;
    s_origin = lower.at_object && !higher.at_object ? higher.s : lower.s;
  }
  const double s_end = std::min(dn_l.s, dn_r.s);
  const bool end_object = dn_l.s <= dn_r.s ? dn_l.at_object : dn_r.at_object;
  g->axis = {a.ImageX(s_origin, 0), a.ImageY(s_origin, 0), a.dx, a.dy};
  g->left_u0 = c.left_u0 + c.edge_slope * s_origin;
  g->right_u0 = c.right_u0 + c.edge_slope * s_origin;
  g->edge_slope = c.edge_slope;
  g->width_px = c.width_px;
  g->left_sign = left_sign;
  g->right_sign = right_sign;
  g->polarity = c.polarity;
  g->s_end = s_end - s_origin;
  g->end_is_object = end_object;
  g->score = c.score;
  return true;
}

void PairCandidate::Judge(PairVerdict v, std::string words) {
  verdict = v;
  if (!words.empty()) {
    why = std::move(words);
    return;
  }
  switch (v) {
    case PairVerdict::kChosen:
      why = "chosen";
      return;
    case PairVerdict::kSpansObjects:
      why = "spans separate objects: the background shows between its edges";
      return;
    case PairVerdict::kNotAtFace:
      why = "its top is not at the nozzle's face";
      return;
    default:
      why.clear();
  }
}

bool RulesOut(PairVerdict v) {
  return v == PairVerdict::kSpansObjects || v == PairVerdict::kInsideWider ||
         v == PairVerdict::kNoTip || v == PairVerdict::kNotAtFace;
}

PairContest ContestPairs(const PairCandidate& b, const StrandGeometry& bg, const PairCandidate& c,
                         const StrandGeometry& cg, const SceneOptions& o) {
  const auto [bl, br] = Interval(b, b.axis);
  const auto [cl, cr] = Interval(c, b.axis);
  // Two strands in one view look alike; a gap between objects (a mixed pair) is another thing.
  if (!Disjoint(b, c) || c.polarity != b.polarity) return PairContest::kNotRivals;
  // Two strand-like objects: the one hanging from the nozzle's face (the nozzle on both its
  // sides) is the strand; a hair that ends at a flank, or in the open, is not. But the face read
  // on one side only does not tell a rival apart: a hair from the face's corner reads so, and so
  // does a strand whose face noise hid on one side (a 91 px strand lost so to an 8 px hair from
  // the corner, in one of four frames). The better-scoring pair read so is never outranked by
  // the face; a weaker one that could not rival it (CouldRival) is.
  const bool b_at_face = HangsFromFace(bg, o), c_at_face = HangsFromFace(cg, o);
  if (o.target == MeasureTarget::kStrand && b_at_face != c_at_face) {
    if (FaceReadInPart(bg, o) || (FaceReadInPart(cg, o) && CouldRival(b, c)))
      return PairContest::kFaceOnOneSide;
    return b_at_face ? PairContest::kFirstAtFace : PairContest::kSecondAtFace;
  }
  // Two parallel objects side by side, closer than either is wide, that the tip did not tell
  // apart: one strand whose stripe matches the background, or a strand and its neighbour.
  // Which is the strand, or whether their union is, the frame cannot say, whatever the scores.
  const double gap_px = std::max(cl - br, bl - cr);
  if (Parallel(b, c) && gap_px < std::max(br - bl, cr - cl)) return PairContest::kSideBySide;
  // Neither at the face: which object is the strand the frame does not say, if the other could
  // be one. (Scores once chose a 10 px hair over an 83 px strand whose nozzle was at the
  // background's level.)
  if (o.target == MeasureTarget::kStrand && !b_at_face && !c_at_face && CouldRival(b, c))
    return PairContest::kNeitherAtFace;
  return c.score >= o.ambiguity_ratio * b.score ? PairContest::kSimilarScore
                                                : PairContest::kOutscored;
}

std::string AmbiguityDetail(PairContest contest, const PairCandidate& b, const PairCandidate& c) {
  assert(Ambiguous(contest));
  return fmt::format(contest == PairContest::kSideBySide
                         ? "two strand-like objects side by side: {} and {}"
                     : contest == PairContest::kNeitherAtFace
                         ? "two strand-like objects, neither hanging clearly from the nozzle's "
                           "face: {} and {}"
                     : contest == PairContest::kFaceOnOneSide
                         ? "two strand-like objects, the nozzle's face read on one side only, or "
                           "faintly, beside one of them: {} and {}"
                         : "two strand-like pairs of similar score: {} and {}",
                     Describe(b), Describe(c));
}

namespace {

// A dark strand's stripe at the background's level leaves two dark bars with a bright gap, and
// the silhouette around all three is ruled out for the background showing inside it: the gap's
// neighbours are of the other polarity, so ContestPairs sees no rivals, and nothing else would
// stop the gap from being measured as the strand.
std::string FlankedDetail(const SceneResult& r, int index) {
  const PairCandidate& b = r.candidates[index];
  if (b.polarity == Polarity::kMixed) return "";
  const PairCandidate* flank[2] = {nullptr, nullptr};
  const auto consider = [&](int other) {
    if (other < 0 || other == index) return;
    const PairCandidate& c = r.candidates[other];
    if (c.polarity == b.polarity || c.polarity == Polarity::kMixed ||
        c.score < kFlankScoreRatio * b.score || !Parallel(b, c))
      return;
    if (c.right == b.left) flank[0] = &c;
    if (c.left == b.right) flank[1] = &c;
  };
  consider(r.chosen);
  for (const auto& runner_up : r.runners_up) consider(runner_up.first);
  if (!flank[0] || !flank[1]) return "";
  return fmt::format(
      "{} lies between two strand-like objects of the other polarity, {} and {}: a stripe in one "
      "strand or a gap between two",
      Describe(b), Describe(*flank[0]), Describe(*flank[1]));
}

// A dark strand's stripe at the background's level whose narrow side is no pair of its own: the
// strand's outline is ruled out for the background showing inside it, and its wide side stood
// alone (42.8 px of a 64.6 px strand, valid at sigma 0.02-0.06).
std::string SplitDetail(const SceneResult& r, int index) {
  const PairCandidate& b = r.candidates[index];
  const auto [bl, br] = Interval(b, b.axis);
  for (const PairCandidate& c : r.candidates) {
    if (c.verdict != PairVerdict::kSpansObjects || c.polarity != b.polarity ||
        c.score < kFlankScoreRatio * b.score || c.width_px <= b.width_px ||
        c.width_px - b.width_px > b.width_px || !Parallel(b, c))
      continue;
    // One edge in common (the same line, if not the same segment).
    const auto [cl, cr] = Interval(c, b.axis);
    if (std::abs(cl - bl) > kSameEdgePx && std::abs(cr - br) > kSameEdgePx) continue;
    return fmt::format(
        "{} shares an edge with a wider pair whose inside shows the background, {}: one strand "
        "split by a stripe at the background's level, or a strand beside another object",
        Describe(b), Describe(c));
  }
  return "";
}

// A pair inside a wider one (or inside one inside it), which then did not hold up for want of a
// tip in line only: a strand lit from one side whose faint shaded edge faded before the nozzle (the
// edges ending 23 px apart), and inside it its bright stripe's edge paired with its far edge, which
// hangs from the face (83.4 px at sigma 0.04, where the strand is 161.8). The wider pair may be
// the strand.
std::string InsideUnheldDetail(const SceneResult& r, int index) {
  const PairCandidate& b = r.candidates[index];
  const auto wider_may_be_strand = [&](const PairCandidate& c) {
    return fmt::format(
        "{} lies inside a wider strand-like pair whose tip was not found ({}: {}): the strand "
        "may be the wider one",
        Describe(b), Describe(c), c.why);
  };
  // Each wider than the last: the chain ends.
  for (int w = b.reinstated_from; w >= 0; w = r.candidates[w].reinstated_from) {
    const PairCandidate& c = r.candidates[w];
    if (c.verdict == PairVerdict::kNoTip) return wider_may_be_strand(c);
  }
  // Or inside one that had no tip in line, though too weak or too short to rule it out first
  // (MayBeInsideOf): a dark 45 px strand under noise of 10 grey levels, its faint edges ending
  // 41 px apart, and inside it a bright stripe hanging from the face (12.8 px at σ 0.5). The face
  // read beside a pair inside another is the other's inside, not the background.
  for (const PairCandidate& c : r.candidates)
    if (c.verdict == PairVerdict::kNoTip && MayBeInsideOf(b, c)) return wider_may_be_strand(c);
  return "";
}

// Whether an edge of `c` lies on one of `b`'s edge lines: across b's axis, each pair's edges
// read at its own mid-stretch.
bool OnAnEdgeLineOf(const PairCandidate& b, const PairCandidate& c) {
  const auto [bl, br] = Interval(b, b.axis);
  const auto [cl, cr] = Interval(c, b.axis);
  for (const double e : {cl, cr})
    if (std::abs(e - bl) <= kSameEdgePx || std::abs(e - br) <= kSameEdgePx) return true;
  return false;
}

// A wider strand-like pair that did not hold up as the strand is out as the strand, but not as
// the reason to doubt a narrower one that does not hang clearly from the nozzle's face: a
// strand lit from one side whose shaded edge is faint reads so. Beside a 14 px hair from the
// face's corner (measured alone, valid at sigma 0.04, where the strand is 111 px), such a strand's
// pair had no tip in line (its faint edge faded before the nozzle) or scored below the minimum
// (never followed), from frame to frame; where its shaded rim sank to the background's level (a
// strand level of 40-60 on a background of 21) it paired as mixed. Such a pair counts as a rival
// whose tip is unknown (one not at the face) and, if mixed, of the narrower one's polarity. A
// narrower one is a hair crossing the view, or hanging from above it. (On ten matrices of 1100
// strand frames each, 3 valid frames became ambiguous so, on pairs of background texture. Pairs
// whose edges faded along them, kWeakEdges, do not count: there they were faint texture 150-680
// px wide, and would have cost 4 more valid frames for no wrong one.)
std::string UnheldRivalDetail(const SceneResult& r, int index, const StrandGeometry& g,
                              const SceneOptions& o) {
  if (HangsFromFace(g, o)) return "";
  const PairCandidate& b = r.candidates[index];
  const StrandGeometry unknown_tip;
  for (const PairCandidate& c : r.candidates) {
    // Judged below the minimum: only while the search still followed pairs (ChoosePair). In a
    // cluttered view it stops before the faint ones, and they do not count: counting every pair
    // below the minimum made 4 more valid frames of ten matrices ambiguous, each on a mixed pair
    // of a long edge (a hair's, a strand's) and a short one of texture.
    // And a mixed pair that held up, but as no rival for its polarity (ContestPairs): the same
    // strand once its faint edge was followed to the nozzle (seed 709 at strand level 60: the
    // hair alone, 14.5 px at σ 0.04 where the strand is 111.4). Weighed like the others, its tip
    // unknown. Not one whose edge lies on the narrower one's own edge line, paired with texture
    // beyond it (a 180 px mixed pair beside an 87 px strand: three valid frames of eight sets
    // made ambiguous).
    const bool mixed_held = c.verdict == PairVerdict::kOutscored &&
                            c.polarity == Polarity::kMixed && !OnAnEdgeLineOf(b, c);
    if ((c.verdict != PairVerdict::kNoTip && c.verdict != PairVerdict::kScoreBelow &&
         !mixed_held) ||
        c.width_px <= b.width_px)
      continue;
    PairCandidate as_strand = c;
    if (as_strand.polarity == Polarity::kMixed) as_strand.polarity = b.polarity;
    if (!Ambiguous(ContestPairs(b, g, as_strand, unknown_tip, o))) continue;
    return fmt::format(
        "{} does not hang clearly from the nozzle's face, and a wider strand-like object {} ({}, "
        "{}, an edge {:.0f} px long{}{}): which is the strand the frame does not say",
        Describe(b), mixed_held ? "held up only as a mixed pair" : "did not hold up as a pair",
        Describe(c), PolarityName(c.polarity), c.long_edge_px, mixed_held ? "" : ": ",
        mixed_held ? "" : c.why);
  }
  return "";
}
// A wider pair of the chosen one's kind, clear of it, that could be the strand and was ruled out
// only for an edge fading along it while its other edge is an object's (kFadedRivalContrast times
// the least contrast): a strand lit from one side whose shaded rim sank to the background's level
// in places. Its tip is unknown, so a narrower pair hanging from the face does not outrank it: a
// hair from the face beside such a strand was measured alone (stringer 8104, 18.2 px at σ 0.10
// where the strand is 153.4; in the other frames the strand's pair held up, the hair's did not).
// Strand-like: its common stretch at least as long as it is wide (a nozzle's flank paired with
// texture, 38 px long and 62 px wide, is not).
std::string FadedRivalDetail(const SceneResult& r, int index, const SceneOptions& o) {
  const PairCandidate& b = r.candidates[index];
  for (const PairCandidate& c : r.candidates) {
    if (c.verdict != PairVerdict::kWeakEdges || c.polarity != b.polarity ||
        c.width_px <= b.width_px || c.length_px < c.width_px || !Disjoint(b, c) ||
        !CouldRival(b, c) ||
        std::max(c.left_contrast, c.right_contrast) < kFadedRivalContrast * o.min_contrast)
      continue;
    return fmt::format(
        "a wider strand-like object ({}) was ruled out only for an edge fading along it (edge "
        "contrast {:.0f}/{:.0f}): it may be the strand rather than {}",
        Describe(c), c.left_contrast, c.right_contrast, Describe(b));
  }
  return "";
}
}  // namespace

std::string ChoiceDoubtDetail(const SceneResult& r, int index, const StrandGeometry& g,
                              const SceneOptions& o) {
  std::string why = FlankedDetail(r, index);
  if (!why.empty() || o.target != MeasureTarget::kStrand) return why;
  why = SplitDetail(r, index);
  if (why.empty()) why = InsideUnheldDetail(r, index);
  if (why.empty()) why = UnheldRivalDetail(r, index, g, o);
  if (why.empty()) why = FadedRivalDetail(r, index, o);
  return why;
}

namespace {

// The frame is ambiguous: `rival` is as likely as the chosen pair, for the reason `detail`.
void AsLikely(PairCandidate* rival, std::string detail, SceneResult* r) {
  rival->Judge(PairVerdict::kAsLikely, "as likely as the chosen pair");
  r->status = FrameStatus::kAmbiguous;
  r->detail = std::move(detail);
}

// Follows the best candidates of one channel on its full-resolution image; the first that holds
// up is chosen (or the frame is ambiguous, or nothing holds up: r.status says which, and why).
void ChoosePair(const cv::Mat& channel, const SceneOptions& o, SceneResult* result) {
  SceneResult& r = *result;
  const GreyImage img{channel, channel.depth() == CV_16U};

  // Follow the best candidates on the full-resolution image; the first that holds up is chosen.
  std::string first_reason;
  PairVerdict first_failure = PairVerdict::kNotExamined;
  int examined = 0;
  for (int i = 0; i < static_cast<int>(r.candidates.size()) && examined < kMaxFollowed; ++i) {
    PairCandidate& c = r.candidates[i];
    if (c.verdict != PairVerdict::kNotExamined) continue;
    if (c.score < o.min_score) {
      c.Judge(PairVerdict::kScoreBelow, fmt::format("score below {:.0f}", o.min_score));
      continue;
    }
    ++examined;
    StrandGeometry g;
    if (!FollowPair(img, o, c, r.edges[c.left].sign, r.edges[c.right].sign, &g, &c.verdict,
                    &c.why)) {
      if (c.verdict == PairVerdict::kWeakEdges) {
        c.left_contrast = g.left_contrast;
        c.right_contrast = g.right_contrast;
      }
      if (first_reason.empty()) {
        first_reason = c.why;
        first_failure = c.verdict;
      }
      // The pairs this one outranked as their wider silhouette compete again, best first.
      bool reinstated = false;
      for (auto& inner : r.candidates) {
        if (inner.suppressed_by != i) continue;
        inner.suppressed_by = -1;
        inner.reinstated_from = i;
        inner.Judge(PairVerdict::kNotExamined);
        reinstated = true;
      }
      if (reinstated) i = -1;
      continue;
    }
    if (r.chosen < 0) {
      r.chosen = i;
      r.geometry = g;
      c.Judge(PairVerdict::kChosen);
      continue;
    }
    // A second pair that holds up: ambiguous when it is a separate object of similar score.
    const PairCandidate& b = r.candidates[r.chosen];
    // Or the wider silhouette of the other kind the chosen one lies inside (MayBeInsideOf). Its
    // detected stretch was too short to rule the chosen one out (SuppressNested): a dark strand
    // whose far edge showed along its lower half only, and inside it a bright stripe hanging
    // from the face (14.0 px at σ 0.19 where the strand is 179.9). A comparable one hanging from
    // the same tip is the object. One too weak to be it outright, or whose tip lies elsewhere,
    // could still be the strand (a faint 45 px strand under noise of 10 grey levels around its
    // bright stripe, 12.8 px at σ 0.5): the face read beside a pair inside another is the
    // other's inside, not the background, and does not decide.
    const auto inside_the_wider = [&] {
      AsLikely(&c,
               fmt::format("{} lies inside a wider strand-like pair that also holds up, {}: the "
                           "strand may be the wider one",
                           Describe(b), Describe(c)),
               &r);
    };
    // One of its own kind, too, where it hangs clearly from the face as a strand does and lies
    // clear of both its edges: a lit strand whose faint shaded rims scored 13 % of its bright
    // stripe's, which was measured (11.5 px at σ 0.18 where the strand is 143.4). One that does
    // not hang so is as often the strand and a hair beside it, paired across both; one on its
    // edge line, the strand's edge paired with a lamp's spot beyond its other (8 right valid
    // frames of 26 sets).
    if (o.target == MeasureTarget::kStrand && SameKind(b, c) && InsideARival(b, c) &&
        !OnAnEdgeLineOf(b, c) && HangsFromFace(g, o)) {
      inside_the_wider();
      return;
    }
    if (o.target == MeasureTarget::kStrand && MayBeInsideOf(b, c)) {
      const bool same_tip =
          std::abs(r.geometry.axis.S(g.axis.ox, g.axis.oy)) <= MaxTipMismatchPx(c.width_px);
      if (!same_tip || !Encloses(o.target, c, b)) {
        inside_the_wider();
        return;
      }
      JudgeInsideWider(c, &r.candidates[r.chosen]);
      r.chosen = i;
      r.geometry = g;
      c.Judge(PairVerdict::kChosen);
      // The pairs the inner one outscored, weighed again against the strand.
      for (const auto& [k, kg] : r.runners_up) {
        const PairContest again = ContestPairs(c, g, r.candidates[k], kg, o);
        if (!Ambiguous(again)) continue;
        AsLikely(&r.candidates[k], AmbiguityDetail(again, c, r.candidates[k]), &r);
        return;
      }
      continue;
    }
    const PairContest contest = ContestPairs(b, r.geometry, c, g, o);
    if (contest == PairContest::kSecondAtFace) {
      r.candidates[r.chosen].Judge(PairVerdict::kNotAtFace);
      r.runners_up.clear();
      r.chosen = i;
      r.geometry = g;
      c.Judge(PairVerdict::kChosen);
      continue;
    }
    if (contest == PairContest::kFirstAtFace) {
      c.Judge(PairVerdict::kNotAtFace);
      continue;
    }
    if (Ambiguous(contest)) {
      AsLikely(&c, AmbiguityDetail(contest, b, c), &r);
      return;
    }
    c.Judge(PairVerdict::kOutscored,
            fmt::format("scores {:.0f} % of the chosen pair", 100 * c.score / b.score));
    r.runners_up.emplace_back(i, g);
  }
  if (r.chosen >= 0) {
    if (std::string why = ChoiceDoubtDetail(r, r.chosen, r.geometry, o); !why.empty()) {
      r.status = FrameStatus::kAmbiguous;
      r.detail = std::move(why);
      return;
    }
    r.status = FrameStatus::kValid;
    r.detail.clear();
    return;
  }
  const PairCandidate* top = nullptr;
  for (const auto& c : r.candidates)
    if (!top || c.score > top->score) top = &c;
  if (top && top->score >= o.min_score && o.target == MeasureTarget::kStrand &&
      first_failure == PairVerdict::kNoTip) {
    r.status = FrameStatus::kNoTip;
    r.detail = fmt::format("best pair ({}): {}", Describe(*top), first_reason);
    return;
  }
  if (CutByBorder(img, r.edges, o.min_length_px)) {
    r.status = FrameStatus::kTouchesBorder;
    r.detail = "a long object runs into the frame or ROI side: its other edge is outside";
    return;
  }
  r.status = FrameStatus::kNoStrand;
  if (top) {
    r.detail =
        fmt::format("best pair ({}) lost: {}", Describe(*top),
                    top->verdict == PairVerdict::kNotExamined ? "no better candidate" : top->why);
  } else {
    r.detail = fmt::format("no pair of parallel edges at least {:.0f} px long ({} straight edges)",
                           o.min_length_px, r.edges.size());
  }
}

}  // namespace

SceneResult FindScene(const std::vector<cv::Mat>& channels, const SceneOptions& o) {
  // Each channel is searched on its own. They are tried best pair first: the first channel in
  // which a pair holds up is used (a clear strand's internal lines may outscore its silhouette in
  // luma and leave two look-alike pairs, while the silhouette stands alone in blue).
  std::vector<SceneResult> found;
  std::vector<double> top_score;
  for (int ch = 0; ch < static_cast<int>(channels.size()); ++ch) {
    const Detection d = DetectEdgePoints(channels[ch], o);
    const std::vector<Piece> pieces = StraightPieces(d, o.max_tilt_deg);
    SceneResult r;
    r.channel = r.measured_channel = ch;
    r.gradient_noise = d.noise / d.factor;
    for (const Piece& p : pieces) {
      EdgeSegment s = ToSegment(p, d);
      if (s.length_px() >= o.min_length_px) r.edges.push_back(s);
    }
    r.candidates = PairSegments(d, r.edges, r.gradient_noise, channels[ch].cols, o);
    for (auto& c : r.candidates) {
      if (!InsideIsOneObject(d, c)) {
        c.Judge(PairVerdict::kSpansObjects);
      }
    }
    SuppressNested(o.target, &r.candidates);
    double top = 0;
    for (const auto& c : r.candidates)
      if (c.verdict == PairVerdict::kNotExamined) top = std::max(top, c.score);
    found.push_back(std::move(r));
    top_score.push_back(top);
  }
  std::vector<int> order(found.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return top_score[a] > top_score[b]; });
  for (int ch : order) {
    if (top_score[ch] < o.min_score && ch != order.front()) break;
    ChoosePair(channels[ch], o, &found[ch]);
    if (found[ch].status == FrameStatus::kValid) return std::move(found[ch]);
  }
  // Nothing held up anywhere: the best channel's account of why.
  return std::move(found[order.front()]);
}

}  // namespace clogscope::vision
