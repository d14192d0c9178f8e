#include "vision/scene/pair_relations.h"

#include <fmt/format.h>

#include <cmath>

#include "common/angle.h"

namespace clogscope::vision {
namespace {

constexpr double kParallelSine = 0.035;  // two axes within 2° of each other are parallel
// A rival that scores less than this share of the best is no strand, even where the tip does not
// decide: the short pairs of clutter discs and blobs that held up scored 7-24 % of the strand's
// in the robustness scenes, while a long hair may score as well as the strand.
constexpr double kRivalScoreRatio = 0.5;

}  // namespace

bool Parallel(const PairCandidate& a, const PairCandidate& b) {
  return std::abs(a.axis.dx * b.axis.dy - a.axis.dy * b.axis.dx) < kParallelSine;
}

// A score ranks by length and contrast, and a strand whose shaded side is faint scores little for
// it: a 111 px strand (its pair 109 px) scored 18-34 % of a 14 px hair from the nozzle's corner,
// which was measured alone. So a pair wider than `b` rivals it whatever its score where one of its
// edges is longer than the pair is wide (a disc's or blob's edges are all short): never the
// thinner object by default. The longer edge, not the common stretch: where a faint edge broke
// up, the stretch shrank to 80 px of that strand while its longer edge ran 250 px.
bool CouldRival(const PairCandidate& b, const PairCandidate& c) {
  return c.score >= kRivalScoreRatio * b.score ||
         (c.width_px > b.width_px && c.long_edge_px >= c.width_px);
}

std::pair<double, double> Interval(const PairCandidate& c, const AxisFrame& frame) {
  const double sm = 0.5 * c.length_px;
  const double xl = c.axis.ImageX(sm, c.left_u0 + c.edge_slope * sm);
  const double yl = c.axis.ImageY(sm, c.left_u0 + c.edge_slope * sm);
  const double xr = c.axis.ImageX(sm, c.right_u0 + c.edge_slope * sm);
  const double yr = c.axis.ImageY(sm, c.right_u0 + c.edge_slope * sm);
  return {frame.U(xl, yl), frame.U(xr, yr)};
}

bool Disjoint(const PairCandidate& b, const PairCandidate& c) {
  if (c.left == b.left || c.left == b.right || c.right == b.left || c.right == b.right)
    return false;
  const auto [bl, br] = Interval(b, b.axis);
  const auto [cl, cr] = Interval(c, b.axis);
  return cr < bl || cl > br;
}

bool OppositeKinds(const PairCandidate& a, const PairCandidate& b) {
  return (a.polarity == Polarity::kBrightOnDark && b.polarity == Polarity::kDarkOnBright) ||
         (a.polarity == Polarity::kDarkOnBright && b.polarity == Polarity::kBrightOnDark);
}

bool SameKind(const PairCandidate& a, const PairCandidate& b) {
  return a.polarity == b.polarity && a.polarity != Polarity::kMixed;
}

bool Contains(const PairCandidate& outer, const PairCandidate& inner) {
  if (outer.width_px <= inner.width_px + 3.0) return false;
  const auto [l, r] = Interval(inner, outer.axis);
  const auto [ol, orr] = Interval(outer, outer.axis);
  return l >= ol - kSameEdgePx && r <= orr + kSameEdgePx;
}

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

bool InsideARival(const PairCandidate& b, const PairCandidate& c) {
  return Contains(c, b) && CouldRival(b, c) && Parallel(b, c);
}

// Only of the other kind: of its own kind, such a pair is as often the strand and a hair beside
// it, paired across both (over eight sets, 41 valid frames, each right, were doubted so).
bool MayBeInsideOf(const PairCandidate& b, const PairCandidate& c) {
  return OppositeKinds(b, c) && InsideARival(b, c);
}

bool OnAnEdgeLineOf(const PairCandidate& b, const PairCandidate& c) {
  const auto [bl, br] = Interval(b, b.axis);
  const auto [cl, cr] = Interval(c, b.axis);
  for (const double e : {cl, cr})
    if (std::abs(e - bl) <= kSameEdgePx || std::abs(e - br) <= kSameEdgePx) return true;
  return false;
}

std::string Describe(const PairCandidate& c) {
  return fmt::format("width {:.1f} px, {:.0f} px long, {:.1f}° tilt, edge SNR {:.0f}, score {:.0f}",
                     c.width_px, c.length_px, std::atan2(c.axis.dx, c.axis.dy) * kRadToDeg, c.snr,
                     c.score);
}

}  // namespace clogscope::vision
