#pragma once

#include "synthetic/adversarial.h"

namespace clogscope::synthetic {

// The Cramér–Rao bound on an adversarial scene's strand width (px) for a measurement that reads
// each edge from its transition, as calipers do: the smallest σ an unbiased such measurement of
// the width over the reference band (vision::DefaultBand) could have, given the camera's blur and
// noise and the strand's cross-section (shading, lens, stripe) as the renderer draws it, with the
// background's level, the strand's brightness, the blur and both edges' places unknown. Each edge
// is read from the pixels within its transition (3 blurs and 2.5 px): the light further in (a lit
// cylinder's ramp, a lens's core) is taken as the strand's own unknown, not as a ruler. Within
// that, it is a lower bound: it knows the cross-section's shape, which no measurement does, and
// leaves out what only adds doubt (the codec, demosaicing's correlations, a stringer, a spot, a
// background slope, blur growing down the frame beyond its value at the tip). For strands wider
// than their two transitions (the matrix's are). A colour scene's pixels each hold one channel of
// the Bayer mosaic. Clipped pixels tell nothing. Infinite when nothing in the band depends on the
// width.
double WidthBoundSigmaPx(const AdversarialScene& scene, double width_px);

}  // namespace clogscope::synthetic
