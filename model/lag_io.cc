#include "model/lag_io.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/csv.h"

namespace clogscope::model {

ProfileForm ParseProfileForm(const std::string& name) {
  if (name == "moves") return ProfileForm::kMoves;
  if (name == "linear") return ProfileForm::kLinear;
  throw std::invalid_argument("profile form '" + name + "': expected moves or linear");
}

FlowProfile ReadFlowProfile(const std::string& path, ProfileForm form,
                            double filament_diameter_mm) {
  const CsvTable t = ParseCsv(ReadFile(path), path);
  const int c_time = t.Column("time_s");
  const int c_flow = t.Column("flow_mm3_s"), c_speed = t.Column("filament_speed_mm_s");
  if (c_time < 0 || (c_flow < 0) == (c_speed < 0)) {
    throw std::invalid_argument(
        path + ": needs a time_s column and one of flow_mm3_s or filament_speed_mm_s");
  }
  if (t.rows.empty()) throw std::invalid_argument(path + ": no rows");
  const double area_mm2 = M_PI * filament_diameter_mm * filament_diameter_mm / 4;
  std::vector<double> time, flow;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const std::string where = fmt::format("{}:{}", path, t.row_line_numbers[i]);
    time.push_back(ParseNumberField(t.rows[i][c_time], where, "time_s"));
    flow.push_back(c_flow >= 0 ? ParseNumberField(t.rows[i][c_flow], where, "flow_mm3_s")
                               : area_mm2 * ParseNumberField(t.rows[i][c_speed], where,
                                                             "filament_speed_mm_s"));
    if (i > 0 && (form == ProfileForm::kMoves ? !(time[i] > time[i - 1]) : time[i] < time[i - 1])) {
      throw std::invalid_argument(
          fmt::format("{}: time {:g} s does not {} (previous {:g} s)", where, time[i],
                      form == ProfileForm::kMoves ? "increase" : "ascend", time[i - 1]));
    }
  }
  if (form == ProfileForm::kMoves) return ProfileFromMoves(time, flow);
  return FlowProfile{time, flow};
}

WidthSeries ReadWidthSeries(const std::string& path) {
  const CsvTable t = ParseCsv(ReadFile(path), path);
  const int c_time = t.Column("time_s"), c_valid = t.Column("valid");
  const int c_px = t.Column("width_px"), c_um = t.Column("width_um");
  const int c_source = t.Column("source");
  if (c_time < 0 || c_px < 0) {
    throw std::invalid_argument(path +
                                ": needs time_s and width_px columns (measure's frames CSV)");
  }
  WidthSeries out;
  out.rows = static_cast<int>(t.rows.size());
  std::vector<const std::vector<std::string>*> valid;
  std::vector<std::string> wheres;
  bool all_um = c_um >= 0;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    if (c_source >= 0 && row[c_source] != t.rows[0][c_source]) {
      throw std::invalid_argument(
          fmt::format("{}:{}: a second source '{}' (after '{}'): give one video's frames", path,
                      t.row_line_numbers[i], row[c_source], t.rows[0][c_source]));
    }
    const bool ok = (c_valid < 0 || row[c_valid] == "1") && !row[c_px].empty();
    if (!ok) {
      ++out.skipped;
      continue;
    }
    valid.push_back(&row);
    wheres.push_back(fmt::format("{}:{}", path, t.row_line_numbers[i]));
    all_um = all_um && !row[c_um].empty();
  }
  out.unit = all_um ? "um" : "px";
  const int c_width = all_um ? c_um : c_px;
  for (size_t i = 0; i < valid.size(); ++i) {
    const auto& row = *valid[i];
    out.samples.push_back(
        {ParseNumberField(row[c_time], wheres[i], "time_s"),
         ParseNumberField(row[c_width], wheres[i], all_um ? "width_um" : "width_px")});
  }
  return out;
}

}  // namespace clogscope::model
