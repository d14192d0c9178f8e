#pragma once

// A step's feedstock result in the diameter table (CSV columns) and in JSON (diameters.json and the
// step files that --resume reads back).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/feedstock.h"

namespace clogscope::pipeline {

// filament_diameter_um, filament_diameter_ci95_um, filament_diameter_px, filament_n,
// filament_speed_mm_s, filament_speed_ci95_mm_s, gear_speed_mm_s, slip_pct, slip_ci95_pct, slip_n,
// feedstock_status, feedstock_detail. The predictor reads filament_diameter_um; drive, slip_pct.
const std::vector<std::string>& FeedstockColumns();
std::vector<std::string> FeedstockFields(const FeedstockResult& r);

nlohmann::json FeedstockJson(const FeedstockResult& r);
// Throws (nlohmann's exceptions or std::invalid_argument) when `j` is not one.
FeedstockResult FeedstockFromJson(const nlohmann::json& j);

}  // namespace clogscope::pipeline
