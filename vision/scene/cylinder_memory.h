#pragma once

#include <map>
#include <vector>

#include "vision/edges/caliper_samples.h"
#include "vision/edges/cylinder_track.h"
#include "vision/edges/grey_image.h"

namespace clogscope::vision {

// How far beyond each edge a caliper's lit cylinder is fitted, for a blur sigma_px.
double CylinderReachPx(double sigma_px);

// Whether a caliper's fitted cylinder converged with its silhouettes inside the slab it was fitted
// on (left_px and right_px, blur sigma_px, as GatherCylinderSamples): a pixel short of its reach.
bool SilhouettesInSlab(const CylinderFit& fit, double left_px, double right_px, double sigma_px);

// The pixels one caliper's lit cylinder is fitted to: the slab s0 <= s < s1 across both edges
// (left_px and right_px at its middle) and far enough beyond them for a blur sigma_px, every
// fourth pixel deep inside the object. Counts the pixels in both edges' transitions and how many
// of them are clipped (ClipZoneHalfWidthPx about left_px and right_px) in *at_edges when given,
// where clipping is judged as the per-edge fits judge it; false when the slab leaves the image.
bool GatherCylinderSamples(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                           double s0_px, double s1_px, double left_px, double right_px,
                           double sigma_px, std::vector<EdgeSample>* samples,
                           ClippedCount* at_edges = nullptr);

// A filament's calipers as lit cylinders, kept from the frames that fitted them in full, for the
// next frames of the same scene (the same axis frame and caliper grid): each caliper's template
// (cylinder_track.h) and the slab it was fitted on.
class CylinderMemory {
 public:
  struct Caliper {
    double s0_px = 0, s1_px = 0, left_px = 0, right_px = 0, sigma_px = 0;  // its slab
    CylinderTemplate cylinder;  // no samples while the caliper rests
    int rest_frames = 0;        // frames it is left out before its full fit is tried again
    int failures = 0;           // full fits in a row that failed
    CylinderFit last;           // its template's last fit, where the next one starts
    // A caliper on the slab s0 <= s < s1 about left_px and right_px, for a blur sigma_px.
    static Caliper OnSlab(double s0_px, double s1_px, double left_px, double right_px,
                          double sigma_px) {
      Caliper c;
      c.s0_px = s0_px;
      c.s1_px = s1_px;
      c.left_px = left_px;
      c.right_px = right_px;
      c.sigma_px = sigma_px;
      return c;
    }
  };
  // After a full fit that failed (a gear tooth over an edge, mostly), a caliper is left out for
  // this many frames: on a drive's video the same few calipers failed again in most frames, at
  // the full fit's most iterations, and cost an eighth of the path's instructions. Each failure
  // in a row doubles the rest, up to kMaxRestDoublings times (4 ... 64 frames): a caliper on the
  // gear's side of the stretch fails whenever it is tried.
  static constexpr int kRestFrames = 4;
  static constexpr int kMaxRestDoublings = 4;

  // Forgets the templates unless they were made in axis frame f on calipers `spacing_px` long.
  void Use(const AxisFrame& f, double spacing_px);
  // Ends every caliper's rest: each is fitted again in the next frame.
  void Wake();
  void Clear() { calipers_.clear(); }
  bool empty() const { return calipers_.empty(); }

  // The caliper starting at s0_px, or null.
  const Caliper* Find(double s0_px) const;
  Caliper* Find(double s0_px);
  // Keeps a caliper's full fit on `samples` (gathered as GatherCylinderSamples with its slab) as
  // its template; a fit that did not converge drops the template it had and rests the caliper.
  void Keep(const Caliper& slab, const std::vector<EdgeSample>& samples, const CylinderFit& fit);

  // What the full measurement that made the templates found beyond the fits: the edge lines
  // u = left_u0 + slope·s (right likewise) and the blur of its per-edge fits, about which its
  // cylinders were fitted, and how far their edges lay from the per-edge fits' beyond the blur
  // (calipers.cc).
  double left_u0_px = 0, right_u0_px = 0, slope = 0;
  double sigma_px = 0;
  double cylinder_doubt_px = 0;
  // Frames measured from the templates (calipers.cc counts them; for tests and benches).
  int frames_from_templates = 0;

 private:
  AxisFrame frame_;
  double spacing_px_ = 0;
  std::map<long, Caliper> calipers_;  // by s0 in 1/1024 px
};

// Every caliper of [band_s0_px, band_s0_px + n·spacing_px) fitted as a lit cylinder: from its
// template where it has one that holds in this frame and keeps its silhouettes in its slab; none
// while it rests; else in full
// (FitLitCylinder on the template's slab, or on one about the memory's lines), its template then
// kept. The slabs stay where the full measurement put them: on real profiles the full fit's width
// moves with the pixels it is given by a tenth of a px.
struct TrackedCylinders {
  std::vector<CylinderFit> fits;   // per caliper; not converged where neither fit held
  bool border = false;             // a slab left the image
  int samples = 0, saturated = 0;  // in the silhouettes' transitions, and clipped there
  int from_template = 0;
  int refused = 0;  // templates that refused the frame (cylinder_track.h), then fitted in full
  int fitted_in_full = 0;
};
TrackedCylinders TrackCylinders(const GreyImage& img, const AxisFrame& f, const ClipLevels& clip,
                                double band_s0_px, double spacing_px, int n,
                                CylinderMemory* memory);

}  // namespace clogscope::vision
