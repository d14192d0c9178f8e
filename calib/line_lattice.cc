#include "calib/line_lattice.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <map>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "common/robust.h"

namespace clogscope::calib {
namespace {

// Marks closer than this are pieces of one line (or a line and a mark on it), not a spacing.
constexpr double kMinGapPx = 2.0;
// A run of fewer than kMinRunSlots lines more than kMaxHoleSlots empty slots away from the
// longest run is not part of the lattice.
constexpr int kMaxHoleSlots = 3, kMinRunSlots = 3;
// Marks that agree to within kSamePieceSigmas of their σ (kSamePiecePx to kSamePieceMaxPx) are
// pieces of one line (dust over a line splits it); σ is floored at kMinPieceSigmaPx.
constexpr double kSamePieceSigmas = 5, kSamePiecePx = 0.1, kSamePieceMaxPx = 0.3;
constexpr double kMinPieceSigmaPx = 0.002;
// A line farther than kChanceSpacings from where its lattice puts it may be there by chance; two
// lattices whose spacings differ by less than kSameSpacing are one, bent by lens distortion.
constexpr double kChanceSpacings = 0.05, kSameSpacing = 0.03;
// Lattices tried from the periodogram: its highest peaks; at most kMaxPeriodogramTerms terms
// (marks × frequencies) for it.
constexpr size_t kPeaks = 6;
constexpr double kMaxPeriodogramTerms = 1e8;

// The marks in one slot and which of them is the line: the longest (dust, or a numeral's stroke
// above the line, is shorter); of equal ones, the nearest to the slot.
struct Slot {
  int line = -1;
  std::vector<int> marks;
  bool operator==(const Slot& o) const { return line == o.line && marks == o.marks; }
};

// A lattice x = a + b·k and the marks on it.
struct Lattice {
  double a = 0, b = 0;
  std::map<int, Slot> slots;   // slot index → its line
  std::vector<bool> off_mark;  // per mark
  int occupied() const { return static_cast<int>(slots.size()); }
  double fill() const {
    if (slots.empty()) return 0;
    return occupied() / double(slots.rbegin()->first - slots.begin()->first + 1);
  }
  // How well the lattice explains the marks: the lines on it, discounted twice by the empty slots
  // among them. A lattice at half the spacing always holds every line and the marks between, but
  // leaves most of its slots empty; at twice the spacing it holds half the lines.
  double score() const { return b > 0 ? occupied() * fill() * fill() : 0; }
};

// Every mark to its nearest slot of lat (a, b); those farther than `tol` spacings, and those of a
// run of fewer than kMinRunSlots slots more than kMaxHoleSlots empty slots away from the longest
// run (a numeral or another scale's line beyond the end of this one, on a slot by chance), off the
// lattice. Sets lat's slots and off_mark.
void AssignSlots(const std::vector<LineMark>& m, double tol, Lattice* lat) {
  lat->slots.clear();
  lat->off_mark.assign(m.size(), false);
  std::map<int, std::vector<int>> in_slot;
  for (size_t i = 0; i < m.size(); ++i) {
    const double t = (m[i].position_px - lat->a) / lat->b;
    const int k = static_cast<int>(std::lround(t));
    if (std::abs(t - k) > tol) {
      lat->off_mark[i] = true;
    } else {
      in_slot[k].push_back(static_cast<int>(i));
    }
  }
  // Runs of slots with at most kMaxHoleSlots empty ones between neighbours; the longest stays.
  struct Run {
    int first, last, occupied;
  };
  std::vector<Run> runs;
  for (const auto& [k, marks] : in_slot) {
    if (runs.empty() || k - runs.back().last > kMaxHoleSlots + 1) runs.push_back({k, k, 0});
    runs.back().last = k;
    ++runs.back().occupied;
  }
  const auto main_run = std::max_element(
      runs.begin(), runs.end(), [](const Run& p, const Run& q) { return p.occupied < q.occupied; });
  auto run = runs.begin();
  for (const auto& entry : in_slot) {  // no structured binding: k is captured below
    const auto k = entry.first;
    const auto& marks = entry.second;
    while (k > run->last) ++run;
    if (run != main_run && run->occupied < kMinRunSlots) {
      for (int i : marks) lat->off_mark[i] = true;
      continue;
    }
    Slot slot{marks[0], marks};
    auto residual = [&](int i) { return std::abs((m[i].position_px - lat->a) / lat->b - k); };
    for (int i : marks) {
      const double li = m[i].length_px, lb = m[slot.line].length_px;
      if (li > lb || (li == lb && residual(i) < residual(slot.line))) slot.line = i;
    }
    lat->slots[k] = slot;
  }
}

// lat's a and b from a line fit index → position over its slots' lines, Huber-reweighted at 2.5
// robust σ (floored: centres agree to a few hundredths of a px).
void HuberFit(const std::vector<LineMark>& m, Lattice* lat) {
  std::vector<double> w(lat->slots.size(), 1.0);
  for (int round = 0; round < 4; ++round) {
    double sw = 0, sk = 0, skk = 0, sx = 0, skx = 0;
    size_t j = 0;
    for (const auto& [k, slot] : lat->slots) {
      const double x = m[slot.line].position_px;
      sw += w[j];
      sk += w[j] * k;
      skk += w[j] * k * k;
      sx += w[j] * x;
      skx += w[j] * k * x;
      ++j;
    }
    const double det = sw * skk - sk * sk;
    if (!(det > 0)) break;
    lat->b = (sw * skx - sk * sx) / det;
    lat->a = (sx - lat->b * sk) / sw;
    std::vector<double> abs_res;
    for (const auto& [k, slot] : lat->slots)
      abs_res.push_back(std::abs(m[slot.line].position_px - lat->a - lat->b * k));
    const double c = 2.5 * std::max(kMadToSigma * UpperMedian(abs_res), 0.01);
    for (size_t q = 0; q < abs_res.size(); ++q)
      w[q] = std::min(1.0, c / std::max(abs_res[q], 1e-12));
  }
}

// Slots by the nearest (AssignSlots) and a line fit over the marks on them (HuberFit), repeated
// until the marks on the lattice no longer change. The fit, not the start, sets the spacing: a
// start from the periodogram is good to a small fraction of a spacing across the marks.
Lattice FitFrom(const std::vector<LineMark>& m, double b0, double a0, double tol) {
  Lattice lat;
  lat.a = a0;
  lat.b = b0;
  std::map<int, Slot> previous;
  for (int iter = 0; iter < 20; ++iter) {
    if (!(lat.b >= kMinGapPx)) {  // no lattice: marks closer are pieces of one line
      lat.slots.clear();
      lat.off_mark.assign(m.size(), true);
      break;
    }
    AssignSlots(m, tol, &lat);
    if (lat.slots.size() < 2 || lat.slots == previous) break;
    previous = lat.slots;
    HuberFit(m, &lat);
    if (!(lat.b > 0)) break;
  }
  return lat;
}

// The best lattice (by score) started from the periodogram's highest peaks over a range of
// spacings, and the best of the others that is not the same lattice.
struct Search {
  bool ok = false;
  Lattice best;
  std::optional<Lattice> second;  // none: every other start reached the best
};

// The same lattice reached twice: the same spacing, slots in the same places.
bool SameLattice(const Lattice& p, const Lattice& q, double tol) {
  const double shift = (q.a - p.a) / p.b;
  return std::abs(q.b / p.b - 1) < 0.01 && std::abs(shift - std::round(shift)) < tol;
}

Search FindLattice(const std::vector<LineMark>& m, double tol, double min_ratio, double max_ratio,
                   double spacing_px = 0) {
  Search out;
  std::vector<double> x;
  for (const auto& mk : m) x.push_back(mk.position_px);
  std::sort(x.begin(), x.end());
  std::vector<double> gaps;
  for (size_t i = 1; i < x.size(); ++i)
    if (x[i] - x[i - 1] >= kMinGapPx) gaps.push_back(x[i] - x[i - 1]);
  if (gaps.empty()) return out;
  // Spacings between min_ratio and max_ratio times `spacing_px`, or the median gap.
  const double gap = spacing_px > 0 ? spacing_px : UpperMedian(gaps);
  const double mean = std::accumulate(x.begin(), x.end(), 0.0) / x.size();
  const double span = std::max(x.back() - x.front(), gap);
  // Frequency steps of an eighth of the peak's width (1/span): no peak is missed. Coarser steps
  // bound the work for absurdly many marks (noise): the fit from a peak refines a rough start.
  const double f_lo = 1 / (max_ratio * gap), f_hi = 1 / (min_ratio * gap);
  const double df = std::max(1 / (8 * span), (f_hi - f_lo) * x.size() / kMaxPeriodogramTerms);
  const int n = static_cast<int>((f_hi - f_lo) / df) + 1;
  auto sum = [&](double f) {
    std::complex<double> s = 0;
    for (double xi : x) s += std::polar(1.0, 2 * M_PI * f * (xi - mean));
    return s;
  };
  // Each mark's term at f_lo + j·df by rotating its term at f_lo: a complex product per
  // frequency, not a sine and a cosine (thousands of marks over a wide image stay fast).
  std::vector<std::complex<double>> sums(n);
  for (double xi : x) {
    std::complex<double> term = std::polar(1.0, 2 * M_PI * f_lo * (xi - mean));
    const std::complex<double> step = std::polar(1.0, 2 * M_PI * df * (xi - mean));
    for (int j = 0; j < n; ++j) {
      sums[j] += term;
      term *= step;
    }
  }
  std::vector<double> power(n);
  for (int j = 0; j < n; ++j) power[j] = std::abs(sums[j]);
  // Peaks inside the range only: a maximum at its end belongs to a spacing outside it.
  std::vector<int> peaks;
  for (int j = 1; j + 1 < n; ++j) {
    if (power[j] > power[j - 1] && power[j] >= power[j + 1]) peaks.push_back(j);
  }
  std::sort(peaks.begin(), peaks.end(), [&](int a, int b) { return power[a] > power[b]; });
  if (peaks.size() > kPeaks) peaks.resize(kPeaks);
  std::vector<Lattice> found;
  for (int j : peaks) {
    double f = f_lo + j * df;
    const double den = power[j - 1] - 2 * power[j] + power[j + 1];
    if (den < 0) f += 0.5 * df * (power[j - 1] - power[j + 1]) / den;
    const double a0 = mean + std::arg(sum(f)) / (2 * M_PI * f);
    Lattice lat = FitFrom(m, 1 / f, a0, tol);
    // A fit that wandered far out of the range is not this peak's lattice.
    if (lat.b > 0.9 * min_ratio * gap && lat.b < 1.1 * max_ratio * gap)
      found.push_back(std::move(lat));
  }
  std::sort(found.begin(), found.end(),
            [](const Lattice& p, const Lattice& q) { return p.score() > q.score(); });
  if (found.empty()) return out;
  out.ok = true;
  out.best = found[0];
  for (size_t i = 1; i < found.size(); ++i) {
    if (SameLattice(out.best, found[i], tol)) continue;
    out.second = found[i];
    break;
  }
  return out;
}

// A candidate line: pieces of one line (a line split by dust, a mark right on it) combined, its
// position weighted by the pieces' σ, its length theirs together; and the marks it came from.
struct Candidate {
  LineMark line;
  std::vector<int> marks;
};

// The marks by position, those that agree to within kSamePieceSigmas of their σ (kSamePiecePx to
// kSamePieceMaxPx) combined.
std::vector<Candidate> CombinePieces(const std::vector<LineMark>& marks) {
  std::vector<int> order(marks.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int i, int j) { return marks[i].position_px < marks[j].position_px; });
  std::vector<Candidate> out;
  std::vector<double> weights;  // Σ 1/σ² of each candidate's marks
  for (int i : order) {
    const LineMark& mk = marks[i];
    const double sigma = std::max(mk.sigma_px, kMinPieceSigmaPx);
    if (!out.empty()) {
      LineMark& c = out.back().line;
      const double same = std::clamp(kSamePieceSigmas * std::hypot(sigma, c.sigma_px), kSamePiecePx,
                                     kSamePieceMaxPx);
      if (mk.position_px - c.position_px <= same) {
        const double w = 1 / (sigma * sigma);
        c.position_px =
            (c.position_px * weights.back() + mk.position_px * w) / (weights.back() + w);
        weights.back() += w;
        c.sigma_px = std::sqrt(1 / weights.back());
        c.length_px += mk.length_px;
        out.back().marks.push_back(i);
        continue;
      }
    }
    out.push_back({{mk.position_px, sigma, mk.length_px}, {i}});
    weights.push_back(1 / (sigma * sigma));
  }
  return out;
}

}  // namespace

