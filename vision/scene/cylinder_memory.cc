#include "vision/scene/cylinder_memory.h"

#include <algorithm>
#include <cmath>

namespace clogscope::vision {
namespace {
long Key(double s0_px) { return std::lround(s0_px * 1024.0); }
}  // namespace

double CylinderReachPx(double sigma_px) { return std::max(10.0, 3.0 * sigma_px + 2.5); }

bool SilhouettesInSlab(const CylinderFit& fit, double left_px, double right_px, double sigma_px) {
  const double outer = CylinderReachPx(sigma_px);
  return fit.converged && std::abs(fit.left_px - left_px) < outer - 1.0 &&
         std::abs(fit.right_px - right_px) < outer - 1.0;
}

bool GatherCylinderSamples(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                           double s0_px, double s1_px, double left_px, double right_px,
                           double sigma_px, std::vector<EdgeSample>* samples,
                           ClippedCount* at_edges) {
  const double outer = CylinderReachPx(sigma_px);
  // In one pass over the slab: clipping is counted in both edges' transitions as the per-edge
  // fits judge it, over all pixels there (a clipped highlight deep inside a lit object is not
  // where its silhouettes are read: the interior's clipping is judged on the band as a whole,
  // calipers.cc); deep inside, the profile only tells the shading's amplitudes, which vary
  // slowly: every fourth pixel there does, and the fit costs a third.
  const double zone = ClipZoneHalfWidthPx(sigma_px);
  const double keep = CylinderInteriorMarginPx(sigma_px);
  ClippedCount left, right;
  samples->clear();
  size_t i = 0;  // the slab's pixels so far
  const bool inside = ForEachSlabPixel(
      img, f, s0_px, s1_px, left_px - outer, right_px + outer, [&](double u_px, float v) {
        const EdgeSample smp{static_cast<float>(u_px), v};
        if (at_edges) {
          left.Add(smp, clip, left_px, zone);
          right.Add(smp, clip, right_px, zone);
        }
        if (smp.u_px < left_px + keep || smp.u_px > right_px - keep || i % 4 == 0)
          samples->push_back(smp);
        ++i;
      });
  if (!inside) return false;
  if (at_edges) {
    at_edges->samples = left.samples + right.samples;
    at_edges->clipped = left.clipped + right.clipped;
  }
  return true;
}

void CylinderMemory::Wake() {
  for (auto& [key, caliper] : calipers_) caliper.rest_frames = 0;
}

void CylinderMemory::Use(const AxisFrame& f, double spacing_px) {
  if (f.ox == frame_.ox && f.oy == frame_.oy && f.dx == frame_.dx && f.dy == frame_.dy &&
      spacing_px == spacing_px_)
    return;
  calipers_.clear();
  frame_ = f;
  spacing_px_ = spacing_px;
}

const CylinderMemory::Caliper* CylinderMemory::Find(double s0_px) const {
  const auto it = calipers_.find(Key(s0_px));
  return it == calipers_.end() ? nullptr : &it->second;
}

CylinderMemory::Caliper* CylinderMemory::Find(double s0_px) {
  const auto it = calipers_.find(Key(s0_px));
  return it == calipers_.end() ? nullptr : &it->second;
}

void CylinderMemory::Keep(const Caliper& slab, const std::vector<EdgeSample>& samples,
                          const CylinderFit& fit) {
  Caliper c = slab;
  if (MakeCylinderTemplate(samples, fit, &c.cylinder)) {
    c.failures = 0;
  } else {
    const Caliper* before = Find(slab.s0_px);
    c.failures = std::min(before ? before->failures + 1 : 1, kMaxRestDoublings + 1);
    c.rest_frames = kRestFrames << (c.failures - 1);
  }
  calipers_[Key(slab.s0_px)] = std::move(c);
}

TrackedCylinders TrackCylinders(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                                double band_s0_px, double spacing_px, int n,
                                CylinderMemory* memory) {
  TrackedCylinders out;
  out.fits.resize(n);
  std::vector<EdgeSample> samples;
  const CylinderTrackOptions options;
  for (int k = 0; k < n; ++k) {
    const double s0 = band_s0_px + k * spacing_px, s1 = s0 + spacing_px;
    CylinderFit& fit = out.fits[k];
    ClippedCount at_edges;
    CylinderMemory::Caliper* c = memory->Find(s0);
    if (c && c->rest_frames > 0) {  // resting after a failed full fit
      --c->rest_frames;
      continue;
    }
    if (c && !c->cylinder.empty()) {
      if (!GatherCylinderSamples(img, f, clip, c->s0_px, c->s1_px, c->left_px, c->right_px,
                                 c->sigma_px, &samples, &at_edges)) {
        out.border = true;
        continue;
      }
      // A template may follow its object from frame to frame: not out of the pixels it has.
      const auto refusal = TrackLitCylinder(&c->cylinder, samples, options, &fit, &c->last);
      if (refusal == CylinderTrackRefusal::kNone &&
          SilhouettesInSlab(fit, c->left_px, c->right_px, c->sigma_px)) {
        ++out.from_template;
        c->last = fit;
        out.samples += at_edges.samples;
        out.saturated += at_edges.clipped;
        continue;
      }
      ++out.refused;
      fit.converged = false;  // (a fit outside its slab) until the full fit below replaces it
    }
    // Its template's slab, or the one of the fit that failed before its rest; else one about the
    // memory's lines.
    const double sc = 0.5 * (s0 + s1);
    const CylinderMemory::Caliper slab =
        c ? CylinderMemory::Caliper::OnSlab(s0, s1, c->left_px, c->right_px, c->sigma_px)
          : CylinderMemory::Caliper::OnSlab(s0, s1, memory->left_u0_px + memory->slope * sc,
                                            memory->right_u0_px + memory->slope * sc,
                                            memory->sigma_px);
    // In full, as calipers.cc's RefitAsCylinders (a cylinder whose silhouettes leave their slab
    // does not count).
    if (!GatherCylinderSamples(img, f, clip, s0, s1, slab.left_px, slab.right_px, slab.sigma_px,
                               &samples, &at_edges)) {
      out.border = true;
      continue;
    }
    out.samples += at_edges.samples;
    out.saturated += at_edges.clipped;
    ++out.fitted_in_full;
    fit = FitLitCylinder(samples, slab.left_px, slab.right_px, slab.sigma_px,
                         CylinderBackground::kOneLine);
    fit.converged = SilhouettesInSlab(fit, slab.left_px, slab.right_px, slab.sigma_px);
    memory->Keep(slab, samples, fit);  // a failed fit drops the caliper's template, rests it
  }
  return out;
}

}  // namespace clogscope::vision
