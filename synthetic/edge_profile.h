#pragma once

namespace clogscope::synthetic {

// Standard normal CDF.
double NormalCdf(double z);

// Mean over one pixel of a Gaussian-blurred straight step edge, exactly.
//
// The step is 1 where the signed distance t (px, along the edge normal, from the pixel centre to
// the edge... measured so that t > 0 is inside) is positive, blurred by an isotropic Gaussian PSF
// of sigma_px (0 allowed: a hard edge). The pixel is a unit square whose projection onto the edge
// normal is the convolution of two boxes of widths |nx| and |ny| (nx² + ny² = 1). The mean is then
// a second difference of the second antiderivative of the blurred step, evaluated in closed form,
// so the rendered edge is exact to rounding error for any tilt and blur.
double PixelMeanOfBlurredStep(double t_px, double sigma_px, double nx, double ny);

}  // namespace clogscope::synthetic
