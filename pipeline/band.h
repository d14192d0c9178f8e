#pragma once

#include <optional>
#include <string>

#include "calib/pixel_scale.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::pipeline {

// "x,y,w,h" (a --roi, or a manifest's roi:) -> rectangle; throws std::invalid_argument naming
// --roi on a malformed value.
cv::Rect ParseRoi(const std::string& text);

// "x,y" in whole px, both >= 0 (a --gear-centre, or a feedstock's gear_centre:) -> point; throws
// std::invalid_argument "WHAT 'text': expected x,y" on anything else.
cv::Point ParsePoint(const std::string& text, const std::string& what);

// The reference band as asked for: its start (below the tip) and its height, each in µm or in px
// or not at all, with the names to give them in messages (options, or manifest keys).
struct BandRequest {
  std::optional<double> start_um, height_um, start_px, height_px;
  std::string start_um_name = "--band-start-um", height_um_name = "--band-height-um";
  std::string start_px_name = "--band-start-px", height_px_name = "--band-height-px";
};

// `top`'s start where it asks for one, else `base`'s; the same for the height.
BandRequest BandOver(const BandRequest& base, const BandRequest& top);

// Why a band cannot be used. Messages are made from it (BandProblemText), never parsed.
enum class BandProblem { kNone, kMicronsWithoutScale, kBothUnits, kNegativeStart, kTooShort };

struct BandResolution {
  BandProblem problem = BandProblem::kNone;
  std::string what;     // the option or key at fault
  vision::BandPx band;  // in px: what was asked, the target's default for the rest
};

// The band in px: parts in px as they are, parts in µm through the scale, the rest the target's
// default (at the nominal 3 µm/px without a scale). A part in µm without a scale is a problem, not
// an assumed scale.
BandResolution ResolveBandPx(const BandRequest& request, vision::MeasureTarget target,
                             std::optional<double> scale_um_per_px);

// The one line for a problem: "WHAT: a band in µm needs a pixel scale (…)".
std::string BandProblemText(const BandResolution& r);

// ResolveBandPx for strand->target at the conversion's scale (none: no scale), into the strand's
// band fields; a problem throws std::invalid_argument with its BandProblemText.
void ApplyBandPx(const BandRequest& request,
                 const std::optional<calib::ScaleCalibration>& conversion,
                 vision::StrandMeasureOptions* strand);

}  // namespace clogscope::pipeline
