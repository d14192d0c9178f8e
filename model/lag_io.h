#pragma once

// Files of the extrusion-lag command: the commanded profile and measure's per-frame table.
#include <string>
#include <vector>

#include "model/extrusion_lag.h"
#include "model/lag_fit.h"

namespace clogscope::model {

enum class ProfileForm {
  kMoves,   // each row's flow holds until the next row's time (G-code moves)
  kLinear,  // linear between rows; two rows at one time make a step
};
// "moves" or "linear"; throws std::invalid_argument otherwise.
ProfileForm ParseProfileForm(const std::string& name);

// CSV with time_s and either flow_mm3_s or filament_speed_mm_s (converted with the filament
// diameter). Throws std::invalid_argument naming the file and line of a bad row.
FlowProfile ReadFlowProfile(const std::string& path, ProfileForm form, double filament_diameter_mm);

// measure's frames CSV: time_s and width_um when every valid row has it, else width_px; rows not
// valid are skipped. Throws std::invalid_argument naming the file for a missing column, more than
// one source in one table, or a bad number.
struct WidthSeries {
  std::vector<WidthSample> samples;
  std::string unit;  // "um" or "px"
  int rows = 0;      // frames in the table
  int skipped = 0;   // not valid
};
WidthSeries ReadWidthSeries(const std::string& path);

}  // namespace clogscope::model
