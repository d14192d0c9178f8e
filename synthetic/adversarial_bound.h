#pragma once

#include "synthetic/adversarial.h"

namespace clogscope::synthetic {

// The Cramér–Rao bound on an adversarial scene's strand width (px): the smallest σ an unbiased
// measurement of the width over the reference band (kBandLengthUm) could have, given the camera's
// blur and noise and the strand's cross-section (shading, lens, stripe) as the renderer draws it,
// with the background's level, the strand's brightness, the blur and the axis's place unknown.
// It is a lower bound: it knows the cross-section's shape, which no measurement does, and leaves
// out what only adds doubt (the codec, demosaicing's correlations, a stringer, a spot, a background
// slope, blur growing down the frame beyond its value at the tip). A colour scene's pixels each
// hold one channel of the Bayer mosaic. Clipped pixels tell nothing. Infinite when nothing in the
// band depends on the width.
double WidthBoundSigmaPx(const AdversarialScene& scene, double width_px);

}  // namespace clogscope::synthetic
