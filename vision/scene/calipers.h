#pragma once

#include "vision/edges/grey_image.h"
#include "vision/scene/scene.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::vision {

class CylinderMemory;

// The precise half of the measurement: cuts [band_s0_px, band_s1_px) of the strand `g` (px along
// its axis from g's origin) into calipers, fits both edges in each on the pixels themselves, fits
// parallel edge lines and combines the calipers' widths. Fills the width, its σ, angle, contrast,
// blur, calipers and overlay geometry of *m, and its status (kValid, or why not: touches_border,
// saturated, occluded, low_contrast, out_of_focus). `data_max` is the largest value the data can
// hold (255 for 8 bit, 4095 for 12-bit data in 16-bit frames).
// With a memory (tracking a lit object), its calipers' lit cylinders are fitted from the templates
// the memory holds where they hold, and the full fits keep templates there (cylinder_memory.h).
void MeasureCalipers(const GreyImage& img, double data_max, const StrandGeometry& g,
                     double band_s0_px, double band_s1_px, const StrandMeasureOptions& opt,
                     StrandMeasurement* m, CylinderMemory* memory = nullptr);

}  // namespace clogscope::vision
