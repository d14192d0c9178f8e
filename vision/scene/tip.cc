#include "vision/scene/tip.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "vision/edges/edge_fit.h"

namespace clogscope::vision {
namespace {

constexpr double kOffsetPx = 2.0;  // contrast is read this far either side of the edge
constexpr double kSearchPx = 3.0;  // how far an edge may move from where it was heading, per px
constexpr double kSearchStepPx = 0.25;
constexpr int kWeakSteps = 3;      // an edge ends after this many weak px in a row
constexpr double kInsidePx = 4.0;  // the object's level is read from this far inside its edge
constexpr int kInsideSpanPx = 5;   // ... over this many px further in (at most)
// Where the following starts, the edge is looked for this share of the width either side of the
// straight line (at least kSearchPx, at most twice it).
constexpr double kStartSearchWidths = 0.05;

struct Curve {
  double s_end = 0;       // the last strong s
  std::vector<double> u;  // u at s_from − i
  bool ended = false;     // the edge weakened or the object's level changed (else it ran on)
};

// The object's level inside an edge (object_side: +1 the object lies at +u): the mean of
// `inside_px` px from kInsidePx in.
bool InsideLevel(const GreyImage& img, const AxisFrame& a, double s, double u, int object_side,
                 int inside_px, double* level) {
  double sum = 0;
  for (int k = 0; k < inside_px; ++k) {
    const double ui = u + object_side * (kInsidePx + k);
    const double x = a.ImageX(s, ui), y = a.ImageY(s, ui);
    if (!img.InsideForBilinear(x, y)) return false;
    sum += img.Bilinear(x, y);
  }
  *level = sum / inside_px;
  return true;
}

// The u within ±reach_px of `heading` where the edge's contrast across is largest (its contrast
// in *contrast); false where a reading leaves the image.
bool StrongestNear(const GreyImage& img, const AxisFrame& a, double s, double heading,
                   double reach_px, int sign, double* u, double* contrast) {
  *contrast = -1e30;
  for (double du = -reach_px; du <= reach_px + 1e-9; du += kSearchStepPx) {
    double c;
    if (!ContrastAcross(img, a, s, heading + du, sign, kOffsetPx, &c)) return false;
    if (c > *contrast) {
      *contrast = c;
      *u = heading + du;
    }
  }
  return true;
}

Curve Follow(const GreyImage& img, const AxisFrame& a, double u_start, double slope, int sign,
             int object_side, double ref, double s_from, double max_steps, double width_px) {
  Curve out;
  out.s_end = s_from;
  double u = u_start, velocity = -slope;  // du per px going up
  int weak = 0;
  double strong_c = ref, first_weak_c = 0;
  // The straight line fitted over the whole stretch lies inside a swell's curving outline where
  // the following starts (4 px inside a 45 % swell, 90 px below the face). The level read inside
  // the line there was 8 px inside the outline, where a lit strand is brighter than 4 px inside
  // it (by 12 grey levels under ambient 0.63): once the following reached the outline, the
  // level seemed to change and the edge ended. The following starts from the edge where it is.
  // (Where no edge as strong as half its usual contrast lies within reach, or the reach leaves
  // the image, from the line.)
  const double start_reach_px =
      std::clamp(kStartSearchWidths * width_px, kSearchPx, 2.0 * kSearchPx);
  double start_u, start_c;
  if (StrongestNear(img, a, s_from, u_start, start_reach_px, sign, &start_u, &start_c) &&
      start_c >= 0.5 * ref)
    u = start_u;
  // The strand's own level inside the edge: where it changes, the edge belongs to another
  // object (the nozzle's outline carries on from the strand's when the nozzle, like the strand,
  // is darker or brighter than the background). A mean across a few px: one px's noise (11 grey
  // levels under JPEG) crossed 0.3 of the edge's contrast three px in a row along a follow of
  // 90 px. No further than the strand's middle.
  const int inside_px = std::clamp(static_cast<int>(0.5 * width_px - kInsidePx), 1, kInsideSpanPx);
  double inside_ref = 0;
  if (!InsideLevel(img, a, s_from, u, object_side, inside_px, &inside_ref)) return out;
  for (int i = 1; i <= max_steps; ++i) {
    const double s = s_from - i;
    const double heading = u + velocity;
    double best_u = heading, best_c;
    if (!StrongestNear(img, a, s, heading, kSearchPx, sign, &best_u, &best_c)) return out;
    double inside = inside_ref;
    InsideLevel(img, a, s, best_u, object_side, inside_px, &inside);
    if (best_c < 0.5 * ref || std::abs(inside - inside_ref) > 0.3 * ref) {
      if (weak == 0) first_weak_c = best_c;
      if (++weak >= kWeakSteps) {
        // The half-contrast crossing between the last strong px and the first weak one.
        if (first_weak_c < 0.5 * ref && strong_c > first_weak_c)
          out.s_end -= std::clamp((strong_c - 0.5 * ref) / (strong_c - first_weak_c), 0.0, 1.0);
        out.ended = true;
        return out;
      }
      continue;  // keep heading the same way over a weak px
    }
    weak = 0;
    strong_c = best_c;
    // Smooth the heading: one noisy px must not turn the curve.
    velocity = 0.5 * velocity + 0.5 * (best_u - u);
    u = best_u;
    out.s_end = s;
    out.u.resize(i, u);
    out.u[i - 1] = u;
  }
  return out;
}

// One reading of where the strand meets the nozzle, along the axis.
struct TipEstimate {
  bool found = false;
  double s_px = 0;
  double doubt_px = 0;  // half the disagreement of its readings, or its fit's σ
};

constexpr double kReachPx = 10.0;  // the face is looked for this far either side of the guess
// An object's end read this far below the mean of its followed edges' ends is not its end: over
// 1360 end readings on seeds 1-25 of every matrix class, the largest was 1.3 px below.
constexpr double kEndBelowEdgesPx = 2.5;
constexpr double kNearGuessPx = 6.0;  // a face further than this from the guess is another line
// A face read within this of the guess needs no second reading about itself (TraceToNozzle).
constexpr double kSameFacePx = 0.5;
// A line across the axis sloping more than this (ds/du) is not the nozzle's face: a strand
// hangs up to ~20° off the nozzle's axis, a flank slopes at 50° and more.
constexpr double kMaxSlant = 0.5;
// The least doubt about a tip: read on two lines that agree (the face and the object's end), or
// on one alone (either, with nothing to confirm it).
constexpr double kTipSigmaConfirmedPx = 0.25, kTipSigmaAlonePx = 0.5;
// The object's end is read in the columns between these fractions of its width either side of
// the axis: clear of the edges' blur, and inside where a swell's curved sides begin.
constexpr double kEndColumns[2] = {0.05, 0.3};
// A face's levels are flat and its lower one the background's: over the reach the profile's
// slope changes the level by at most this share of the step (a nozzle's face: a few %; a dip
// read as a step: 50 % and more), and the level below it is the background's further down within
// this share of the step.
constexpr double kMaxSlopeShareOfStep = 0.25;

// The mean of the columns u0..u1 (step 1 px) every half px along the axis from s0 to s1, in the
// rows that lie in the image; *pixels counts the pixels read.
std::vector<EdgeSample> ColumnProfile(const GreyImage& img, const AxisFrame& a, double s0,
                                      double s1, double u0, double u1, int* pixels) {
  constexpr double kStepPx = 0.5;
  std::vector<EdgeSample> profile;
  *pixels = 0;
  const int columns = static_cast<int>(std::floor(u1 - u0 + 1e-9)) + 1;
  if (columns <= 0) return profile;  // no column between u0 and u1
  for (double s = s0; s <= s1; s += kStepPx) {
    // A row across the axis lies in the image when both its ends do; then every column does.
    const double x0 = a.ImageX(s, u0), y0 = a.ImageY(s, u0);
    const double x1 = a.ImageX(s, u0 + columns - 1), y1 = a.ImageY(s, u0 + columns - 1);
    if (!img.InsideForBilinear(x0, y0) || !img.InsideForBilinear(x1, y1)) continue;
    double sum = 0;
    for (int k = 0; k < columns; ++k) sum += img.Bilinear(x0 + k * a.dy, y0 - k * a.dx);
    profile.push_back({static_cast<float>(s), static_cast<float>(sum / columns)});
    *pixels += columns;
  }
  return profile;
}

// A blurred step along the axis in the columns u0..u1 (step 1 px) near s_guess. The step depends
// on s alone, so it is fitted to the columns' mean profile: the same least-squares edge as all
// their pixels give, at the cost of one column (a strand's end spans dozens, every frame).
bool AxialStep(const GreyImage& img, const AxisFrame& a, double s_guess, double u0, double u1,
               double min_contrast, EdgeFit* fit) {
  constexpr int kMinPixels = 60;
  int pixels = 0;
  const std::vector<EdgeSample> profile =
      ColumnProfile(img, a, s_guess - kReachPx, s_guess + kReachPx, u0, u1, &pixels);
  if (pixels < kMinPixels) return false;
  *fit = FitBlurredStep(profile, s_guess, 1.5, s_guess);
  return fit->converged && std::abs(fit->step) >= min_contrast &&
         std::abs(fit->edge_px - s_guess) <= kReachPx - 2.0 && fit->sigma_px <= 6.0;
}

// One reading of a line across the axis (the nozzle's face, the object's end): where it crosses
// the columns about u_px.
struct LineReading {
  double u_px = 0, s_px = 0, sigma_px = 0;
  double step = 0;  // signed, along +s
};

// The nozzle's face beside the strand: just outside the outline on one side, the profile along
// the axis steps from the nozzle to the background at the face. A blurred step fitted there puts
// the tip to a fraction of a px, where the end of a followed edge is only good to the blur.
// Columns from just outside the outline outward: near the face a swollen strand may still be
// wider than the outline followed, and the profile there crosses it too; so the side is read at
// the first two offsets where the face shows.
std::vector<LineReading> FaceOnSide(const GreyImage& img, const AxisFrame& a, double s_guess,
                                    double half_px, double min_contrast, int side) {
  constexpr double kColumnsPx = 4.0;
  constexpr double kOffsetsPx[] = {3.0, 9.0, 15.0, 21.0, 30.0};
  std::vector<LineReading> found;
  for (double offset : kOffsetsPx) {
    const double u_in = side * (half_px + offset), u_out = side * (half_px + offset + kColumnsPx);
    EdgeFit fit;
    if (!AxialStep(img, a, s_guess, std::min(u_in, u_out), std::max(u_in, u_out), min_contrast,
                   &fit)) {
      if (found.empty()) continue;
      break;
    }
    if (std::abs(fit.edge_px - s_guess) > kNearGuessPx) break;
    // A face is a step between two flat levels, onto the background: the same columns further
    // down are at the level below it. A profile the fit could only follow with its slope doing a
    // step's work is a dip (beside a die swell the columns cross the swollen strand's outline and
    // back: a step of +131 on a slope of −6.7 per px, 7 px below the face); a step onto another
    // level is some other object's outline (a tilted strand's own, under a nozzle at the
    // background's level, once told which of a strand and a hair hung from the nozzle).
    const double share = kMaxSlopeShareOfStep * std::abs(fit.step);
    const auto onto_background = [&] {
      int pixels = 0;
      const std::vector<EdgeSample> further =
          ColumnProfile(img, a, s_guess + kReachPx, s_guess + 3 * kReachPx, std::min(u_in, u_out),
                        std::max(u_in, u_out), &pixels);
      if (further.empty()) return false;
      double background = 0;
      for (const EdgeSample& e : further) background += e.value / further.size();
      return std::abs(EdgeModelValue(fit, fit.edge_px + 3.0 * fit.sigma_px) - background) <= share;
    };
    if (std::abs(fit.slope_per_px) * kReachPx > share || !onto_background()) {
      if (found.empty()) continue;
      break;
    }
    found.push_back({0.5 * (u_in + u_out), fit.edge_px, fit.edge_sigma_px, fit.step});
    if (found.size() == 2) break;
  }
  return found;
}

// The line through readings on both sides of the axis, where it crosses the axis (u = 0): the
// nozzle's face or the object's end need not be square to a strand that hangs at an angle, but a
// slope steeper than kMaxSlant is two lines (a flank on one side). Doubtful by the readings' own
// σ and, with more readings than the line needs, by their scatter about it.
TipEstimate LineAcross(const std::vector<LineReading>& left,
                       const std::vector<LineReading>& right) {
  TipEstimate e;
  if (left.empty() || right.empty()) return e;
  double n = 0, su = 0, ss = 0, suu = 0, sus = 0, sigma = 0;
  int up = 0;
  for (const auto* side : {&left, &right})
    for (const LineReading& r : *side) {
      up += r.step > 0;
      n += 1;
      su += r.u_px;
      ss += r.s_px;
      suu += r.u_px * r.u_px;
      sus += r.u_px * r.s_px;
      sigma = std::max(sigma, r.sigma_px);
    }
  // One line steps the same way on both sides: from the nozzle's level to the background's (a
  // face), or to the strand's (the object's end).
  if (up > 0 && up < n) return e;
  const double det = n * suu - su * su;
  if (det <= 0) return e;
  const double slope = (n * sus - su * ss) / det, at_axis = (ss - slope * su) / n;
  if (std::abs(slope) > kMaxSlant) return e;
  double ssr = 0;
  for (const auto* side : {&left, &right})
    for (const LineReading& r : *side) ssr += std::pow(r.s_px - at_axis - slope * r.u_px, 2);
  e.found = true;
  e.s_px = at_axis;
  e.doubt_px = n > 2 ? std::max(sigma, std::sqrt(ssr / (n - 2))) : sigma;
  return e;
}

// The object's own end along the axis in columns u0..u1: where the strand gives way to the
// nozzle above it.
std::vector<LineReading> ObjectEnd(const GreyImage& img, const AxisFrame& a, double s_guess,
                                   double u0, double u1, double min_contrast) {
  EdgeFit fit;
  if (!AxialStep(img, a, s_guess, u0, u1, min_contrast, &fit) ||
      std::abs(fit.edge_px - s_guess) > kNearGuessPx)
    return {};
  return {{0.5 * (u0 + u1), fit.edge_px, fit.edge_sigma_px, fit.step}};
}

}  // namespace

TipTrace TraceToNozzle(const GreyImage& img, const AxisFrame& a, double left_u0, double right_u0,
                       double slope, int left_sign, int right_sign, double ref_l, double ref_r,
                       double s_from, double min_face_step) {
  TipTrace t;
  const double width = right_u0 - left_u0;
  const double max_steps = std::max(20.0, 2.0 * width);
  const Curve l = Follow(img, a, left_u0 + slope * s_from, slope, left_sign, +1, ref_l, s_from,
                         max_steps, width);
  const Curve r = Follow(img, a, right_u0 + slope * s_from, slope, right_sign, -1, ref_r, s_from,
                         max_steps, width);
  // An outline that runs on as far as it was followed (or out of the image) has no end here.
  t.runs_on = !l.ended && !r.ended;
  if (t.runs_on) return t;
  // A nozzle face ends both edges together; a hair or a flank that one edge ran into does not.
  if (std::abs(l.s_end - r.s_end) > MaxTipMismatchPx(width)) return t;
  t.found = true;
  const double edges_end = 0.5 * (l.s_end + r.s_end);
  t.s_tip_px = edges_end;
  t.widest_px = width;
  const size_t n = std::min(l.u.size(), r.u.size());
  for (size_t i = 0; i < n; ++i) t.widest_px = std::max(t.widest_px, r.u[i] - l.u[i]);
  // The followed edges end within the blur of the face. Sharper are the face itself where the
  // nozzle shows beside the strand, and the object's own end where the nozzle's level differs
  // from the strand's (read along the axis in each half of the strand: a face slanted across it
  // shows as their disagreement).
  const double axis_u = 0.5 * (left_u0 + right_u0) + slope * t.s_tip_px;
  AxisFrame centred = a;
  centred.ox = a.ImageX(0, axis_u);
  centred.oy = a.ImageY(0, axis_u);
  const double half = 0.5 * t.widest_px;
  // The face read on both sides of the strand about s.
  const auto faces_about = [&](double s) {
    return std::array<std::vector<LineReading>, 2>{
        FaceOnSide(img, centred, s, half, min_face_step, -1),
        FaceOnSide(img, centred, s, half, min_face_step, +1)};
  };
  // Looked for from the edge that got furthest, then from both ends' middle: an edge that
  // stopped short in noise leaves the other's end nearer the face.
  for (double s_guess : {std::min(l.s_end, r.s_end), t.s_tip_px}) {
    std::array<std::vector<LineReading>, 2> faces = faces_about(s_guess);
    TipEstimate face = LineAcross(faces[0], faces[1]);
    // Read again about the face found: the edges of a swell that flares too fast to follow end
    // several px short of it, and a window about their end holds too little of the face to fit
    // in the columns further out, where the flare no longer crosses them (swell 9422: the edges
    // ended 6.5 px below the face, only the columns beside the flare read it, 4-5 px low, and
    // the width came out 2.1-2.9 px narrow at σ 0.23-0.28). A face within kSameFacePx of the
    // guess is read the same about itself: on 228 faces of four classes, the 109 that near moved
    // by at most 0.008 px when read again (those 0.5-1 px off, by up to 0.7 px).
    if (face.found && std::abs(face.s_px - s_guess) > kSameFacePx) {
      std::array<std::vector<LineReading>, 2> again = faces_about(face.s_px);
      const TipEstimate refined = LineAcross(again[0], again[1]);
      if (refined.found) {
        face = refined;
        faces = std::move(again);
      }
    }
    // The object's end lies where its edges end, or above them where a swell flared too fast to
    // follow; never below where both edges were still followed. A step read there is something
    // inside the strand, fitted because the end itself lay just beyond reach above (swell 3664:
    // 10 px below the end, the width 1.65 px narrow at σ 0.10-0.12 in two frames of four).
    const auto end_near = [&](double s) {
      const TipEstimate e = LineAcross(ObjectEnd(img, centred, s, -kEndColumns[1] * width,
                                                 -kEndColumns[0] * width, min_face_step),
                                       ObjectEnd(img, centred, s, kEndColumns[0] * width,
                                                 kEndColumns[1] * width, min_face_step));
      return e.found && e.s_px > edges_end + kEndBelowEdgesPx ? TipEstimate{} : e;
    };
    // Edges that flare out into a swell too fast to follow end short of the nozzle: the object's
    // end may lie beyond the reach below, and is looked for again half a reach further up.
    TipEstimate end = end_near(s_guess);
    if (!end.found) end = end_near(s_guess - 0.5 * kReachPx);
    // A face on one side only, or two that are not one line (a flank, a hair's end): the reading
    // nearest the guess.
    const LineReading* one = nullptr;
    if (!face.found)
      for (const auto& side : faces)
        for (const LineReading& r : side)
          if (!one || std::abs(r.s_px - s_guess) < std::abs(one->s_px - s_guess)) one = &r;
    t.face_sides = face.found ? 2 : one ? 1 : 0;
    t.face_step = 0;
    if (face.found)
      for (const auto& side : faces)
        for (const LineReading& r : side) t.face_step = std::max(t.face_step, std::abs(r.step));
    if (end.found) {
      // Confirmed by the face beside it, or alone (the nozzle at the background's level).
      const bool confirmed = face.found || one;
      const double other_s = face.found ? face.s_px : one ? one->s_px : end.s_px;
      t.s_tip_px = end.s_px;
      t.tip_sigma_px = std::max({confirmed ? kTipSigmaConfirmedPx : kTipSigmaAlonePx, end.doubt_px,
                                 0.5 * std::abs(end.s_px - other_s)});
      break;
    }
    if (face.found) {
      t.s_tip_px = face.s_px;
      t.tip_sigma_px = std::max(kTipSigmaAlonePx, face.doubt_px);
      break;
    }
    if (one) {
      t.s_tip_px = one->s_px;  // its doubt is the caller's: unconfirmed
      break;
    }
  }
  return t;
}

}  // namespace clogscope::vision