bool LatticeOptions::Validate(std::string* why) const {
  if (!(tolerance_spacings > 0 && tolerance_spacings < 0.5)) {
    *why = "lattice tolerance must be in (0, 0.5) spacings";
    return false;
  }
  if (min_lines < 3) {
    *why = "a lattice needs at least 3 lines";
    return false;
  }
  if (!(min_length_fraction >= 0 && min_length_fraction < 1)) {
    *why = "lattice minimum length fraction must be in [0, 1)";
    return false;
  }
  if (!(ambiguity_ratio > 0 && ambiguity_ratio <= 1) ||
      !(second_lattice_fill > 0 && second_lattice_fill <= 1) ||
      !(second_lattice_lines > 0 && second_lattice_lines <= 1)) {
    *why = "lattice ambiguity ratio and second-lattice fill and lines must be in (0, 1]";
    return false;
  }
  return true;
}

const char* LatticeStatusName(LatticeStatus s) {
  switch (s) {
    case LatticeStatus::kOk:
      return "ok";
    case LatticeStatus::kTooFewMarks:
      return "too few marks";
    case LatticeStatus::kTooFewOnLattice:
      return "too few lines on a lattice";
    case LatticeStatus::kAmbiguous:
      return "two lattices fit";
    case LatticeStatus::kTwoSpacings:
      return "two spacings";
  }
  return "?";
}

