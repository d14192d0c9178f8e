#include "vision/scene/self_check.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/robust.h"
#include "vision/edges/caliper_samples.h"

namespace clogscope::vision {
namespace {

constexpr int kRows = 8;
constexpr double kMinReachPx = 20.0;    // how far out the outside is looked at, at least
constexpr double kNearPx = 3.0;         // the background's level: this far beyond the blur
constexpr double kMaxObjectLike = 0.4;  // of one side's outside samples
// A level nearer the object's than the background's: beyond this share of the contrast.
constexpr double kObjectLikeShare = 0.5;
// Levels are read this far from an edge, beyond its blur: kInsetBlurs blurs and kInsetPx px.
constexpr double kInsetBlurs = 3.0, kInsetPx = 2.0;
constexpr double kMaxLevelMismatch = 1.0;  // of the object's contrast
// A thin object's level is read along its middle where that is this many blurs from each edge.
constexpr double kThinLevelBlurs = 2.0;
// Another edge just outside a silhouette: looked for this far from it (blurs, and px).
constexpr double kOutsideEdgeBlurs = 2.5, kOutsideEdgePx = 4.0;
// A gap between two objects inside a silhouette: a run of px within kGapLevelBand of the object's
// contrast from the background, at least kMinGapPx and kMinGapBlurs wide, its mean within
// kGapLevelShare of it. (A narrow stripe at the background's level, blurred, peaks there: a dark
// 41 px strand's stripe 8 px inside its edge read so over 3-4 px at a blur of 1.6 px.)
constexpr double kGapLevelBand = 0.25, kGapLevelShare = 0.1, kMinGapPx = 3.0, kMinGapBlurs = 3.0;
// With the object's body on both sides such a run may be a stripe at the background's level (the
// matrix draws stripes up to 0.3 of the width) or a lens's core (centred, its rims alike: 28 and
// 28 px of a 113 px lens whose core covers 51 %) — but not one over half the width with the body
// on one side under half as wide as on the other: a strand and a hair 218 px beside it, paired
// across both (382 px where the strand is 153: bodies of 154 and 10 px).
constexpr double kMaxStripeShare = 0.5, kMinBodyBalance = 0.5;
// A run at the background's level from one end of the read, over at least this share of the
// width, with the object's body beyond it: the silhouette's edge on that side has no object
// behind it past its blur (a hair thinner than the inset, paired with the strand's far edge).
// Less may be a stripe at the background's level by a rim thinner than the inset (stripe 3836:
// 0.19-0.21 of a 37.7 px strand, its width right).
constexpr double kEdgeRunShare = 0.25;
// A wider object around the silhouette: each side's outside read on to kWiderReachWidths times its
// width (a stripe down to a twelfth of its strand's width; the matrix draws them from a twentieth
// to 0.3), and kMinReachPx at least, for a step of at least the least contrast to a farther level
// over two plateaus of the larger of kPlateauBlurs blurs and kMinPlateauPx px, sharp as an edge
// (from a quarter to three quarters of it within kSharpBlurs blurs plus kSharpPx px), the two
// sides' farther levels within kFarLevelMismatch of the smaller step. The farther level holds
// beyond, within kHeldShare of the step, over kMinHeldFraction of the wider object's width.
constexpr double kWiderReachWidths = 12.0, kPlateauBlurs = 3.0, kMinPlateauPx = 6.0;
constexpr double kSharpBlurs = 3.0, kSharpPx = 4.0, kFarLevelMismatch = 0.5;
constexpr double kHeldShare = 0.5, kMinHeldFraction = 0.8;
// Its edge parallel to the object's: in the band's two halves within the larger of kParallelBlurs
// blurs and kParallelPx px of one distance.
constexpr double kParallelBlurs = 1.0, kParallelPx = 2.0;
// One edge's residuals this many times the other's, and by this many grey levels.
constexpr double kMaxResidualRatio = 2.0, kMinResidualExcess = 1.5;

// Along u from the edge at u0 + slope·s, `dir` ±1, from `from` over `length` px: per px of distance
// the median over kRows rows of the band (noise and a blob over a few rows do not count).
std::vector<double> Strip(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                          double slope, double from, double dir, double length) {
  std::vector<double> out, column;
  out.reserve(static_cast<size_t>(std::max(0.0, length)) + 1);
  column.reserve(kRows);
  static_assert(kRows == 8);  // MedianOf8 below
  const BandRows<kRows> rows(f, s0, s1);
  double row_u[kRows];  // each row's edge
  for (int r = 0; r < kRows; ++r) row_u[r] = u0 + slope * rows.s[r];
  for (double d = 0; d <= length; d += 1.0) {
    column.clear();
    for (int r = 0; r < kRows; ++r) {
      const double u = row_u[r] + dir * (from + d);
      const double x = rows.X(r, u), y = rows.Y(r, u);
      if (img.InsideForBilinear(x, y)) column.push_back(img.Bilinear(x, y));
    }
    // Each row's ray leaves the (convex) frame once: none inside, none further out either.
    if (column.empty() && d > 0) break;
    if (column.size() == kRows)
      out.push_back(MedianOf8(column.data()));
    else if (column.size() >= kRows / 2)
      out.push_back(MedianInPlace(&column));
  }
  return out;
}

double InsetPx(double blur_px) { return kInsetBlurs * blur_px + kInsetPx; }

// The background's level just outside the edge at u0 + slope·s (`dir` outward), from inset_px
// over kNearPx; false where the frame's border leaves too little of it.
bool NearBackground(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                    double slope, double inset_px, double dir, double* level) {
  const std::vector<double> near = Strip(img, f, s0, s1, u0, slope, inset_px, dir, kNearPx);
  if (near.size() < 2) return false;
  *level = Median(near);
  return true;
}

// A step in `strip` (read outward from the near background, at level `near`) to a farther level
// that holds over a plateau (kPlateauBlurs) past another as far from `near` as the least contrast,
// sharp as an edge (kSharpBlurs): the farther level and where its step lies, or false. A slow fall
// first (a background's gradient, a lit strand's shading toward its rim) leaves nothing judged.
struct StepBeyond {
  double level = 0, distance_px = 0;
};
int PlateauPx(double blur_px) {
  return static_cast<int>(std::ceil(std::max(kMinPlateauPx, kPlateauBlurs * blur_px)));
}
bool FindStepBeyond(const std::vector<double>& strip, double near, double blur_px, double min_step,
                    StepBeyond* out) {
  const int plateau = PlateauPx(blur_px);
  const int n = static_cast<int>(strip.size());
  std::vector<double> window;
  const auto median_of = [&](int from) {
    window.assign(strip.begin() + from, strip.begin() + from + plateau);
    return MedianInPlace(&window);
  };
  for (int i = 0; i + 2 * plateau <= n; ++i) {
    const double first = median_of(i) - near;
    if (std::abs(first) < min_step) continue;
    // Past the step, a plateau on the same side and as far: not a thin object (a hair).
    const double far = median_of(i + plateau);
    const double step = far - near;
    if (std::abs(step) < min_step || step * first <= 0) continue;
    // Where the outside crosses three quarters of the step (3 px running means), near the
    // plateaus, and the last place before it below a quarter.
    const auto share = [&](int j) {
      const double mean =
          (strip[std::max(j - 1, 0)] + strip[j] + strip[std::min(j + 1, n - 1)]) / 3;
      return (mean - near) / step;
    };
    int j75 = std::max(0, i - plateau);
    while (j75 < i + 2 * plateau - 1 && share(j75) < 0.75) ++j75;
    if (share(j75) < 0.75) continue;
    int j25 = j75;
    while (j25 > 0 && share(j25) >= 0.25) --j25;
    if (share(j25) >= 0.25 || j75 - j25 > kSharpBlurs * blur_px + kSharpPx) return false;
    out->level = far;
    out->distance_px = 0.5 * (j25 + j75);
    return true;
  }
  return false;
}

}  // namespace

SelfCheck CheckOutsideIsBackground(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                   double left_u0, double right_u0, double slope, double blur_px) {
  SelfCheck out;
  const double width = right_u0 - left_u0;
  const double gap = InsetPx(blur_px);
  // The object's level just inside both edges; an object too thin for that, along its middle
  // where its edges' blur has reached its level (a stripe at a dark strand's rim, taken for the
  // object, went unchecked: AdversarialTest.AStripeAtADarkStrandsRimIsNotTheObject).
  std::vector<double> inside;
  const bool thin = width < 2 * gap + 2;
  if (!thin) {
    inside = Strip(img, f, s0, s1, left_u0, slope, gap, +1, 2.0);
    const std::vector<double> inside_r = Strip(img, f, s0, s1, right_u0, slope, gap, -1, 2.0);
    inside.insert(inside.end(), inside_r.begin(), inside_r.end());
  } else if (width >= 2 * kThinLevelBlurs * blur_px) {
    const double middle = 0.5 * width;
    inside = Strip(img, f, s0, s1, left_u0, slope, middle - 0.5, +1, 1.0);
  }
  if (inside.size() < 2) return out;  // too thin to read an inside level
  const double object = Median(inside);
  // As far out as the edge fits' windows and what pulls them reach.
  const double reach = kMinReachPx + 3.0 * blur_px;
  double background[2];
  for (int side = 0; side < 2; ++side) {
    const double u0 = side == 0 ? left_u0 : right_u0, dir = side == 0 ? -1.0 : 1.0;
    const std::vector<double> far = Strip(img, f, s0, s1, u0, slope, gap, dir, reach);
    // The frame's border: not judged here.
    if (!NearBackground(img, f, s0, s1, u0, slope, gap, dir, &background[side]) || far.size() < 10)
      return out;
    const double step = std::abs(object - background[side]);
    if (step <= 0) continue;
    long object_like = 0;
    // Not background: nearer the object's level than the background's (another object, a lamp's
    // reflection behind the edge).
    for (double v : far) object_like += std::abs(v - background[side]) > kObjectLikeShare * step;
    const double fraction = static_cast<double>(object_like) / far.size();
    if (fraction > kMaxObjectLike) {
      out.passed = false;
      out.why = fmt::format(
          "the silhouette's outside is not background: {:.0f} % of the {:.0f} px beyond its {} "
          "edge is nearer the object's level (another object, a reflection)",
          100 * fraction, reach, side == 0 ? "left" : "right");
      return out;
    }
  }
  // A thin object's against the nearer of the two: across the 20-30 px between its outsides a
  // background seldom changes by more than that, and outsides so far apart are one background
  // and another object (a dark strand beside the bright stripe at its rim). Across a wide strand
  // a background's gradient may (22 grey levels across 180 px, the strand 21 below the darker
  // side), and there the mean counts.
  const double contrast =
      thin ? std::min(std::abs(object - background[0]), std::abs(object - background[1]))
           : std::abs(object - 0.5 * (background[0] + background[1]));
  if (std::abs(background[0] - background[1]) > kMaxLevelMismatch * contrast) {
    out.passed = false;
    out.why = fmt::format(
        "the background outside its edges differs ({:.0f} and {:.0f} grey levels, the object "
        "{:.0f}): not one object's silhouette",
        background[0], background[1], object);
  }
  return out;
}

SelfCheck CheckInsideIsOneObject(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                 double left_u0, double right_u0, double slope, double blur_px,
                                 double min_step) {
  SelfCheck out;
  const double width_px = right_u0 - left_u0;
  const double inset_px = InsetPx(blur_px);
  const double gap_run_px = std::max(kMinGapPx, kMinGapBlurs * blur_px);
  // No room for a gap between two objects (and a blur that is no number: nothing to read).
  if (!(width_px >= 2 * inset_px + gap_run_px + 2)) return out;
  const std::vector<double> inside =
      Strip(img, f, s0, s1, left_u0, slope, inset_px, +1, width_px - 2 * inset_px);
  const int n = static_cast<int>(inside.size());
  double bg_l, bg_r;
  // Strip drops a distance the frame's border cuts: then its px no longer map to distances.
  if (!NearBackground(img, f, s0, s1, left_u0, slope, inset_px, -1, &bg_l) ||
      !NearBackground(img, f, s0, s1, right_u0, slope, inset_px, +1, &bg_r) ||
      n != static_cast<int>(std::floor(width_px - 2 * inset_px)) + 1)
    return out;
  // The background's levels where they were read, the middle of each near strip, and a straight
  // line between them (a gradient); inside[k] lies inset_px + k px inside the left edge.
  const double at_l = -(inset_px + 0.5 * kNearPx), at_r = width_px + inset_px + 0.5 * kNearPx;
  const auto background = [&](int k) {
    return bg_l + (bg_r - bg_l) * (inset_px + k - at_l) / (at_r - at_l);
  };
  const auto deviation = [&](int k) { return inside[k] - background(k); };
  // The object's contrast: the larger of the two ends' (one end may be a hair's, blurred thin).
  const double step = std::max(std::abs(deviation(0)), std::abs(deviation(n - 1)));
  if (!(step >= min_step)) return out;
  const auto object_like = [&](int k) { return std::abs(deviation(k)) > kObjectLikeShare * step; };
  const auto background_like = [&](int k) { return std::abs(deviation(k)) < kGapLevelBand * step; };
  // Whether the object's body shows anywhere over [from, to).
  const auto body_in = [&](int from, int to) {
    for (int j = from; j < to; ++j)
      if (object_like(j)) return true;
    return false;
  };
  // The deviation from the background farthest from it over [from, to).
  const auto extreme = [&](int from, int to) {
    double e = 0;
    for (int j = from; j < to; ++j)
      if (std::abs(deviation(j)) > std::abs(e)) e = deviation(j);
    return e;
  };
  // A run at the background's level, clear of both ends of the read, with the object's body on
  // one side and, on the other, only a thin part of the same kind that nowhere reaches
  // kObjectLikeShare of the contrast: a hair beside the strand, too thin and blurred to read as an
  // object of its own. (With the body on both sides the run may as well be a stripe at the
  // background's level inside one object: the search judges that, on the whole pair. A lit
  // strand's dark rim strip, shaded to the background's level, lies on the other side of it
  // from its lit body. Over half the width and off the middle, it is the background between two
  // objects.)
  for (int k = 1; k < n; ++k) {
    if (!background_like(k) || background_like(k - 1)) continue;
    int end = k;
    double sum = 0;
    while (end < n && background_like(end)) sum += deviation(end), ++end;
    const int run = end - k;
    if (end < n && run >= gap_run_px && std::abs(sum / run) <= kGapLevelShare * step) {
      const bool body_before = body_in(0, k), body_after = body_in(end, n);
      const double body_l_px = inset_px + k, body_r_px = width_px - inset_px - end;
      if (body_before && body_after && extreme(0, k) * extreme(end, n) > 0 &&
          run >= kMaxStripeShare * width_px &&
          std::min(body_l_px, body_r_px) < kMinBodyBalance * std::max(body_l_px, body_r_px)) {
        out.passed = false;
        out.why = fmt::format(
            "the background shows inside it: {} px at the background's level {:.0f} px inside "
            "its left edge, over {:.0f} % of its width, between {:.0f} and {:.0f} px of the "
            "object (two objects and the background between them, measured as one)",
            run, inset_px + k, 100.0 * run / width_px, body_l_px, body_r_px);
        return out;
      }
      if (body_before != body_after && extreme(0, k) * extreme(end, n) > 0) {
        out.passed = false;
        out.why = fmt::format(
            "the background shows inside it: {} px at the background's level {:.0f} px inside "
            "its left edge, a thin object between it and the {} edge (a hair beside the strand, "
            "the two measured as one)",
            run, inset_px + k, body_before ? "right" : "left");
        return out;
      }
    }
    k = end;  // inside[end] is no background: no run starts there
  }
  // The runs above lie clear of the read's ends. One from an end means the object on that side
  // is thinner than the inset: a hair whose blurred tail does not reach past it, paired with the
  // strand's far edge across the background between them (stringer 3690: 322.8 px at σ 0.14
  // where the strand is 178.5; 121 px at the background's level inside the hair's edge, then the
  // strand). On nine sets (10 800 frames) no other frame had such a run over 0.15 of the width
  // but stripe 3836's (kEdgeRunShare).
  for (const bool from_left : {true, false}) {
    const auto at = [&](int j) { return from_left ? j : n - 1 - j; };
    int run = 0;
    double sum = 0;
    for (; run < n && background_like(at(run)); ++run) sum += deviation(at(run));
    if (run >= n || run < gap_run_px || run < kEdgeRunShare * width_px ||
        std::abs(sum / run) > kGapLevelShare * step)
      continue;
    if (!(from_left ? body_in(run, n) : body_in(0, n - run))) continue;
    out.passed = false;
    out.why = fmt::format(
        "the background shows just inside its {} edge: {} px at the background's level, {:.0f} % "
        "of its width, then the object (a thin object beside it, the two measured as one)",
        from_left ? "left" : "right", run, 100.0 * run / width_px);
    return out;
  }
  return out;
}

SelfCheck CheckNoEdgeJustOutside(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                 double left_u0, double right_u0, double slope, double blur_px,
                                 double min_step) {
  SelfCheck out;
  const double mid = 0.5 * (s0 + s1);
  const double depth_px = kOutsideEdgeBlurs * blur_px + kOutsideEdgePx;
  for (int side = 0; side < 2; ++side) {
    const double u = (side == 0 ? left_u0 : right_u0) + slope * mid;
    // Outward: away from the object, which lies toward +u of the left edge.
    const double d = InnerEdgeDistance(img, f, s0, s1, u, side == 0 ? -1 : 1, depth_px, min_step);
    if (std::isfinite(d)) {
      out.passed = false;
      out.why = fmt::format(
          "another edge {:.1f} px outside its {} edge: the strand's own outline beyond a stripe "
          "measured as the object, or another object against it (a shadow, a hair)",
          d, side == 0 ? "left" : "right");
      return out;
    }
  }
  return out;
}

SelfCheck CheckNotOnAWiderObject(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                                 double left_u0, double right_u0, double slope, double blur_px,
                                 double min_step, bool object_dark) {
  SelfCheck out;
  const double width_px = right_u0 - left_u0;
  const double inset_px = InsetPx(blur_px);
  if (!(width_px > 0)) return out;
  const double reach_px = std::max(kMinReachPx, kWiderReachWidths * width_px);
  double near[2];
  StepBeyond beyond[2];
  bool stepped[2];
  for (int side = 0; side < 2; ++side) {
    const double u0 = side == 0 ? left_u0 : right_u0, dir = side == 0 ? -1.0 : 1.0;
    if (!NearBackground(img, f, s0, s1, u0, slope, inset_px, dir, &near[side])) return out;
    const std::vector<double> strip = Strip(img, f, s0, s1, u0, slope, inset_px, dir, reach_px);
    stepped[side] = FindStepBeyond(strip, near[side], blur_px, min_step, &beyond[side]);
  }
  if (!stepped[0] && !stepped[1]) return out;
  // The step each side is judged by: its own, or on a side without one the other side's.
  double step[2];
  if (stepped[0] && stepped[1]) {
    step[0] = beyond[0].level - near[0];
    step[1] = beyond[1].level - near[1];
    // The near levels on one side of the farther ones, which are one background.
    if (step[0] * step[1] <= 0 ||
        std::abs(beyond[0].level - beyond[1].level) >
            kFarLevelMismatch * std::min(std::abs(step[0]), std::abs(step[1])))
      return out;
  } else {
    // A step on one side only, the other side's near level already the farther one: the wider
    // object ends just beyond the silhouette there (a stripe by a dark strand's rim, the rim a
    // blur or two wide: 17.6 px measured where the strand is 108.5).
    // Only a body of the other kind than the object (darker than the background under a bright
    // silhouette): one of its kind, fainter, is as likely a hair or a shadow beside it (a dark
    // hair converging on a dark strand read as a grey body 22 px wide, stringer 8905).
    const int a = stepped[0] ? 0 : 1, b = 1 - a;
    step[a] = step[b] = beyond[a].level - near[a];
    if (object_dark || step[a] < 0) return out;
    // A stripe is the lesser part of its strand (the matrix draws them up to 0.3 of the width):
    // the body beyond it reaches at least as far again as the object is wide. A dark blob by a
    // bright strand ends sooner (spot 9705: 33 px beside a 56 px strand, measured right).
    if (inset_px + beyond[a].distance_px < width_px) return out;
    if (std::abs(near[b] - beyond[a].level) > kFarLevelMismatch * std::abs(step[a])) return out;
    beyond[b] = {near[b], 0.0};
  }
  // A dark object on a bright field ringed by dark is a silhouette on a backlight's disc (or in a
  // microscope's vignette): not judged. A bright one on a lit body (a highlight on a lit strand),
  // or on a dark body against a bright background (on a dark strand), is a stripe; as is a dark
  // one on a body darker than the background.
  if (object_dark && step[0] < 0) return out;
  // The farther level is the background: it holds beyond the step for as wide as the wider object
  // would be (or to the frame's border). Neighbours of one level on both sides (a bright strand
  // between two others, on a dark background) end sooner.
  const int plateau = PlateauPx(blur_px);
  const double wider_px = width_px + 2 * inset_px + beyond[0].distance_px + beyond[1].distance_px;
  for (int side = 0; side < 2; ++side) {
    const double u0 = side == 0 ? left_u0 : right_u0, dir = side == 0 ? -1.0 : 1.0;
    const std::vector<double> far = Strip(
        img, f, s0, s1, u0, slope, inset_px + beyond[side].distance_px + plateau, dir, wider_px);
    if (static_cast<int>(far.size()) < 2 * plateau) return out;
    long held = 0;
    for (double v : far)
      held += std::abs(v - beyond[side].level) <= kHeldShare * std::abs(step[side]);
    if (held < kMinHeldFraction * far.size()) return out;
  }
  // An edge parallel to the object's, on at least one side: in each half of the band, at the same
  // distance. (A background's texture brighter around a strand steps where its blobs end, 18 px
  // out over part of the band and elsewhere over the rest. A lit strand's shaded edge may fade in
  // one half.)
  const double mid = 0.5 * (s0 + s1);
  bool parallel = false;
  for (int side = 0; side < 2 && !parallel; ++side) {
    const double u0 = side == 0 ? left_u0 : right_u0, dir = side == 0 ? -1.0 : 1.0;
    StepBeyond half[2];
    bool found = true;
    for (int h = 0; h < 2 && found; ++h) {
      const std::vector<double> part =
          Strip(img, f, h == 0 ? s0 : mid, h == 0 ? mid : s1, u0, slope, inset_px, dir, reach_px);
      found = FindStepBeyond(part, near[side], blur_px, min_step, &half[h]) &&
              (half[h].level - near[side]) * (beyond[side].level - near[side]) > 0;
    }
    parallel = found && std::abs(half[0].distance_px - half[1].distance_px) <=
                            std::max(kParallelPx, kParallelBlurs * blur_px);
  }
  if (!parallel) return out;
  out.passed = false;
  if (stepped[0] && stepped[1]) {
    out.why = fmt::format(
        "it lies on a wider object: outside both its edges the level ({:.0f} and {:.0f} grey "
        "levels) steps on to the background's ({:.0f} and {:.0f}) {:.0f} and {:.0f} px out (a "
        "stripe inside the strand measured as the object)",
        near[0], near[1], beyond[0].level, beyond[1].level, inset_px + beyond[0].distance_px,
        inset_px + beyond[1].distance_px);
  } else {
    const int a = stepped[0] ? 0 : 1;
    out.why = fmt::format(
        "it lies at the side of a wider object: outside its {} edge the level ({:.0f} grey "
        "levels) steps on to the background's ({:.0f}) {:.0f} px out, which lies just outside "
        "its {} edge ({:.0f}) (a stripe by the strand's rim measured as the object)",
        a == 0 ? "left" : "right", near[a], beyond[a].level, inset_px + beyond[a].distance_px,
        a == 0 ? "right" : "left", near[1 - a]);
  }
  return out;
}

SelfCheck CheckEdgeResiduals(const std::vector<double>& left_rms,
                             const std::vector<double>& right_rms) {
  SelfCheck out;
  if (left_rms.size() < 3 || right_rms.size() < 3) return out;
  const double l = Median(left_rms), r = Median(right_rms);
  const double worse = std::max(l, r), better = std::max(std::min(l, r), 1e-9);
  if (worse > kMaxResidualRatio * better && worse - better > kMinResidualExcess) {
    out.passed = false;
    out.why = fmt::format(
        "the {} edge fits a silhouette on a plain background {:.1f}× worse than the {} "
        "(residuals {:.1f} and {:.1f} grey levels)",
        l > r ? "left" : "right", worse / better, l > r ? "right" : "left", worse, better);
  }
  return out;
}

}  // namespace clogscope::vision
