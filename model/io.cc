#include "model/io.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/csv.h"
#include "common/path_check.h"
#include "common/yaml_fields.h"
#include "model/step_status.h"

namespace clogscope::model {
namespace {

int ParseStep(const std::string& text, const std::string& where) {
  const double v = ParseNumberField(text, where, "step");
  if (v != std::floor(v))
    throw std::invalid_argument(fmt::format("{}: step '{}' is not a whole number", where, text));
  return static_cast<int>(v);
}

std::string Fmt(double v) { return fmt::format("{:.10g}", v); }

}  // namespace

std::vector<StepInput> ReadDiameterTable(const std::string& path, double default_temperature_c) {
  const CsvTable t = ParseCsv(ReadFile(path), path);
  const int c_step = t.Column("step"), c_mean = t.Column("mean_um"),
            c_temp = t.Column("temperature_c");
  if (c_mean < 0)
    throw std::invalid_argument(path + ": no mean_um column (the diameter table of measure)");
  if (t.rows.empty()) throw std::invalid_argument(path + ": no rows");
  const int c_status = t.Column("status");  // measure's table marks steps that failed: skipped
  const int c_filament = t.Column("filament_diameter_um");  // optional: measured feedstock
  std::vector<StepInput> steps;
  std::set<int> seen;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    const std::string where = fmt::format("{}:{}", path, t.row_line_numbers[i]);
    if (c_status >= 0 && row[c_status] == StepStatusName(StepStatus::kFailed)) continue;
    StepInput s;
    s.step = c_step >= 0 ? ParseStep(row[c_step], where) : static_cast<int>(i) + 1;
    s.source_line = t.row_line_numbers[i];
    s.diameter_m = ParseNumberField(row[c_mean], where, "mean_um") * 1e-6;
    s.temperature_c =
        c_temp >= 0 ? ParseNumberField(row[c_temp], where, "temperature_c") : default_temperature_c;
    if (c_filament >= 0 && !row[c_filament].empty()) {
      s.filament_diameter_m =
          ParseNumberField(row[c_filament], where, "filament_diameter_um") * 1e-6;
    }
    if (!seen.insert(s.step).second)
      throw std::invalid_argument(fmt::format("{}: step {} appears twice", where, s.step));
    steps.push_back(s);
  }
  if (steps.empty()) throw std::invalid_argument(path + ": no step has a diameter (all failed)");
  return steps;
}

std::vector<std::optional<double>> ReadStepColumn(const std::string& path,
                                                  const std::vector<StepInput>& steps,
                                                  const std::string& column) {
  const CsvTable t = ParseCsv(ReadFile(path), path);
  const int c = t.Column(column), c_step = t.Column("step");
  if (c < 0) return {};
  std::map<int, size_t> index;
  for (size_t i = 0; i < steps.size(); ++i) index[steps[i].step] = i;
  std::vector<std::optional<double>> out(steps.size());
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    const std::string where = fmt::format("{}:{}", path, t.row_line_numbers[i]);
    const int step = c_step >= 0 ? ParseStep(row[c_step], where) : static_cast<int>(i) + 1;
    const auto it = index.find(step);
    if (it == index.end() || row[c].empty()) continue;
    out[it->second] = ParseNumberField(row[c], where, column);
  }
  return out;
}

