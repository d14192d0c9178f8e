#pragma once

// Thermal clog risk (hot-end cooling study: E3D-like Diamond hot end, PLA and ABS): heat-sink
// temperature against fan air velocity, the study's clog criteria, and the critical softened
// length before the filament buckles. Equations: docs/clog-physics.md §1.
#include <optional>
#include <string>
#include <vector>

#include "model/parameters.h"
#include "model/predictor.h"

namespace clogscope::model {

enum class Material { kPla, kAbs };
// "pla" or "abs" (any case); throws std::invalid_argument listing the names otherwise.
Material ParseMaterial(const std::string& name);
const char* MaterialName(Material m);

// One tested fan velocity of the study, the heat-sink temperature measured there, and what the
// print did.
struct CoolingObservation {
  double velocity_m_s = 0;
  double t4_c = 0;
  const char* outcome = "";  // "safe", "problems", "complete clog"
};

// T4(V) = a1·exp(−b1·V) + a2·exp(−b2·V), °C, V the fan air velocity in m/s.
struct HeatSinkCorrelation {
  double a1_c = 0, b1_s_per_m = 0, a2_c = 0, b2_s_per_m = 0;
  double T4C(double velocity_m_s) const;
  double DT4DV(double velocity_m_s) const;  // derivative, °C per m/s
};

struct CoolingData {
  Material material = Material::kPla;
  HeatSinkCorrelation correlation;
  double min_tested_velocity_m_s = 0, max_tested_velocity_m_s = 0;
  double safe_below_t4_c = 0;  // the study's criterion
  // The fastest tested velocity with problems (or a complete clog): at or below it, clog risk.
  double clog_risk_at_velocity_m_s = 0;
  double ClogRiskFromT4C() const { return correlation.T4C(clog_risk_at_velocity_m_s); }
  double melt_viscosity_pa_s = 0;  // the study's Hagen–Poiseuille estimate
  std::vector<CoolingObservation> observations;
};
const CoolingData& CoolingDataOf(Material m);

// The fan velocity at which the correlation gives `t4_c`: T4 falls monotonically with V, so a
// bracket and safeguarded Newton steps find it to 1e-12 m/s. No value when no V ≥ 0 gives it
// (t4_c at or above the still-air value, or ≤ 0); `why` then says so.
std::optional<double> FanVelocityForT4(const CoolingData& data, double t4_c, std::string* why);

enum class ClogRisk { kSafe, kMarginal, kClogRisk };
const char* ClogRiskName(ClogRisk r);  // "safe", "marginal", "clog_risk"

struct ThermalAssessment {
  Material material = Material::kPla;
  double velocity_m_s = 0;
  double t4_c = 0;
  bool extrapolated = false;  // outside the tested velocities (or their temperatures)
  ClogRisk risk = ClogRisk::kSafe;
  std::string explanation;           // the criterion and the nearest observations
  double min_safe_velocity_m_s = 0;  // V where T4 meets the criterion
};

// From a fan velocity (m/s, ≥ 0) or from a measured T4 (°C). Throw std::invalid_argument for a
// negative or non-finite velocity, or a T4 no velocity can give.
ThermalAssessment AssessFanVelocity(Material m, double velocity_m_s);
ThermalAssessment AssessHeatSinkTemperature(Material m, double t4_c);

// Pin-ended Euler buckling of the softened filament under the pressure it must supply:
// L_crt = √(π² E R² / (4 ΔP)), metres. Throws std::invalid_argument for non-positive inputs.
double CriticalSoftenedLengthM(double modulus_pa, double filament_radius_m, double pressure_pa);

// Hagen–Poiseuille pressure drop 8 μ Q l / (π r⁴), Pa.
double HagenPoiseuillePressurePa(double viscosity_pa_s, double flow_m3_s, double length_m,
                                 double radius_m);

struct SofteningOptions {
  double modulus_pa = 0;      // filament modulus near its glass transition
  double viscosity_pa_s = 0;  // Hagen–Poiseuille melt viscosity (the study: PLA 100, ABS 350)
  std::optional<double> hp_length_m;  // default: the extruder's exit capillary (zone 3) length
  bool Validate(std::string* why) const;
};

struct SofteningStep {
  int step = 0;
  double temperature_c = 0;
  double diameter_um = 0;
  double dp_hagen_poiseuille_pa = 0;  // over l at radius D/2, the study's estimate
  double l_crt_hagen_poiseuille_mm = 0;
  double dp_power_law_pa = 0;  // ClogScope's three-zone back-pressure at (D, T)
  double l_crt_power_law_mm = 0;
};

// L_crt both ways at every step; Q = print speed × layer height × nozzle diameter, R the filament
// radius, both from `params`. Throws std::invalid_argument for unusable options or steps.
std::vector<SofteningStep> CriticalLengths(const ExtruderParams& params,
                                           const std::vector<StepInput>& steps,
                                           const SofteningOptions& options);

}  // namespace clogscope::model
