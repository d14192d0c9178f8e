// Candidate pairs from a channel's edge segments (pair_candidates.h).
#include "vision/scene/pair_candidates.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/angle.h"
#include "common/robust.h"
#include "vision/scene/pair_relations.h"

namespace clogscope::vision {
namespace {

constexpr int kMaxCandidates = 40;     // pairs kept after scoring
constexpr double kMixedPenalty = 0.5;  // a pair brighter on one side only is less likely
// How far a long pair's edges may open over its length: 0.6°, and 1.7° narrowing downward below a
// nozzle (die swell 4640, a strand 1.29 times as wide at the nozzle relaxing over 0.35 widths: its
// lines 0.9° apart; 4727, 1.42 over 0.3 widths, 1.45°).
constexpr double kMaxOpening = 0.01, kMaxSwellOpening = 0.03;
// The most of such a closing its lower half may hold: two straight lines closing in hold half of
// it there (the gap between a hair and a strand, stringer 4136: 0.51), swells 0.01-0.26 (4738).
constexpr double kMaxLowerClosingShare = 1.0 / 3;
// What a pair width_px wide may open by over len_px at that rate per px: 2 px, or 3 % of its width.
double MaxOpeningPx(double width_px, double len_px, double per_px) {
  return std::max({2.0, 0.03 * width_px, per_px * len_px});
}

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

// How far from a segment's line an edge point may lie and count as its (detection-scale px).
constexpr double kLineTolPx = 2.0;
// A segment's line at the detection scale, x = a + b·y.
struct SmallLine {
  double a, b;
  int sign;
};
SmallLine ToSmall(const Detection& d, const EdgeSegment& e) {
  const double f = d.factor, off = 0.5 * (d.factor - 1);
  const double y0 = (e.top.y - off) / f, y1 = (e.bottom.y - off) / f;
  const double x0 = (e.top.x - off) / f, x1 = (e.bottom.x - off) / f;
  const double slope = y1 > y0 ? (x1 - x0) / (y1 - y0) : 0.0;
  return {x0 - slope * y0, slope, e.sign};
}

// The edge point of the line's sign nearest its x on row r, within kLineTolPx.
const EdgePoint* PointNear(const Detection& d, const SmallLine& l, int r) {
  constexpr double tol_px = kLineTolPx;
  const double x = l.a + l.b * d.row_y[r];
  const auto& pts = d.rows[r];
  auto it = std::lower_bound(pts.begin(), pts.end(), x - tol_px,
                             [](const EdgePoint& p, double v) { return p.x < v; });
  const EdgePoint* hit = nullptr;
  double best = tol_px;
  for (; it != pts.end() && it->x <= x + tol_px; ++it) {
    if (it->sign == l.sign && std::abs(it->x - x) <= best) {
      best = std::abs(it->x - x);
      hit = &*it;
    }
  }
  return hit;
}

// Whether a pair that closes downward by closing_px holds its width over the lower half of the
// rows both edges share: a swell closes at its top and runs parallel below, where two objects
// that close in (a hair slanting onto a strand's edge) keep closing, half of it in the lower half.
// From the edge points near each line.
bool ParallelBelowASwell(const Detection& d, const EdgeSegment& left, const EdgeSegment& right,
                         double width_px, double closing_px) {
  const double f = d.factor, off = 0.5 * (d.factor - 1);
  const double y_top = std::max(left.top.y, right.top.y);
  const double y_bottom = std::min(left.bottom.y, right.bottom.y);
  const double y_mid = 0.5 * (y_top + y_bottom);
  const SmallLine l = ToSmall(d, left), r = ToSmall(d, right);
  // The widths along the rows as a line in y (Piece's fit, the width in place of x): its slope is
  // the pair's opening per px down.
  Piece widths;
  for (size_t k = 0; k < d.row_y.size(); ++k) {
    const double y = d.row_y[k] * f + off;
    if (y < y_mid || y > y_bottom) continue;
    const EdgePoint* pl = PointNear(d, l, static_cast<int>(k));
    const EdgePoint* pr = PointNear(d, r, static_cast<int>(k));
    if (pl && pr) widths.pts.push_back({pr->x - pl->x, d.row_y[k], 0.0f, 0});
  }
  if (static_cast<int>(widths.pts.size()) < kMinPiecePoints) return false;
  widths.Fit();
  const double half_px = y_bottom - y_mid, opening_px = std::abs(widths.b) * half_px;
  return opening_px <= MaxOpeningPx(width_px, half_px, kMaxOpening) &&
         opening_px <= kMaxLowerClosingShare * closing_px;
}

// Two edges as a strand silhouette: geometry and score, or false when they are not parallel, too
// short together, too narrow or too wide. `left`/`right` in the result are 0 and 1 (a and b).
// With the detection, a strand's pair may close downward as a swell does (ParallelBelowASwell).
bool MakeCandidate(const EdgeSegment& a, const EdgeSegment& b, double noise_full, int roi_width,
                   double min_overlap, const SceneOptions& o, const Detection* d,
                   PairCandidate* out) {
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
  const EdgeSegment& L = li == 0 ? a : b;
  const EdgeSegment& R = li == 0 ? b : a;
  // Not parallel enough; a long pair may open by 0.6° (a curved end tilts a segment's fitted
  // line). A strand's pair may close downward by up to kMaxSwellOpening where it runs parallel
  // below: a swell relaxing below the nozzle curves each edge's top, within a piece's
  // straightness, and its line leans in.
  const double closing = w0 - w1;
  if (std::abs(closing) > MaxOpeningPx(width, len, kMaxOpening) &&
      !(o.target == MeasureTarget::kStrand && d && closing > 0 &&
        closing <= MaxOpeningPx(width, len, kMaxSwellOpening) &&
        ParallelBelowASwell(*d, L, R, width, closing)))
    return false;
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
  SmallLine lines[2] = {ToSmall(d, a), ToSmall(d, b)};
  constexpr int kMaxGapRows = 6;
  const int n = static_cast<int>(d.rows.size());
  std::vector<const EdgePoint*> hit[2];
  for (int pass = 0; pass < 2; ++pass) {
    for (int side = 0; side < 2; ++side) {
      hit[side].assign(n, nullptr);
      for (int r = 0; r < n; ++r) hit[side][r] = PointNear(d, lines[side], r);
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

}  // namespace

std::vector<PairCandidate> PairSegments(const Detection& d, const std::vector<EdgeSegment>& edges,
                                        double noise_full, int roi_width, const SceneOptions& o) {
  std::vector<PairCandidate> seeds;
  for (size_t i = 0; i < edges.size(); ++i) {
    for (size_t j = i + 1; j < edges.size(); ++j) {
      PairCandidate c;
      if (!MakeCandidate(edges[i], edges[j], noise_full, roi_width, 0.5 * o.min_length_px, o, &d,
                         &c))
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
    // nozzle): the seed's own segments stand. (Only a seed may close as a swell does: extended,
    // the lines of a strand and of a hair beside its top took in the hair's edge, closed by it
    // at the top and ran parallel below, and the band was put on the two together, stringer
    // 4685, 12.6 px wide at σ 0.16.)
    if (!MakeCandidate(el, er, noise_full, roi_width, o.min_length_px, o, nullptr, &c) &&
        !MakeCandidate(edges[seeds[k].left], edges[seeds[k].right], noise_full, roi_width,
                       o.min_length_px, o, &d, &c))
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

void JudgeInsideWider(const PairCandidate& outer, PairCandidate* inner) {
  inner->Judge(PairVerdict::kInsideWider,
               fmt::format("inside a wider pair ({:.1f} px)", outer.width_px));
}

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

}  // namespace clogscope::vision
