#include "model/parameters.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "common/csv.h"

namespace clogscope::model {
namespace {

constexpr double kInf = 1e300;

}  // namespace

const std::vector<ParamInfo>& AllParams() {
  static const std::vector<ParamInfo> kParams = {
      {Param::kMotorTorqueNm, "motor_torque_nm", "feeding stepper torque T_z", false, 1e-4, 100},
      {Param::kDriveRollerRadiusM, "drive_roller_radius_m", "drive roller radius R_rol", false,
       1e-4, 0.1},
      {Param::kFilamentDiameterM, "filament_diameter_m", "filament diameter d_f", false, 1e-4,
       0.01},
      {Param::kNozzleDiameterM, "nozzle_diameter_m", "nominal (unclogged) exit diameter D_0", false,
       1e-5, 0.01},
      {Param::kNozzleEntryRadiusM, "nozzle_entry_radius_m", "R1, zone 1 and cone entry", false,
       1e-5, 0.01},
      {Param::kZone1LengthM, "zone1_length_m", "L1, cylindrical entry zone", false, 0, 1},
      {Param::kZone3LengthM, "zone3_length_m", "L3, exit land", false, 0, 0.1},
      {Param::kNozzleAngleDeg, "nozzle_angle_deg", "inside (full) cone angle alpha", false, 1, 179},
      {Param::kPrintSpeedMS, "print_speed_m_s", "print speed", false, 1e-6, 10},
      {Param::kLayerHeightM, "layer_height_m", "layer height", false, 1e-6, 0.01},
      {Param::kConsistencyPaSn, "consistency_pa_sn", "power-law consistency K", false, 1e-6, 1e9},
      {Param::kFlowIndex, "flow_index", "power-law index n", false, 0.05, 2},
      {Param::kActivationTemperatureK, "activation_temperature_k",
       "beta = E_a/R of the Arrhenius shift", false, 0, 1e6},
      {Param::kReferenceTemperatureC, "reference_temperature_c", "T_0", false, -273.15 + 1e-9,
       1000},
      {Param::kNaturalFrequencyHz, "natural_frequency_hz", "first bending mode of the mounted bar",
       false, 1e-3, 1e6},
      {Param::kBeamLengthM, "beam_length_m", "bar mount length L", false, 1e-4, 10},
      {Param::kBeamWidthM, "beam_width_m", "bar mount width W", false, 1e-5, 1},
      {Param::kBeamHeightM, "beam_height_m", "bar mount height H", false, 1e-5, 1},
      {Param::kBeamModulusPa, "beam_modulus_pa", "bar Young's modulus", false, 1e6, 1e13},
      {Param::kBeamDensityKgM3, "beam_density_kg_m3", "bar density", false, 1, 1e5},
      {Param::kDampingRatio, "damping_ratio", "modal damping ratio zeta", false, 1e-6, 0.99},
      {Param::kCurrentLimitMa, "current_limit_ma", "driver saturation current I_max", false, 1e-3,
       1e6},
      {Param::kGainMS2PerN, "gain_m_s2_per_n", "modal gain G (amplitude per newton of load)", true,
       0, kInf},
      {Param::kBaselineAmplitudeMS2, "baseline_amplitude_m_s2",
       "measured amplitude at D_0, T_0 (calibrates G)", true, 0, kInf},
      {Param::kCurrentOffsetMa, "current_offset_ma", "I_0, motor current without back-pressure",
       true, -1e6, 1e6},
      {Param::kCurrentGainMaPerN, "current_gain_ma_per_n", "g, current per newton of back-pressure",
       true, -1e6, 1e6},
      {Param::kFilamentModulusPa, "filament_modulus_pa", "filament Young's modulus E_f", true, 1e3,
       1e13},
      {Param::kUnsupportedLengthM, "unsupported_length_m", "unsupported filament length L_u", true,
       1e-6, 10},
  };
  return kParams;
}

const ParamInfo& InfoOf(Param p) { return AllParams()[static_cast<int>(p)]; }

Param ParamByName(const std::string& name) {
  if (name == "gain") return Param::kGainMS2PerN;
  for (const auto& info : AllParams()) {
    if (name == info.name) return info.id;
  }
  std::string names;
  for (const auto& info : AllParams()) names += std::string(names.empty() ? "" : ", ") + info.name;
  throw std::invalid_argument(
      fmt::format("unknown parameter '{}' (known: {}, load_model)", name, names));
}

const char* LoadModelName(LoadModel m) { return m == LoadModel::kSum ? "sum" : "difference"; }

std::vector<std::string> ExtruderParams::PresetNames() { return {"direct-pla", "bowden-pla"}; }

ExtruderParams ExtruderParams::Preset(const std::string& name) {
  const bool direct = name == "direct-pla";
  if (!direct && name != "bowden-pla") {
    throw std::invalid_argument("--extruder '" + name +
                                "': not a preset (direct-pla, bowden-pla) nor a readable file");
  }
  ExtruderParams p;
  p.origin = name;
  p.Set(Param::kMotorTorqueNm, 0.285);
  p.Set(Param::kDriveRollerRadiusM, 5.4e-3);
  p.Set(Param::kFilamentDiameterM, 1.75e-3);
  p.Set(Param::kNozzleDiameterM, direct ? 0.40e-3 : 0.35e-3);
  p.Set(Param::kNozzleEntryRadiusM, 0.875e-3);
  p.Set(Param::kZone1LengthM, 15e-3);
  p.Set(Param::kZone3LengthM, 0.8e-3);
  p.Set(Param::kNozzleAngleDeg, 110);
  p.Set(Param::kPrintSpeedMS, 0.050);
  p.Set(Param::kLayerHeightM, 0.2e-3);
  p.Set(Param::kConsistencyPaSn, 650);
  p.Set(Param::kFlowIndex, 0.66);
  p.Set(Param::kActivationTemperatureK, 17200);
  p.Set(Param::kReferenceTemperatureC, 220);
  p.Set(Param::kNaturalFrequencyHz, direct ? 203.6 : 16.5);
  p.Set(Param::kBeamLengthM, direct ? 0.030 : 0.100);
  p.Set(Param::kBeamWidthM, direct ? 0.013 : 0.022);
  p.Set(Param::kBeamHeightM, direct ? 0.016 : 0.006);
  p.Set(Param::kBeamModulusPa, 70e9);
  p.Set(Param::kBeamDensityKgM3, 2700);
  p.Set(Param::kDampingRatio, 0.02);
  p.Set(Param::kCurrentLimitMa, 1000);
  return p;
}

void ExtruderParams::Set(Param p, double value) {
  values_[static_cast<int>(p)] = value;
  has_[static_cast<int>(p)] = true;
}

void ExtruderParams::Unset(Param p) {
  values_[static_cast<int>(p)] = 0;
  has_[static_cast<int>(p)] = false;
}

void ExtruderParams::SetByName(const std::string& name, const std::string& value) {
  if (name == "load_model") {
    if (value == "sum") {
      load_model = LoadModel::kSum;
    } else if (value == "difference") {
      load_model = LoadModel::kDifference;
    } else {
      throw std::invalid_argument("load_model '" + value + "': expected sum or difference");
    }
    return;
  }
  const Param p = ParamByName(name);
  Set(p, ParseNumberField(value, InfoOf(p).name, "value"));
}

bool ExtruderParams::Validate(std::string* why) const {
  for (const auto& info : AllParams()) {
    const int i = static_cast<int>(info.id);
    if (!has_[i]) {
      if (info.optional) continue;
      *why = fmt::format("{} is missing", info.name);
      return false;
    }
    const double v = values_[i];
    if (!std::isfinite(v) || v < info.lower || v > info.upper) {
      *why = fmt::format("{} = {:g} is outside its range [{:g}, {:g}]", info.name, v, info.lower,
                         info.upper);
      return false;
    }
  }
  if (Get(Param::kNozzleDiameterM) >= 2 * Get(Param::kNozzleEntryRadiusM)) {
    *why = fmt::format("nozzle_diameter_m = {:g} is not smaller than the entry bore {:g} m",
                       Get(Param::kNozzleDiameterM), 2 * Get(Param::kNozzleEntryRadiusM));
    return false;
  }
  if (Has(Param::kFilamentModulusPa) != Has(Param::kUnsupportedLengthM)) {
    *why = "filament_modulus_pa and unsupported_length_m go together (buckling ratio)";
    return false;
  }
  return true;
}

}  // namespace clogscope::model
