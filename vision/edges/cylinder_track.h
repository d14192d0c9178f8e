#pragma once

// A lit cylinder fitted in full once (cylinder_fit.h), fitted again in later frames of a steady
// scene as a template: the model's three shapes (box, lit, tilt) and their derivatives by centre,
// radius and blur are kept for each group of the caliper's pixels (at about the same u: a group's
// pixels read from its values by the model's slope), so that a later frame's fit on the same
// pixels needs them evaluated again only when the object has moved. The template's model is
// exact in the background and the three amplitudes (a change of lighting is followed), and first
// order in the geometry about where its shapes were evaluated: when the centre, radius or blur
// moved further than that holds, the shapes are evaluated again there; it refuses when they moved
// too far for that, and when the profile no longer looks like the reference's (more noise, other
// shading), rather than give a width the full fit would not.
#include <array>
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/cylinder_fit.h"
#include "vision/edges/edge_fit.h"

namespace clogscope::vision {

struct CylinderTemplate {
  // The caliper's pixels in groups at about the same u (GroupCylinderPixels about the reference
  // fit's silhouettes). A row per group, a column per kShapeColumns: its mean u − u_ref, the three
  // shapes and their derivatives d[shape][centre, radius, blur], at the geometry below (columns,
  // so that a frame's model is evaluated for all groups at once).
  enum { kDu, kShape, kDShape = kShape + 3, kShapeColumns = kDShape + 9 };
  static constexpr int DShape(int shape, int by) { return kDShape + 3 * shape + by; }
  std::vector<double> shapes;                    // column by column, a row per group
  bool empty() const { return shapes.empty(); }  // no template
  PixelGroups groups;
  int pixels = 0;    // the caliper's samples
  double noise = 0;  // robust scale (1.4826·MAD) of the reference fit's residuals, grey levels
  float first_u_px = 0, last_u_px = 0;  // the samples' ends, to tell that they are the same pixels
  CylinderFit reference;                // the full fit the template was made from
  double max_sigma_px = 0;              // the full fit's bound on the blur
  // The geometry the shapes are evaluated at: the reference's, or where a fit that moved beyond
  // the first order's reach (CylinderTrackOptions) evaluated them again.
  double centre_px = 0, radius_px = 0, sigma_px = 0;
  int relinearisations = 0;  // frames whose accepted fit evaluated them again
};

// Limits beyond which the template refuses. Lengths in px.
struct CylinderTrackOptions {
  // Centre or radius this far from the geometry the template's shapes were evaluated at: beyond
  // its first order's reach. The shapes are then evaluated again where the fit moved to, and the
  // fit done again, at most max_relinearisations times; beyond, it refuses (kMoved).
  double max_shift_px = 0.3;
  double max_blur_change_px = 0.3;
  int max_relinearisations = 2;
  // The residuals' robust scale above this many times the template's: something the template does
  // not describe (a particle, a gear tooth, a change of the scene).
  double max_noise_ratio = 1.5;
  // The object's brightness above the background (its amplitudes a, k, l) changed by more than
  // this fraction of the template's a + k: the lighting changed, and the template's shading with
  // it.
  double max_shading_change_fraction = 0.15;
};

// Why a template was not fitted to a frame.
enum class CylinderTrackRefusal {
  kNone,
  kOtherSamples,    // not the template's pixels
  kMoved,           // beyond max_relinearisations, or the blur beyond the full fit's bounds
  kShadingChanged,  // amplitudes beyond max_shading_change_fraction
  kNoisier,         // residual scale beyond max_noise_ratio
  kNotConverged,
};
const char* CylinderTrackRefusalName(CylinderTrackRefusal r);

// The template of a converged full fit with one background line (CylinderBackground::kOneLine) on
// `samples` (the same samples it was fitted to). False when the fit did not converge or has a line
// each side.
bool MakeCylinderTemplate(const std::vector<EdgeSample>& samples, const CylinderFit& fit,
                          CylinderTemplate* out);

// Fits the template to `samples`, the template's pixels in a later frame: steps on the full fit's
// robust (Cauchy) loss at the reference fit's scale (Gauss–Newton ones until the scale is taken,
// then Newton's, on the loss's and the model's own curvature). On success fills *out as
// FitLitCylinder would (edges, their σ from the weighted normal matrix, blur, amplitudes, noise)
// and returns kNone; otherwise the reason, and *out is not converged. On success only, *t keeps its
// shapes evaluated again where the object moved to, if it did. `start`, when given and converged,
// is where the fit starts (the same template's fit in the frame before, which lies nearer this
// frame's than the template's own).
CylinderTrackRefusal TrackLitCylinder(CylinderTemplate* t, const std::vector<EdgeSample>& samples,
                                      const CylinderTrackOptions& options, CylinderFit* out,
                                      const CylinderFit* start = nullptr);

}  // namespace clogscope::vision
