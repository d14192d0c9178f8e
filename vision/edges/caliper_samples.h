#pragma once

// The pixels a caliper works on: one slab of the strand, across one edge or both.
#include <cmath>
#include <vector>

#include "vision/edges/clip_levels.h"
#include "vision/edges/edge_fit.h"
#include "vision/edges/grey_image.h"

namespace clogscope::vision {

// The clip levels of the slab s0 <= s < s1, u0 <= u <= u1: the data's max and 0, or a spike at
// most 1 % of black-to-white inside the data's white (black), or in the outer 4 % of its range,
// holding ≥ 2 % of the slab's pixels, ≥ 5× the pixels of the values just inside it and ≥ 2× those
// beyond it (or ≥ 10× and ≥ 1×, or ≥ 3× and ≥ 5×); or such a spike split over two levels, the
// second half to twice the first, the pair ≥ 10× the values just inside it and ≥ 6.7× those
// beyond it. Where the slab holds ≥ 2 % of its pixels in those levels but no spike, the spike is
// looked for in the whole image (every 4th pixel of every 4th row, when the image holds 4 times
// the slab's pixels), and taken where the slab holds ≥ 2 % of its pixels at it.
ClipLevels FindClipLevels(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                          double u1, const DataLevels& levels);

// The pixels of the slab s0 <= s < s1, u0 <= u <= u1 (axis frame f): its bounding box's rows
// (false when the box leaves the image), and in row y the pixels first <= x <= last.
bool SlabBounds(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                double u1, int* x_lo, int* x_hi, int* y_lo, int* y_hi);
void SlabRow(const AxisFrame& f, int y, int x_lo, int x_hi, double s0, double s1, double u0,
             double u1, int* first, int* last);
// Calls visit(u, value) for each pixel of that slab, a row at a time, each row in order of x;
// false, with no call, when the slab leaves the image.
template <class Visit>
bool ForEachSlabPixel(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                      double u1, Visit&& visit) {
  int x_lo, x_hi, y_lo, y_hi;
  if (!SlabBounds(img, f, s0, s1, u0, u1, &x_lo, &x_hi, &y_lo, &y_hi)) return false;
  const auto row = [&](int y, const auto* values) {
    int first, last;
    SlabRow(f, y, x_lo, x_hi, s0, s1, u0, u1, &first, &last);
    for (int x = first; x <= last; ++x) visit(f.U(x, y), static_cast<float>(values[x]));
  };
  for (int y = y_lo; y <= y_hi; ++y) {
    if (img.is16)
      row(y, img.m.ptr<uint16_t>(y));
    else
      row(y, img.m.ptr<uint8_t>(y));
  }
  return true;
}

// Gathers the pixels of the slab s0 <= s < s1, u0 <= u <= u1 (axis frame f) in (u, value) form,
// counting those at or beyond the clip levels in *saturated (when given). Returns false when the
// slab leaves the image.
bool GatherEdgeSamples(const GreyImage& img, const AxisFrame& f, double s0, double s1, double u0,
                       double u1, const ClipLevels& clip, std::vector<EdgeSample>* out,
                       int* saturated = nullptr);

// A caliper's pixels in groups at about the same u: sorted by u, a group takes the next pixel
// while it lies within span_px of the group's first, or within interior_span_px where the group
// starts inside [interior_lo_px, interior_hi_px) (not past its end). On an object nearly along a
// pixel axis a slab's rows give a group per column, and a fit evaluates its model and Jacobian
// once a group, at its mean u, and each pixel's value from there by the model's slope across u:
// what that leaves out is the model's curvature over the span.
struct PixelGroups {
  std::vector<int> pixels;        // indices into the samples, group by group
  std::vector<float> offset_px;   // each of them: its u less its group's mean u
  std::vector<int> end;           // where each group's pixels end in `pixels`
  std::vector<double> mean_u_px;  // each group's mean u
  size_t size() const { return end.size(); }
};
// A fit's groups about an edge of blur σ span this many σ: the model's curvature over the span is
// below 1e-4 of the step, and odd about the edge (it moves no edge).
inline constexpr double kGroupSpanBlurs = 0.05;
// (Samples' u must be finite.)
PixelGroups GroupByU(const std::vector<EdgeSample>& samples, double span_px,
                     double interior_lo_px = 0, double interior_hi_px = 0,
                     double interior_span_px = 0);

// Of the samples within half_px of an edge at edge_u (its transition, where the edge's position
// is read), how many there are and how many are clipped.
struct ClippedCount {
  int samples = 0, clipped = 0;
  // Counts one sample, when it lies within half_px of edge_u.
  void Add(const EdgeSample& smp, const ClipLevels& clip, double edge_u, double half_px) {
    if (std::abs(smp.u_px - edge_u) > half_px) return;
    ++samples;
    clipped += Clipped(smp.value, clip);
  }
};
ClippedCount CountClippedNear(const std::vector<EdgeSample>& samples, const ClipLevels& clip,
                              double edge_u, double half_px);
// An edge's transition, where clipping is judged: two blurs either side of it, and 1 px for the
// pixel footprint. (A clipped object or background reaching into it biases the edge; clipping
// further away moves a plateau's level by a fraction of a grey level.)
inline double ClipZoneHalfWidthPx(double sigma_px) { return 2.0 * sigma_px + 1.0; }

// How far inside the object, from an edge at edge_u (the object toward `inward`, ±1), the next
// edge lies: a stripe, a lens's core, a clear strand's inner line. Read from the profile across
// the axis averaged over the band s0..s1: past the edge's own gradient peak the gradient falls,
// then turns back at ≥ 25 % of the edge's gradient with a step of at least min_step across it, in
// the median over the band's rows (a blob over part of the band does not count). Looks as deep as
// max_depth_px; returns infinity when nothing is there. beyond_px (when given): how far the edge
// after it lies, where the gradient turns back to the silhouette's sign by the same rule (a
// stripe's far side), as deep as beyond_depth_px (or max_depth_px) where the image allows;
// infinity when none.
double InnerEdgeDistance(const GreyImage& img, const AxisFrame& f, double s0, double s1,
                         double edge_u, int inward, double max_depth_px, double min_step,
                         double* beyond_px = nullptr, double beyond_depth_px = 0);

// Sub-pixel start for an edge fit: along the normal at s, from u_guess - half to u_guess + half in
// half-pixel steps, the crossing of the local mid-level (between the profile's extremes) nearest to
// u_guess in the edge's direction (sign: +1 rising with u, −1 falling, 0 either). Returns u_guess
// when the profile has no clear step (extremes closer than min_step) or no such crossing (a
// brighter stripe beside a dark strand's edge crosses the mid-level, its edge does not).
double RefineEdgeGuess(const GreyImage& img, const AxisFrame& f, double s, double u_guess,
                       double half, double min_step, int sign);

}  // namespace clogscope::vision
