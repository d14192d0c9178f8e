#include "pipeline/step_file.h"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "common/csv.h"
#include "pipeline/feedstock_io.h"

namespace clogscope::pipeline {
namespace {

using nlohmann::json;

// Column positions in a frame's fields (FrameColumns()).
constexpr size_t kValidColumn = 3;
constexpr size_t kWidthColumn = 4;
// The frames' widths are written with 4 decimals: their mean matches the stored one to this.
constexpr double kMeanTolerancePx = 1e-3;

// What must match for a step file from an earlier run to stand for this one: the step, the
// sampling, how each frame was measured and how pixels became microns.
json MeasuredHow(const StepSpec& s, const ExperimentOptions& o) {
  const vision::StrandMeasureOptions& m = o.strand;
  json key = {{"step", s.step},
              {"temperature_c", s.temperature_c},
              {"video", s.video},
              {"images", s.images},
              {"start_s", s.start_s},
              {"end_s", s.end_s},
              {"settle_s", s.settle_s},
              {"samples", o.samples},
              {"outlier_mad_k", o.outlier_mad_k},
              {"roi", {m.roi.x, m.roi.y, m.roi.width, m.roi.height}},
              {"polarity", static_cast<int>(m.polarity)},
              {"target", static_cast<int>(m.target)},
              {"band_px", {m.band_start_px, m.band_height_px}},
              {"caliper_spacing_px", m.caliper_spacing_px},
              {"min_contrast_fraction", m.min_contrast_fraction},
              {"max_blur_px", m.max_blur_px},
              {"max_tilt_deg", m.max_tilt_deg},
              {"min_length_px", m.min_length_px},
              {"shading", m.shading},
              {"min_caliper_fraction", m.min_caliper_fraction},
              {"max_saturated_fraction", m.max_saturated_fraction}};
  if (o.feedstock && !s.feedstock_video.empty()) {
    const FeedstockOptions& f = *o.feedstock;
    const cv::Rect& r = f.strand.roi;
    json gear;
    if (f.gear) {
      const cv::Rect& g = f.gear->roi;
      gear = {g.x,
              g.y,
              g.width,
              g.height,
              f.gear_radius_mm,
              f.gear->centre_px ? json({f.gear->centre_px->x, f.gear->centre_px->y}) : json()};
    }
    key["feedstock"] = {{"video", s.feedstock_video},
                        {"pairs", f.pairs},
                        {"roi", {r.x, r.y, r.width, r.height}},
                        {"polarity", static_cast<int>(f.strand.polarity)},
                        {"gear", gear}};
    if (f.conversion) {
      const calib::ScaleCalibration& c = *f.conversion;
      key["feedstock"]["conversion"] = {c.method, c.scale_um_per_px, c.scale_sigma_um_per_px,
                                        c.edge_bias_px, c.edge_bias_sigma_px};
    }
  }
  if (o.conversion) {
    const calib::ScaleCalibration& c = *o.conversion;
    key["conversion"] = {c.method, c.scale_um_per_px, c.scale_sigma_um_per_px, c.edge_bias_px,
                         c.edge_bias_sigma_px};
  }
  return key;
}

// A number the result needs: finite (NaN only where `nan_ok`; JSON writes NaN as null).
double Number(const json& j, const char* key, bool nan_ok = false) {
  const json& v = j.at(key);
  if (v.is_null() && nan_ok) return NAN;
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw std::invalid_argument(fmt::format("{} is not finite", key));
  return x;
}

int Count(const json& j, const char* key) {
  const int n = j.at(key).get<int>();
  if (n < 0) throw std::invalid_argument(fmt::format("{} is negative", key));
  return n;
}

// Fills `r` from the JSON, or throws (nlohmann's exceptions or std::invalid_argument) saying why.
void Read(const json& j, const StepSpec& spec, const ExperimentOptions& o, StepResult* r) {
  if (j.at("spec") != MeasuredHow(spec, o))
    throw std::invalid_argument("measured another way (step, source, options or conversion)");
  r->spec = spec;
  r->status = model::ParseStepStatus(j.at("status").get<std::string>());
  if (r->status == model::StepStatus::kFailed)
    throw std::invalid_argument("the step failed last time");
  r->detail = j.at("detail").get<std::string>();
  r->n_examined = Count(j, "n_examined");
  r->n_valid = Count(j, "n_valid");
  r->n_used = Count(j, "n_used");
  r->n_rejected = Count(j, "n_rejected");
  r->mean_px = Number(j, "mean_px");
  r->std_px = Number(j, "std_px");
  r->has_um = j.at("has_um").get<bool>();
  r->mean_um = Number(j, "mean_um");
  r->std_um = Number(j, "std_um");
  r->sem_um = Number(j, "sem_um");
  r->cal_sigma_um = Number(j, "cal_sigma_um");
  r->ci95_um = Number(j, "ci95_um", /*nan_ok=*/r->n_used < 2);
  const size_t columns = FrameColumns().size();
  int valid = 0, used = 0;
  double sum_px = 0;
  for (const auto& f : j.at("frames")) {
    FrameRecord fr;
    fr.fields = f.at("fields").get<std::vector<std::string>>();
    fr.used = f.at("used").get<bool>();
    if (fr.fields.size() != columns) throw std::invalid_argument("a frame has the wrong columns");
    if (fr.fields[kValidColumn] == "1") ++valid;
    if (fr.used) {
      ++used;
      sum_px += ParseNumberField(fr.fields[kWidthColumn], "step file", "width_px");
    }
    r->frames.push_back(std::move(fr));
  }
  // The counts, the frames and the summary must tell the same story.
  if (r->n_examined != static_cast<int>(r->frames.size()) || r->n_valid != valid ||
      r->n_used != used || r->n_used + r->n_rejected != r->n_valid || r->n_used < 1 ||
      (r->status == model::StepStatus::kOk) != (r->n_valid >= o.samples))
    throw std::invalid_argument("its counts do not match its frames");
  if (!(r->mean_px > 0) || r->std_px < 0 || std::abs(sum_px / used - r->mean_px) > kMeanTolerancePx)
    throw std::invalid_argument("its mean does not match its frames");
  if (r->has_um != o.conversion.has_value() || r->std_um < 0 || r->sem_um < 0 ||
      r->cal_sigma_um < 0 || r->ci95_um < 0)
    throw std::invalid_argument("its spreads are inconsistent");
  if (j.contains("feedstock") && !j.at("feedstock").is_null()) {
    r->feedstock = FeedstockFromJson(j.at("feedstock"));
    if (r->feedstock->status == FeedstockStatus::kFailed)
      throw std::invalid_argument("the step's feedstock failed last time");
  }
  r->resumed = true;
}

}  // namespace

std::string StepFileName(int step) { return fmt::format("step_{:04d}.json", step); }

std::string StepFileText(const StepResult& r, const ExperimentOptions& o) {
  json frames = json::array();
  for (const auto& f : r.frames) frames.push_back({{"fields", f.fields}, {"used", f.used}});
  json j = {{"spec", MeasuredHow(r.spec, o)},
            {"line", r.spec.line},
            {"status", model::StepStatusName(r.status)},
            {"detail", r.detail},
            {"n_examined", r.n_examined},
            {"n_valid", r.n_valid},
            {"n_used", r.n_used},
            {"n_rejected", r.n_rejected},
            {"mean_px", r.mean_px},
            {"std_px", r.std_px},
            {"has_um", r.has_um},
            {"mean_um", r.mean_um},
            {"std_um", r.std_um},
            {"sem_um", r.sem_um},
            {"cal_sigma_um", r.cal_sigma_um},
            {"ci95_um", r.ci95_um},
            {"frames", frames}};
  if (r.feedstock) j["feedstock"] = FeedstockJson(*r.feedstock);
  // Replace invalid UTF-8 (say, from a file name) rather than throw.
  return j.dump(-1, ' ', false, json::error_handler_t::replace) + "\n";
}

bool ReadStepFile(const std::string& text, const StepSpec& spec, const ExperimentOptions& o,
                  StepResult* result, std::string* why) {
  StepResult r;
  try {
    Read(json::parse(text), spec, o, &r);
  } catch (const std::exception& e) {
    // nlohmann's messages name the JSON problem; ours say what does not add up.
    *why = e.what();
    return false;
  }
  *result = std::move(r);
  return true;
}

}  // namespace clogscope::pipeline
