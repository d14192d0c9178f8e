#include "pipeline/feedstock_io.h"

#include <cmath>
#include <stdexcept>

#include "common/csv.h"
#include "pipeline/experiment.h"

namespace clogscope::pipeline {
namespace {

using nlohmann::json;

std::string Cell(const std::optional<double>& v, int digits) {
  return v ? CsvNumber(*v, digits) : std::string();
}

json Optional(const std::optional<double>& v) { return v ? json(*v) : json(); }

std::optional<double> ReadOptional(const json& j, const char* key) {
  const json& v = j.at(key);
  if (v.is_null()) return std::nullopt;
  const double x = v.get<double>();
  if (!std::isfinite(x)) throw std::invalid_argument(std::string(key) + " is not finite");
  return x;
}

}  // namespace

const std::vector<std::string>& FeedstockColumns() {
  static const std::vector<std::string> c = {"filament_diameter_um", "filament_diameter_ci95_um",
                                             "filament_diameter_px", "filament_n",
                                             "filament_speed_mm_s",  "filament_speed_ci95_mm_s",
                                             "gear_speed_mm_s",      "slip_pct",
                                             "slip_ci95_pct",        "slip_n",
                                             "feedstock_status",     "feedstock_detail"};
  return c;
}

std::vector<std::string> FeedstockFields(const FeedstockResult& r) {
  const bool have = r.n_diameter > 0;
  return {have && r.has_um ? CsvNumber(r.diameter_um, kTableUmDecimals) : "",
          have && r.has_um ? CsvNumber(r.diameter_ci95_um, 3) : "",
          have ? CsvNumber(r.diameter_px, 4) : "",
          std::to_string(r.n_diameter),
          Cell(r.speed_mm_s, 5),
          Cell(r.speed_ci95_mm_s, 5),
          Cell(r.gear_mm_s, 5),
          Cell(r.slip_pct, 3),
          Cell(r.slip_ci95_pct, 3),
          std::to_string(r.n_slip),
          FeedstockStatusName(r.status),
          r.detail};
}

json FeedstockJson(const FeedstockResult& r) {
  return {{"status", FeedstockStatusName(r.status)},
          {"detail", r.detail},
          {"video", r.video},
          {"n_pairs", r.n_pairs},
          {"n_diameter", r.n_diameter},
          {"diameter_px", r.diameter_px},
          {"diameter_std_px", r.diameter_std_px},
          {"has_um", r.has_um},
          {"diameter_um", r.diameter_um},
          {"diameter_ci95_um", r.diameter_ci95_um},
          {"n_speed", r.n_speed},
          {"n_gear", r.n_gear},
          {"n_slip", r.n_slip},
          {"speed_mm_s", Optional(r.speed_mm_s)},
          {"speed_ci95_mm_s", Optional(r.speed_ci95_mm_s)},
          {"gear_mm_s", Optional(r.gear_mm_s)},
          {"gear_ci95_mm_s", Optional(r.gear_ci95_mm_s)},
          {"slip_pct", Optional(r.slip_pct)},
          {"slip_ci95_pct", Optional(r.slip_ci95_pct)}};
}

FeedstockResult FeedstockFromJson(const json& j) {
  FeedstockResult r;
  r.status = ParseFeedstockStatus(j.at("status").get<std::string>());
  r.detail = j.at("detail").get<std::string>();
  r.video = j.at("video").get<std::string>();
  r.n_pairs = j.at("n_pairs").get<int>();
  r.n_diameter = j.at("n_diameter").get<int>();
  r.diameter_px = j.at("diameter_px").get<double>();
  r.diameter_std_px = j.at("diameter_std_px").get<double>();
  r.has_um = j.at("has_um").get<bool>();
  r.diameter_um = j.at("diameter_um").get<double>();
  r.diameter_ci95_um =
      j.at("diameter_ci95_um").is_null() ? NAN : j.at("diameter_ci95_um").get<double>();
  r.n_speed = j.at("n_speed").get<int>();
  r.n_gear = j.at("n_gear").get<int>();
  r.n_slip = j.at("n_slip").get<int>();
  r.speed_mm_s = ReadOptional(j, "speed_mm_s");
  r.speed_ci95_mm_s = ReadOptional(j, "speed_ci95_mm_s");
  r.gear_mm_s = ReadOptional(j, "gear_mm_s");
  r.gear_ci95_mm_s = ReadOptional(j, "gear_ci95_mm_s");
  r.slip_pct = ReadOptional(j, "slip_pct");
  r.slip_ci95_pct = ReadOptional(j, "slip_ci95_pct");
  if (r.n_pairs < 0 || r.n_diameter < 0 || r.n_diameter > r.n_pairs || r.n_slip < 0 ||
      (r.n_diameter > 0 && !(r.diameter_px > 0)))
    throw std::invalid_argument("its feedstock counts do not add up");
  return r;
}

}  // namespace clogscope::pipeline
