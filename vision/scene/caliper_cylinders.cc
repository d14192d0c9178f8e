#include "vision/scene/caliper_cylinders.h"

#include <algorithm>
#include <cmath>

#include "common/robust.h"
#include "vision/edges/residual_structure.h"

namespace clogscope::vision {

void TakeCylinder(const CylinderFit& cyl, CaliperFit* cf) {
  cf->left.converged = cf->right.converged = cyl.converged;
  cf->left.edge_px = cyl.left_px;
  cf->right.edge_px = cyl.right_px;
  cf->left.edge_sigma_px = cyl.left_sigma_px;
  cf->right.edge_sigma_px = cyl.right_sigma_px;
  cf->left.sigma_px = cf->right.sigma_px = cyl.sigma_px;
  cf->width_sigma_px = cyl.width_sigma_px;
  cf->terminator_px = cyl.terminator_px;
}

void TakeTrackedCylinders(const TrackedCylinders& tracked, std::vector<CaliperFit>* fits) {
  for (size_t k = 0; k < fits->size(); ++k) {
    TakeCylinder(tracked.fits[k], &(*fits)[k]);
    (*fits)[k].left.contrast = CylinderEdgeContrast(tracked.fits[k], 0);
    (*fits)[k].right.contrast = CylinderEdgeContrast(tracked.fits[k], 1);
  }
}

void RefitAsCylinders(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                      double band_s0, double spacing, const EdgeLines& lines, double sigma_px,
                      CylinderBackground background, std::vector<CaliperFit>* fits,
                      double structure_doubt_px[2], CylinderMemory* memory) {
  const double outer = CylinderReachPx(sigma_px);
  std::vector<EdgeSample> samples;
  // The residuals the calipers share near each silhouette (residual_structure.h): a profile the
  // lit cylinder does not describe there (a codec's ringing about the shading's steep start,
  // a stripe or halo beside the edge) moves both of its edges alike in every caliper.
  EdgeStructureDoubt doubt[2] = {EdgeStructureDoubt(outer), EdgeStructureDoubt(outer)};
  std::vector<double> residuals;
  // Each caliper starts from its neighbour's blur: the fit then mostly has only the edges to move.
  double sigma_start = sigma_px;
  for (size_t k = 0; k < fits->size(); ++k) {
    CaliperFit& cf = (*fits)[k];
    const double s0 = band_s0 + k * spacing, sc = s0 + 0.5 * spacing;
    const double l = lines.left_u0 + lines.slope * sc, r = lines.right_u0 + lines.slope * sc;
    // Clipping was judged by the per-edge fits, which saw the same transitions.
    CylinderFit cyl;
    if (GatherCylinderSamples(img, f, clip, s0, s0 + spacing, l, r, sigma_px, &samples))
      cyl = FitLitCylinder(samples, l, r, sigma_start, background,
                           structure_doubt_px ? &residuals : nullptr);
    const bool ok = SilhouettesInSlab(cyl, l, r, sigma_px);
    cf.left.converged = cf.right.converged = ok;
    cyl.converged = ok;
    // A caliper whose fit failed loses its template: counted as none, not as refused every frame.
    if (memory)
      memory->Keep(CylinderMemory::Caliper::OnSlab(s0, s0 + spacing, l, r, sigma_px), samples, cyl);
    if (ok) sigma_start = cyl.sigma_px;
    if (!ok) continue;
    for (int side = 0; side < 2 && structure_doubt_px; ++side) {
      int near = 0;
      const double edge = side == 0 ? cyl.left_px : cyl.right_px;
      for (size_t i = 0; i < samples.size(); ++i) {
        const double du = samples[i].u_px - edge;
        if (std::abs(du) > outer) continue;
        doubt[side].structure().Add(du, residuals[i]);
        ++near;
      }
      doubt[side].AddCaliper(cyl.rms, side == 0 ? cyl.left_sigma_px : cyl.right_sigma_px, near,
                             2 * outer);
    }
    TakeCylinder(cyl, &cf);
  }
  for (int side = 0; side < 2 && structure_doubt_px; ++side)
    structure_doubt_px[side] = doubt[side].DoubtPx();
}

bool CylinderOutwardShiftsPx(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                             double band_s0, double spacing, double s_mid_px,
                             const EdgeLines& lines, double sigma_px,
                             const std::vector<CaliperFit>& fits, double outward_px[2]) {
  std::vector<CaliperFit> cylinders = fits;
  RefitAsCylinders(img, f, clip, band_s0, spacing, lines, sigma_px, CylinderBackground::kEachSide,
                   &cylinders, nullptr, nullptr);
  const EdgeLines lit = FitEdgeLines(cylinders, band_s0, spacing);
  const EdgeLines plain = FitEdgeLines(fits, band_s0, spacing);
  if (lit.calipers < 2 || plain.calipers < 2) return false;
  const auto at = [&](double u0, double slope) { return u0 + slope * s_mid_px; };
  outward_px[0] = at(plain.left_u0, plain.slope) - at(lit.left_u0, lit.slope);
  outward_px[1] = at(lit.right_u0, lit.slope) - at(plain.right_u0, plain.slope);
  return true;
}

}  // namespace clogscope::vision
