#include "apps/thermal_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <stdexcept>

#include "apps/cli_util.h"
#include "common/atomic_file.h"
#include "common/provenance.h"
#include "model/clog_physics_io.h"
#include "model/io.h"
#include "model/prediction_run.h"

namespace clogscope::apps {
namespace {

namespace fs = std::filesystem;

void PrintAssessment(const model::ThermalAssessment& a) {
  const auto& d = model::CoolingDataOf(a.material);
  fmt::print("{} at {:.3f} m/s: T4 {:.1f} °C — {}\n  {}\n  safe (T4 < {:g} °C) from {:.3f} m/s{}\n",
             model::MaterialName(a.material), a.velocity_m_s, a.t4_c, model::ClogRiskName(a.risk),
             a.explanation, d.safe_below_t4_c, a.min_safe_velocity_m_s,
             a.extrapolated ? fmt::format("\n  EXTRAPOLATED: the study tested {:g}…{:g} m/s",
                                          d.min_tested_velocity_m_s, d.max_tested_velocity_m_s)
                            : "");
}

void PrintSoftening(const ThermalReport& r) {
  fmt::print(
      "critical softened length L_crt = √(π² E R² / (4 ΔP)), E {:g} Pa; ΔP by Hagen–Poiseuille "
      "(μ {:g} Pa·s) and by ClogScope's power law:\n",
      r.softening_options->modulus_pa, r.softening_options->viscosity_pa_s);
  fmt::print("{:>4} {:>7} {:>9} {:>12} {:>12} {:>12} {:>12}\n", "step", "T °C", "D µm", "ΔP_HP kPa",
             "L_crt HP mm", "ΔP_PL kPa", "L_crt PL mm");
  for (const auto& s : r.softening) {
    fmt::print("{:>4} {:>7.1f} {:>9.1f} {:>12.1f} {:>12.2f} {:>12.1f} {:>12.2f}\n", s.step,
               s.temperature_c, s.diameter_um, s.dp_hagen_poiseuille_pa / 1e3,
               s.l_crt_hagen_poiseuille_mm, s.dp_power_law_pa / 1e3, s.l_crt_power_law_mm);
  }
}

}  // namespace

bool ThermalCommandOptions::Validate(std::string* why) const {
  try {
    model::ParseMaterial(material);
  } catch (const std::invalid_argument& e) {
    *why = std::string("--material: ") + e.what();
    return false;
  }
  if (fan_velocity_m_s.empty() && t4_c.empty() && diameters.empty())
    *why = "give --fan-velocity-m-s, --t4-c or --diameters";
  else if (filament_modulus_pa && !(*filament_modulus_pa > 0))
    *why = "--filament-modulus-pa must be positive";
  else if (viscosity_pa_s && !(*viscosity_pa_s > 0))
    *why = "--viscosity-pa-s must be positive";
  else if (hp_length_mm && !(*hp_length_mm > 0))
    *why = "--hp-length-mm must be positive";
  else if (!CheckTableAndExtruderPaths(diameters, extruder, why))
    return false;
  else
    return true;
  return false;
}

ThermalReport ComputeThermal(const ThermalCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  const model::Material m = model::ParseMaterial(o.material);
  ThermalReport r;
  for (double v : o.fan_velocity_m_s) {
    if (!(v >= 0))
      throw std::invalid_argument(fmt::format("--fan-velocity-m-s {:g}: must be ≥ 0", v));
    r.assessments.push_back(model::AssessFanVelocity(m, v));
  }
  for (double t : o.t4_c) {
    try {
      r.assessments.push_back(model::AssessHeatSinkTemperature(m, t));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--t4-c: ") + e.what());
    }
  }
  if (o.diameters.empty()) return r;
  const model::ExtruderParams params = model::LoadExtruderWithOverrides(o.extruder, o.set);
  model::SofteningOptions so;
  if (o.filament_modulus_pa) {
    so.modulus_pa = *o.filament_modulus_pa;
  } else if (params.Has(model::Param::kFilamentModulusPa)) {
    so.modulus_pa = params.Get(model::Param::kFilamentModulusPa);
  } else {
    throw std::invalid_argument(
        "--diameters needs the filament's modulus near its glass transition: "
        "--filament-modulus-pa (or filament_modulus_pa in the extruder)");
  }
  so.viscosity_pa_s = o.viscosity_pa_s.value_or(model::CoolingDataOf(m).melt_viscosity_pa_s);
  if (o.hp_length_mm) so.hp_length_m = *o.hp_length_mm * 1e-3;
  const auto steps =
      model::ReadDiameterTable(o.diameters, params.Get(model::Param::kReferenceTemperatureC));
  r.softening = model::CriticalLengths(params, steps, so);
  r.softening_options = so;
  return r;
}

int RunThermal(int argc, char** argv) {
  CLI::App app{
      "Thermal clog risk of a hot end (hot-end cooling study): heat-sink temperature T4 against "
      "fan air velocity, the study's clog criteria, and the critical softened length L_crt per "
      "step of a diameter table.",
      "clogscope thermal"};
  ThermalCommandOptions o;
  app.add_option("--material", o.material, "pla or abs")->required();
  app.add_option("--fan-velocity-m-s", o.fan_velocity_m_s,
                 "Fan air velocity at the heat sink (repeatable)");
  app.add_option("--t4-c", o.t4_c, "Measured heat-sink temperature T4 (repeatable)");
  app.add_option("--diameters", o.diameters,
                 "Diameter table CSV: L_crt at each step's effective diameter");
  app.add_option("--extruder", o.extruder, "Preset or YAML file (for --diameters)")
      ->capture_default_str();
  app.add_option("--set", o.set, "Override an extruder parameter: name=value (repeatable)");
  app.add_option("--filament-modulus-pa", o.filament_modulus_pa,
                 "Filament modulus E near the glass transition");
  app.add_option("--viscosity-pa-s", o.viscosity_pa_s,
                 "Melt viscosity for Hagen–Poiseuille (default: the study's PLA 100, ABS 350)");
  app.add_option("--hp-length-mm", o.hp_length_mm,
                 "Hagen–Poiseuille length (default: the exit capillary, zone 3)");
  app.add_option("--out", o.out_dir, "Write thermal.json (and softening.csv) here");
  app.footer(
      "Examples:\n"
      "  clogscope thermal --material pla --fan-velocity-m-s 0.3\n"
      "  clogscope thermal --material abs --t4-c 75\n"
      "  clogscope thermal --material pla --fan-velocity-m-s 0.5 --diameters diameters.csv "
      "--filament-modulus-pa 5e7 --out thermal/\n"
      "Equations and sources: docs/clog-physics.md §1.");
  if (!ParseCommandLine(app, argc, argv)) return 0;
  const ThermalReport r = ComputeThermal(o);
  for (const auto& a : r.assessments) PrintAssessment(a);
  if (r.softening_options) PrintSoftening(r);
  if (o.out_dir.empty()) return 0;
  CreateOutputDirectory(o.out_dir);
  const Provenance prov = CurrentProvenance();
  std::vector<std::string> written = {(fs::path(o.out_dir) / "thermal.json").string()};
  WriteFileAtomically(written[0],
                      model::ThermalJson(r.assessments, r.softening, r.softening_options, prov));
  if (r.softening_options) {
    written.push_back((fs::path(o.out_dir) / "softening.csv").string());
    WriteFileAtomically(written[1], model::SofteningCsv(r.softening, prov));
  }
  spdlog::info("wrote {}", fmt::join(written, ", "));
  return 0;
}

}  // namespace clogscope::apps