std::vector<Measurement> ReadMeasurements(const std::string& path,
                                          const std::vector<StepInput>& steps) {
  const CsvTable t = ParseCsv(ReadFile(path), path);
  const int c_step = t.Column("step"), c_temp = t.Column("temperature_c");
  const int c_amp = t.Column("amplitude_m_s2"), c_cur = t.Column("current_ma");
  if (c_amp < 0 && c_cur < 0)
    throw std::invalid_argument(path + ": needs an amplitude_m_s2 or current_ma column");
  if (c_step < 0 && c_temp < 0)
    throw std::invalid_argument(
        path + ": needs a step or temperature_c column to match the diameter table");
  std::vector<Measurement> out;
  for (size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    const std::string where = fmt::format("{}:{}", path, t.row_line_numbers[i]);
    Measurement m;
    m.source_line = t.row_line_numbers[i];
    if (c_step >= 0) {
      m.step = ParseStep(row[c_step], where);
    } else {
      const double temp = ParseNumberField(row[c_temp], where, "temperature_c");
      int matches = 0;
      for (const auto& s : steps) {
        if (std::abs(s.temperature_c - temp) < 1e-6) {
          m.step = s.step;
          ++matches;
        }
      }
      if (matches != 1) {
        throw std::invalid_argument(
            fmt::format("{}: temperature {:g} °C matches {} steps of the diameter table (need "
                        "exactly 1; add a step column)",
                        where, temp, matches));
      }
    }
    if (c_amp >= 0 && !row[c_amp].empty())
      m.amplitude_m_s2 = ParseNumberField(row[c_amp], where, "amplitude_m_s2");
    if (c_cur >= 0 && !row[c_cur].empty())
      m.current_ma = ParseNumberField(row[c_cur], where, "current_ma");
    out.push_back(m);
  }
  return out;
}

ExtruderParams ParseExtruderYaml(const std::string& text, const std::string& source) {
  const YAML::Node root = LoadYamlText(text, source);
  if (!root.IsMap())
    throw std::invalid_argument(source + ": expected a mapping of parameter names to values");
  // Values not in the file come from the preset it names (direct-pla when it names none).
  ExtruderParams p = ExtruderParams::Preset("direct-pla");
  if (root["preset"]) {
    const std::string preset = root["preset"].Scalar();
    try {
      p = ExtruderParams::Preset(preset);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument(fmt::format("{}:{}: preset '{}' is not direct-pla or bowden-pla",
                                              source, root["preset"].Mark().line + 1, preset));
    }
  }
  p.origin = source;
  for (const auto& kv : root) {
    const std::string key = kv.first.Scalar();
    const int line = kv.first.Mark().line + 1;
    if (key == "preset") continue;
    if (!kv.second.IsScalar()) {
      throw std::invalid_argument(
          fmt::format("{}:{}: {}: expected a single value", source, line, key));
    }
    try {
      p.SetByName(key, kv.second.Scalar());
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("{}:{}: {}", source, line, e.what()));
    }
  }
  return p;
}

ExtruderParams LoadExtruder(const std::string& preset_or_file) {
  for (const auto& name : ExtruderParams::PresetNames()) {
    if (preset_or_file == name) return ExtruderParams::Preset(name);
  }
  std::string why;
  if (InspectPath(preset_or_file, &why) == PathKind::kMissing)
    return ExtruderParams::Preset(preset_or_file);
  RequireInputPath("", preset_or_file, PathExpect::kPresetOrFile);
  return ParseExtruderYaml(ReadFile(preset_or_file), preset_or_file);
}

std::string ExtruderToYaml(const ExtruderParams& params, const Provenance& prov,
                           const std::vector<FittedValue>& fitted) {
  std::map<Param, const FittedValue*> fit;
  for (const auto& f : fitted) fit[f.param] = &f;
  std::string out =
      fmt::format("# clogscope {} extruder parameters ({})\n# created {}\n# command {}\n",
                  prov.version, params.origin, prov.created_utc, prov.command_line);
  out += fmt::format("load_model: {}\n", LoadModelName(params.load_model));
  for (const auto& info : AllParams()) {
    if (!params.Has(info.id)) continue;
    out += fmt::format("{}: {}", info.name, Fmt(params.Get(info.id)));
    const auto it = fit.find(info.id);
    if (it != fit.end()) out += fmt::format("  # fitted, sigma {}", Fmt(it->second->sigma));
    out += "\n";
  }
  return out;
}

