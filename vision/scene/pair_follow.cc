// Following a candidate pair along the full-resolution image: its edges walked to their ends,
// the nozzle's tip traced (scene.h, FollowPair).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/robust.h"
#include "vision/scene/scene.h"
#include "vision/scene/tip.h"

namespace clogscope::vision {
namespace {

constexpr double kFollowOffsetPx = 3.0;  // edge contrast is read this far either side
// An edge walk that ends within this of its start began off the edge.
constexpr double kOffEdgeStartPx = 3.0;
constexpr double kEndFraction = 0.3;  // an edge ends where its contrast falls below this share

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

}  // namespace clogscope::vision