std::string LatticeIndexing::LeftOutSummary() const {
  const std::pair<int, const char*> why[] = {{off_lattice, "off the lattice"},
                                             {shared_slot, "in a slot that holds a longer line"},
                                             {too_short, "too short for a line"}};
  std::string text = fmt::format("{} of {} marks left out", left_out(), marks);
  const int reasons = (off_lattice > 0) + (shared_slot > 0) + (too_short > 0);
  const char* sep = ": ";
  for (const auto& [count, reason] : why) {
    if (count == 0) continue;
    text += reasons == 1 ? fmt::format("{}{}", sep, reason)
                         : fmt::format("{}{} {}", sep, count, reason);
    sep = ", ";
  }
  return text;
}

LatticeIndexing IndexLinesOnLattice(const std::vector<LineMark>& marks, int image,
                                    const LatticeOptions& opt) {
  std::string why;
  if (!opt.Validate(&why)) throw std::invalid_argument(why);
  if (image < 0) throw std::invalid_argument("negative image number");
  for (const auto& mk : marks) {
    if (!std::isfinite(mk.position_px) || !std::isfinite(mk.sigma_px) ||
        !std::isfinite(mk.length_px))
      throw std::invalid_argument("line mark with a non-finite position, σ or length");
  }
  LatticeIndexing out;
  out.marks = static_cast<int>(marks.size());
  if (out.marks < opt.min_lines) {
    out.reason = fmt::format("{} mark(s) found; a lattice needs at least {} lines", out.marks,
                             opt.min_lines);
    return out;
  }
  const double tol = opt.tolerance_spacings;
  const std::vector<Candidate> candidates = CombinePieces(marks);
  // Candidates far shorter than the lines are no lines: a speck of dust, a numeral's stroke (one
  // on the slot of a line hidden or cut by the border would pass the lattice). Most candidates are
  // lines and most lines are the short ticks: the upper quartile of the lengths is a short tick's.
  std::vector<double> lengths;
  for (const auto& c : candidates)
    if (c.line.length_px > 0) lengths.push_back(c.line.length_px);
  std::sort(lengths.begin(), lengths.end());
  const double line_length_px = lengths.empty() ? 0 : lengths[lengths.size() * 3 / 4];
  const double min_length_px = opt.min_length_fraction * line_length_px;
  std::vector<LineMark> m;
  std::vector<const std::vector<int>*> m_marks;  // the marks of each m
  for (const Candidate& c : candidates) {
    if (c.line.length_px < min_length_px) {
      out.too_short += static_cast<int>(c.marks.size());
      continue;
    }
    m.push_back(c.line);
    m_marks.push_back(&c.marks);
  }
  if (static_cast<int>(m.size()) < opt.min_lines) {
    out.reason =
        fmt::format("only {} of {} marks are long enough for lines; a lattice needs at least {}",
                    m.size(), out.marks, opt.min_lines);
    return out;
  }
  // Spacings of 0.8 to 3 times the median gap between neighbouring marks: marks between the lines
  // only make the gaps smaller.
  const Search s = FindLattice(m, tol, 0.8, 3.0);
  if (!s.ok) {
    out.reason = "the marks lie on top of each other: no spacing between them";
    return out;
  }
  const Lattice& lat = s.best;
  out.pitch_px = lat.b;
  // Left out, counted in marks: candidates off the lattice, and those beside the line in a slot.
  for (size_t j = 0; j < m.size(); ++j)
    if (lat.off_mark[j]) out.off_lattice += static_cast<int>(m_marks[j]->size());
  for (const auto& [k, slot] : lat.slots) {
    for (int j : slot.marks)
      if (j != slot.line) out.shared_slot += static_cast<int>(m_marks[j]->size());
  }
  if (lat.occupied() < opt.min_lines) {
    out.status = LatticeStatus::kTooFewOnLattice;
    out.reason = fmt::format(
        "only {} of {} marks sit on one lattice (spacing {:.2f} px); need at least {}: the lines "
        "are not evenly spaced",
        lat.occupied(), out.marks, lat.b, opt.min_lines);
    return out;
  }
  // Another spacing that explains the marks about as well; or half, a third, twice or three times
  // this one (with marks between every other slot as many as the lines, which are the lines
  // cannot be told).
  auto ambiguous = [&](const Lattice& o) {
    return o.occupied() >= opt.min_lines && o.score() >= opt.ambiguity_ratio * lat.score();
  };
  auto refuse_ambiguous = [&](const Lattice& o) {
    out.status = LatticeStatus::kAmbiguous;
    out.reason = fmt::format(
        "two lattices fit about equally well: {} marks at a spacing of {:.2f} px, {} at {:.2f} px",
        lat.occupied(), lat.b, o.occupied(), o.b);
    return out;
  };
  if (s.second && ambiguous(*s.second)) return refuse_ambiguous(*s.second);
  for (double ratio : {0.5, 1.0 / 3, 2.0, 3.0}) {
    const int starts = ratio > 1 ? static_cast<int>(ratio) : 1;
    for (int j = 0; j < starts; ++j) {
      const Lattice o = FitFrom(m, ratio * lat.b, lat.a + j * lat.b, tol);
      if (std::abs(o.b / (ratio * lat.b) - 1) < 0.05 && ambiguous(o)) return refuse_ambiguous(o);
    }
  }
  // The marks off the lattice must not be lines of another spacing. Lines of another spacing
  // also fall on this lattice by chance, within the tolerance but far from where the lattice puts
  // them (the lattice's own lines sit within hundredths of a pixel): they are tried with the rest.
  std::vector<LineMark> rest;
  for (size_t i = 0; i < m.size(); ++i)
    if (lat.off_mark[i]) rest.push_back(m[i]);
  for (const auto& [k, slot] : lat.slots) {
    const LineMark& line = m[slot.line];
    if (std::abs(line.position_px - lat.a - lat.b * k) > kChanceSpacings * lat.b)
      rest.push_back(line);
  }
  if (static_cast<int>(rest.size()) >= opt.min_lines) {
    // Spacings near this one's but not this one (lens distortion changes it by far less than
    // kSameSpacing): marks off the lattice also fall on wide lattices by chance (a numeral's
    // strokes repeat with the numerals).
    const Search r = FindLattice(rest, tol, 0.4, 2.5, lat.b);
    const int needed = std::max<int>(
        opt.min_lines, static_cast<int>(std::ceil(opt.second_lattice_lines * lat.occupied())));
    if (r.ok && r.best.occupied() >= needed && r.best.fill() >= opt.second_lattice_fill &&
        std::abs(r.best.b / lat.b - 1) > kSameSpacing) {
      out.status = LatticeStatus::kTwoSpacings;
      out.reason = fmt::format(
          "{} lines at a spacing of {:.2f} px and {} at {:.2f} px: the lines are not evenly "
          "spaced, so no pitch fits them",
          lat.occupied(), lat.b, r.best.occupied(), r.best.b);
      return out;
    }
  }
  const int k0 = lat.slots.begin()->first;
  out.slot0_px = lat.a + lat.b * k0;
  for (const auto& [k, slot] : lat.slots) {
    out.lines.push_back({image, k - k0, m[slot.line].position_px, m[slot.line].sigma_px});
    out.line_marks.push_back(*m_marks[slot.line]);
  }
  out.status = LatticeStatus::kOk;
  return out;
}

}  // namespace clogscope::calib
