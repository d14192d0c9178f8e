#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "synthetic/adversarial.h"

namespace clogscope::synthetic {

// The adversarial strand's cross-section, shared by the renderer (adversarial.cc) and the
// Cramér–Rao bound (adversarial_bound.h). x is the place across the strand in half widths from its
// axis (|x| < 1 inside).

// A transparent cylinder on a backlight seen through a lens of finite aperture: a ray crossing
// the cylinder at x = u/R (|x| < 1) leaves deviated by δ = 2(asin x − asin(x/n)). It reaches the
// sensor from the backlight only while δ is within the optics' acceptance; outside, the rim shows
// only scattered light (the rim floor). Fresnel losses take ~8 %.
double LensTransmission(double x, double n, double acceptance_rad, double floor);

// An opaque strand's own light at x (8-bit grey levels): a lit cylinder, from the ambient share at
// its rims to its full level where its surface faces the lamp (x = sin light_deg; flat when
// shading_ambient is 1); past the terminator, the ambient share alone.
double StrandEmission(const AdversarialScene& p, double x);

// The camera's blur and pixels on a layer rendered at `oversample` samples per pixel along each
// axis (CV_32F): a Gaussian of sigma_hi_px (hi-res px), then the mean of each oversample ×
// oversample block of samples. The numbers of cv::GaussianBlur (its kernel and reflected border)
// followed by cv::resize with INTER_AREA, computed at the output pixels only: a quarter of the
// work of blurring every sample. With `bottom_weight` (one per hi-res row, 0..1), hi-res row Y is
// (1 − w) times that blur plus w times a blur of sigma_bottom_hi_px: blur growing down the frame.
cv::Mat BlurAndBin(const cv::Mat& hires, int oversample, double sigma_hi_px,
                   double sigma_bottom_hi_px = 0, const std::vector<float>& bottom_weight = {});

// A colour scene: an orange strand (and nozzle) on a blue background, the light of each
// multiplied by these per channel (B, G, R).
inline constexpr double kStrandTint[3] = {0.3, 0.65, 1.0}, kBackgroundTint[3] = {1.0, 0.6, 0.25};

// The frames are 8 bit: a pixel's value is rounded and clipped to 0..kFullScale.
inline constexpr double kFullScale = 255.0;

// The camera's noise: read noise plus shot noise growing with the signal, a pixel of radiance r
// (8-bit grey levels) drawing noise of variance noise_sigma² (kReadShare + r/255)/(kReadShare + 1)
// (noise_sigma is the noise at 255, and 0.58 of it at black).
inline constexpr double kReadShare = 0.5;
inline double NoiseVariance(double noise_sigma, double radiance) {
  return noise_sigma * noise_sigma * (kReadShare + radiance / 255.0) / (kReadShare + 1.0);
}

}  // namespace clogscope::synthetic