std::string PredictionsCsv(const Prediction& pr, const Provenance& prov) {
  std::string out = ProvenanceCsvComment(prov);
  out +=
      "step,temperature_c,diameter_um,dp1_pa,dp2_pa,dp3_pa,dp_total_pa,f_bp_n,f_feed_n,load_n,"
      "relative_amplitude,amplitude_increase_pct,amplitude_m_s2,natural_frequency_hz,current_ma,"
      "buckling_ratio,filament_diameter_um\n";
  for (const auto& r : pr.steps) {
    out += CsvLine({std::to_string(r.step), Fmt(r.temperature_c), Fmt(r.diameter_um), Fmt(r.dp1_pa),
                    Fmt(r.dp2_pa), Fmt(r.dp3_pa), Fmt(r.dp_total_pa), Fmt(r.f_bp_n),
                    Fmt(r.f_feed_n), Fmt(r.load_n), Fmt(r.relative_amplitude),
                    Fmt(r.amplitude_increase_pct), r.amplitude_m_s2 ? Fmt(*r.amplitude_m_s2) : "",
                    Fmt(r.natural_frequency_hz), r.current_ma ? Fmt(*r.current_ma) : "",
                    r.buckling_ratio ? Fmt(*r.buckling_ratio) : "",
                    r.filament_diameter_um ? Fmt(*r.filament_diameter_um) : ""});
    out += "\n";
  }
  return out;
}

std::string PredictionsJson(const Prediction& pr, const ExtruderParams& params,
                            const Provenance& prov, const FitSummary* fit) {
  nlohmann::ordered_json j;
  j["provenance"] = {{"tool", "clogscope"},
                     {"version", prov.version},
                     {"created_utc", prov.created_utc},
                     {"command_line", prov.command_line}};
  nlohmann::ordered_json pj;
  pj["origin"] = params.origin;
  pj["load_model"] = LoadModelName(params.load_model);
  for (const auto& info : AllParams()) {
    if (params.Has(info.id)) pj[info.name] = params.Get(info.id);
  }
  j["parameters"] = pj;
  j["reference_load_n"] = pr.reference_load_n;
  j["feed_force_n"] = pr.feed_force_n;
  j["beam_frequency_hz"] = pr.beam_frequency_hz;
  j["gain_m_s2_per_n"] = pr.gain_m_s2_per_n ? nlohmann::ordered_json(*pr.gain_m_s2_per_n) : nullptr;
  j["gain_source"] = pr.gain_source;
  auto rows = nlohmann::ordered_json::array();
  auto opt = [](const std::optional<double>& v) {
    return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json();
  };
  for (const auto& r : pr.steps) {
    rows.push_back({{"step", r.step},
                    {"temperature_c", r.temperature_c},
                    {"diameter_um", r.diameter_um},
                    {"dp1_pa", r.dp1_pa},
                    {"dp2_pa", r.dp2_pa},
                    {"dp3_pa", r.dp3_pa},
                    {"dp_total_pa", r.dp_total_pa},
                    {"f_bp_n", r.f_bp_n},
                    {"f_feed_n", r.f_feed_n},
                    {"load_n", r.load_n},
                    {"relative_amplitude", r.relative_amplitude},
                    {"amplitude_increase_pct", r.amplitude_increase_pct},
                    {"amplitude_m_s2", opt(r.amplitude_m_s2)},
                    {"natural_frequency_hz", r.natural_frequency_hz},
                    {"current_ma", opt(r.current_ma)},
                    {"buckling_ratio", opt(r.buckling_ratio)},
                    {"filament_diameter_um", opt(r.filament_diameter_um)}});
  }
  j["steps"] = rows;
  if (fit) {
    nlohmann::ordered_json fj;
    fj["usable"] = fit->usable;
    fj["message"] = fit->message;
    fj["rms_relative"] = fit->rms_relative;
    fj["worst_relative"] = fit->worst_relative;
    fj["iterations"] = fit->iterations;
    auto vals = nlohmann::ordered_json::array();
    for (const auto& v : fit->values) {
      vals.push_back({{"name", InfoOf(v.param).name},
                      {"initial", v.initial},
                      {"value", v.value},
                      {"sigma", std::isfinite(v.sigma) ? nlohmann::ordered_json(v.sigma)
                                                       : nlohmann::ordered_json()},
                      {"at_bound", v.at_bound}});
    }
    fj["values"] = vals;
    auto res = nlohmann::ordered_json::array();
    for (const auto& r : fit->residuals) {
      res.push_back({{"step", r.step},
                     {"quantity", r.quantity},
                     {"measured", r.measured},
                     {"model", r.model},
                     {"relative", r.relative}});
    }
    fj["residuals"] = res;
    j["fit"] = fj;
  }
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace clogscope::model
