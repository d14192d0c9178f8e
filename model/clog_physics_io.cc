#include "model/clog_physics_io.h"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "common/csv.h"

namespace clogscope::model {
namespace {

using Json = nlohmann::ordered_json;

Json ProvenanceJson(const Provenance& p) {
  return {{"tool", "clogscope"},
          {"version", p.version},
          {"created_utc", p.created_utc},
          {"command_line", p.command_line}};
}

// NaN has no JSON form: null.
Json Number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

std::string Cell(double v, int decimals) { return CsvNumber(v, decimals); }

}  // namespace

std::string ThermalJson(const std::vector<ThermalAssessment>& assessments,
                        const std::vector<SofteningStep>& softening,
                        const std::optional<SofteningOptions>& so, const Provenance& prov) {
  Json j;
  j["provenance"] = ProvenanceJson(prov);
  j["source"] = "hot-end cooling study (E3D-like Diamond hot end), docs/clog-physics.md §1";
  Json list = Json::array();
  for (const auto& a : assessments) {
    const auto& d = CoolingDataOf(a.material);
    list.push_back({{"material", MaterialName(a.material)},
                    {"fan_velocity_m_s", a.velocity_m_s},
                    {"t4_c", a.t4_c},
                    {"risk", ClogRiskName(a.risk)},
                    {"extrapolated", a.extrapolated},
                    {"tested_velocity_m_s", {d.min_tested_velocity_m_s, d.max_tested_velocity_m_s}},
                    {"criterion_t4_below_c", d.safe_below_t4_c},
                    {"clog_risk_from_t4_c", d.ClogRiskFromT4C()},
                    {"min_safe_velocity_m_s", a.min_safe_velocity_m_s},
                    {"explanation", a.explanation}});
  }
  j["assessments"] = list;
  if (so) {
    j["softening"] = {{"filament_modulus_pa", so->modulus_pa},
                      {"melt_viscosity_pa_s", so->viscosity_pa_s}};
    Json rows = Json::array();
    for (const auto& r : softening) {
      rows.push_back({{"step", r.step},
                      {"temperature_c", r.temperature_c},
                      {"diameter_um", r.diameter_um},
                      {"dp_hagen_poiseuille_pa", r.dp_hagen_poiseuille_pa},
                      {"l_crt_hagen_poiseuille_mm", r.l_crt_hagen_poiseuille_mm},
                      {"dp_power_law_pa", r.dp_power_law_pa},
                      {"l_crt_power_law_mm", r.l_crt_power_law_mm}});
    }
    j["softening"]["steps"] = rows;
  }
  return j.dump(2) + "\n";
}

std::string SofteningCsv(const std::vector<SofteningStep>& rows, const Provenance& prov) {
  std::string out = ProvenanceCsvComment(prov);
  out +=
      "step,temperature_c,diameter_um,dp_hagen_poiseuille_pa,l_crt_hagen_poiseuille_mm,"
      "dp_power_law_pa,l_crt_power_law_mm\n";
  for (const auto& r : rows) {
    out += CsvLine({std::to_string(r.step), Cell(r.temperature_c, 2), Cell(r.diameter_um, 3),
                    Cell(r.dp_hagen_poiseuille_pa, 1), Cell(r.l_crt_hagen_poiseuille_mm, 4),
                    Cell(r.dp_power_law_pa, 1), Cell(r.l_crt_power_law_mm, 4)}) +
           "\n";
  }
  return out;
}

std::string DriveCsv(const DrivePrediction& d, const Provenance& prov) {
  std::string out = ProvenanceCsvComment(prov);
  out +=
      "step,temperature_c,diameter_um,f_bp_n,feed_force_n,slip_pct,slip_sigma_pct,"
      "slip_velocity_form_pct,commanded_flow_mm3_s,delivered_flow_mm3_s,measured_slip_pct\n";
  for (const auto& s : d.steps) {
    out += CsvLine({std::to_string(s.step), Cell(s.temperature_c, 2), Cell(s.diameter_um, 3),
                    Cell(s.f_bp_n, 4), Cell(s.feed_force_n, 4), Cell(s.slip_pinch.pct, 4),
                    Cell(s.slip_pinch.sigma_pct, 4), Cell(s.slip_velocity.pct, 4),
                    Cell(s.commanded_flow_mm3_s, 5), Cell(s.delivered_flow_mm3_s, 5),
                    CsvNumber(s.measured_slip_pct, 4)}) +
           "\n";
  }
  return out;
}

std::string DriveJson(const DrivePrediction& d, const DriveOptions& o, const Provenance& prov) {
  Json j;
  j["provenance"] = ProvenanceJson(prov);
  j["source"] = "roller filament drive study (PLA, seven rollers), docs/clog-physics.md §2";
  const auto& r = d.roller;
  j["roller"] = {{"name", r.name},
                 {"outer_diameter_mm", r.outer_diameter_mm},
                 {"k_s_pct_n", r.k_s_pct_n},
                 {"k_s_sigma_pct_n", r.k_s_sigma_pct_n},
                 {"k_pct_per_n", r.k_pct_per_n},
                 {"k_sigma_pct_per_n", r.k_sigma_pct_per_n},
                 {"min_pinch_force_n", d.min_pinch.computed_n},
                 {"min_pinch_force_sigma_n", d.min_pinch.sigma_n},
                 {"min_pinch_force_printed_n", d.min_pinch.printed_n},
                 {"min_pinch_force_agrees", d.min_pinch.agrees}};
  j["pinch_force_n"] = o.pinch_force_n;
  j["pinch_below_minimum"] = d.pinch_below_minimum;
  j["friction_n"] = o.friction_n;
  j["k_p_pct"] = o.k_p_pct;
  j["filament_speed_mm_s"] = d.filament_speed_mm_s;
  j["velocity_form_extrapolated"] = d.velocity_form_extrapolated;
  Json steps = Json::array();
  for (const auto& s : d.steps) {
    Json row = {{"step", s.step},
                {"temperature_c", s.temperature_c},
                {"diameter_um", s.diameter_um},
                {"f_bp_n", s.f_bp_n},
                {"feed_force_n", s.feed_force_n},
                {"slip_pct", s.slip_pinch.pct},
                {"slip_sigma_pct", s.slip_pinch.sigma_pct},
                {"slip_velocity_form_pct", s.slip_velocity.pct},
                {"commanded_flow_mm3_s", s.commanded_flow_mm3_s},
                {"delivered_flow_mm3_s", s.delivered_flow_mm3_s}};
    if (s.measured_slip_pct) row["measured_slip_pct"] = *s.measured_slip_pct;
    steps.push_back(row);
  }
  j["steps"] = steps;
  return j.dump(2) + "\n";
}

std::string LagFitJson(const LagFitSummary& f, const std::string& unit, const Provenance& prov) {
  Json j;
  j["provenance"] = ProvenanceJson(prov);
  j["source"] = "pressure-advance study: width = gain · Q_out(t − offset), docs/clog-physics.md §3";
  j["usable"] = f.usable;
  j["message"] = f.message;
  j["k_s"] = f.k_s;
  j["k_sigma_s"] = Number(f.k_sigma_s);
  j["k_la_to_set_s"] = f.k_la_s;
  j["gain_" + unit + "_per_mm3_s"] = f.gain;
  j["gain_sigma_" + unit + "_per_mm3_s"] = Number(f.gain_sigma);
  j["offset_s"] = f.offset_s;
  j["offset_sigma_s"] = Number(f.offset_sigma_s);
  j["rms_" + unit] = f.rms;
  j["worst_residual_" + unit] = f.worst_residual;
  j["worst_residual_time_s"] = f.worst_time_s;
  j["frames_used"] = f.samples_used;
  j["frames_total"] = f.samples_total;
  j["outliers"] = f.outliers;
  j["iterations"] = f.iterations;
  j["solver"] = f.solver_report;
  return j.dump(2) + "\n";
}

std::string LagFitCsv(const FlowProfile& p, const std::vector<WidthSample>& s,
                      const LagFitSummary& f, const std::string& unit, const Provenance& prov) {
  std::vector<double> shifted;
  for (const auto& x : s) shifted.push_back(x.time_s - f.offset_s);
  const auto q = OutletFlow(p, f.k_s, 0.0, shifted);
  std::string out = ProvenanceCsvComment(prov);
  out += fmt::format(
      "time_s,width_{0},fitted_width_{0},outlet_flow_mm3_s,commanded_flow_mm3_s,outlier\n", unit);
  for (size_t i = 0; i < s.size(); ++i) {
    out += CsvLine({Cell(s[i].time_s, 6), Cell(s[i].width, 4), Cell(f.fitted_width[i], 4),
                    Cell(q[i], 5), Cell(p.At(shifted[i]), 5), f.outlier[i] ? "1" : "0"}) +
           "\n";
  }
  return out;
}

std::string LagSimulationCsv(const FlowProfile& p, const std::vector<double>& t,
                             const std::vector<double>& outlet, const std::vector<double>& with_la,
                             const Provenance& prov) {
  std::string out = ProvenanceCsvComment(prov);
  out += "time_s,commanded_flow_mm3_s,outlet_flow_mm3_s";
  out += with_la.empty() ? "\n" : ",outlet_flow_linear_advance_mm3_s\n";
  for (size_t i = 0; i < t.size(); ++i) {
    std::vector<std::string> row = {Cell(t[i], 6), Cell(p.At(t[i]), 5), Cell(outlet[i], 5)};
    if (!with_la.empty()) row.push_back(Cell(with_la[i], 5));
    out += CsvLine(row) + "\n";
  }
  return out;
}

}  // namespace clogscope::model
