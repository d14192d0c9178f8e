#pragma once

// Internal to MeasureCalipers (calipers.h): the calipers' lit cylinders (cylinder_fit.h), fitted in
// full or taken from their templates (cylinder_memory.h), as the calipers' edges.
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/cylinder_fit.h"
#include "vision/edges/grey_image.h"
#include "vision/scene/caliper_edges.h"
#include "vision/scene/cylinder_memory.h"

namespace clogscope::vision {

// A caliper's edges from its lit cylinder.
void TakeCylinder(const CylinderFit& cyl, CaliperFit* cf);

// Each caliper's edges from its tracked cylinder (TrackCylinders), with their contrasts as a
// per-edge fit's.
void TakeTrackedCylinders(const TrackedCylinders& tracked, std::vector<CaliperFit>* fits);

// Replaces each caliper's two per-edge fits by one lit cylinder across its whole profile (see
// cylinder_fit.h): shared centre, radius, blur and shading, so the interior's curvature fixes the
// shading that a per-edge fit trades against its edge. A caliper whose cylinder does not fit, or
// whose silhouettes leave their windows, is dropped rather than mixed with per-edge widths.
// structure_doubt_px (per side), when given: how far what the cylinders' residuals share near each
// silhouette may have moved it (residual_structure.h). With a memory, each cylinder is kept as the
// template of its caliper (cylinder_memory.h).
void RefitAsCylinders(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                      double band_s0, double spacing, const EdgeLines& lines, double sigma_px,
                      CylinderBackground background, std::vector<CaliperFit>* fits,
                      double structure_doubt_px[2], CylinderMemory* memory);

// Where the calipers' lit cylinders (fitted as RefitAsCylinders does, each side's background its
// own line, nothing kept) would put an object's silhouettes against the per-edge fits in `fits`:
// per side (0 left, 1 right), how far outward of the per-edge lines at s_mid_px the cylinders'
// lines lie, px (negative: inward). False when fewer than two calipers have both.
bool CylinderOutwardShiftsPx(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                             double band_s0, double spacing, double s_mid_px,
                             const EdgeLines& lines, double sigma_px,
                             const std::vector<CaliperFit>& fits, double outward_px[2]);

}  // namespace clogscope::vision
