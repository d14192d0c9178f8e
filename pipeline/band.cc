#include "pipeline/band.h"

#include <fmt/format.h>

#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace clogscope::pipeline {

namespace {

// The comma-separated whole numbers of `text`; nullopt when one is not a whole number.
std::optional<std::vector<int>> WholeNumbers(const std::string& text) {
  std::vector<int> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      v.push_back(std::stoi(item, &used));
      if (used != item.size()) return std::nullopt;
    } catch (const std::exception&) {
      return std::nullopt;
    }
  }
  return v;
}

}  // namespace

cv::Rect ParseRoi(const std::string& text) {
  const std::optional<std::vector<int>> v = WholeNumbers(text);
  if (!v || v->size() != 4)
    throw std::invalid_argument("--roi '" + text + "': expected x,y,w,h in whole px");
  const std::vector<int>& r = *v;
  if (r[0] < 0 || r[1] < 0 || r[2] <= 0 || r[3] <= 0)
    throw std::invalid_argument("--roi '" + text + "': x and y must be >= 0, w and h > 0");
  return cv::Rect(r[0], r[1], r[2], r[3]);
}

cv::Point ParsePoint(const std::string& text, const std::string& what) {
  const std::optional<std::vector<int>> v = WholeNumbers(text);
  if (!v || v->size() != 2 || (*v)[0] < 0 || (*v)[1] < 0)
    throw std::invalid_argument(what + " '" + text + "': expected x,y");
  return cv::Point((*v)[0], (*v)[1]);
}

BandRequest BandOver(const BandRequest& base, const BandRequest& top) {
  BandRequest out = base;
  if (top.start_um || top.start_px) {
    out.start_um = top.start_um;
    out.start_px = top.start_px;
    out.start_um_name = top.start_um_name;
    out.start_px_name = top.start_px_name;
  }
  if (top.height_um || top.height_px) {
    out.height_um = top.height_um;
    out.height_px = top.height_px;
    out.height_um_name = top.height_um_name;
    out.height_px_name = top.height_px_name;
  }
  return out;
}

BandResolution ResolveBandPx(const BandRequest& q, vision::MeasureTarget target,
                             std::optional<double> scale_um_per_px) {
  BandResolution r;
  const auto fail = [&](BandProblem p, const std::string& what) {
    r.problem = p;
    r.what = what;
    return r;
  };
  if (q.start_um && q.start_px)
    return fail(BandProblem::kBothUnits, q.start_um_name + " and " + q.start_px_name);
  if (q.height_um && q.height_px)
    return fail(BandProblem::kBothUnits, q.height_um_name + " and " + q.height_px_name);
  if (q.start_um && !scale_um_per_px)
    return fail(BandProblem::kMicronsWithoutScale, q.start_um_name);
  if (q.height_um && !scale_um_per_px)
    return fail(BandProblem::kMicronsWithoutScale, q.height_um_name);
  const double scale = scale_um_per_px.value_or(vision::kNominalScaleUmPerPx);
  const vision::BandPx fallback = vision::DefaultBand(target, scale);
  r.band.start_px = q.start_px ? *q.start_px : q.start_um ? *q.start_um / scale : fallback.start_px;
  r.band.height_px = q.height_px   ? *q.height_px
                     : q.height_um ? *q.height_um / scale
                                   : fallback.height_px;
  if (!(r.band.start_px >= 0))
    return fail(BandProblem::kNegativeStart, q.start_um ? q.start_um_name : q.start_px_name);
  if (!(r.band.height_px >= 4))
    return fail(BandProblem::kTooShort, q.height_um ? q.height_um_name : q.height_px_name);
  return r;
}

std::string BandProblemText(const BandResolution& r) {
  switch (r.problem) {
    case BandProblem::kNone:
      return "";
    case BandProblem::kMicronsWithoutScale:
      return r.what +
             ": a band in µm needs a pixel scale: --scale-um-per-px or --calib (in a manifest also "
             "scale_um_per_px: or calibration:), or give the band in px";
    case BandProblem::kBothUnits:
      return r.what + ": give each part of the band either in µm or in px, not both";
    case BandProblem::kNegativeStart:
      return fmt::format("{}: the band start ({:.2f} px) must not be negative", r.what,
                         r.band.start_px);
    case BandProblem::kTooShort:
      return fmt::format("{}: the band height ({:.2f} px) must be at least 4 px", r.what,
                         r.band.height_px);
  }
  return "";
}

void ApplyBandPx(const BandRequest& request,
                 const std::optional<calib::ScaleCalibration>& conversion,
                 vision::StrandMeasureOptions* strand) {
  const BandResolution r =
      ResolveBandPx(request, strand->target,
                    conversion ? std::optional(conversion->scale_um_per_px) : std::nullopt);
  if (r.problem != BandProblem::kNone) throw std::invalid_argument(BandProblemText(r));
  strand->band_start_px = r.band.start_px;
  strand->band_height_px = r.band.height_px;
}

}  // namespace clogscope::pipeline
