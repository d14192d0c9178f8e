#include "model/thermal.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "common/ascii.h"
#include "model/physics.h"

namespace clogscope::model {
namespace {

// The study's numbers for one material: correlation, tested range, criterion, observations.
CoolingData Cooling(Material m, HeatSinkCorrelation c, double min_v, double max_v, double safe_t4,
                    double clog_v, double viscosity, std::vector<CoolingObservation> observations) {
  CoolingData d;
  d.material = m;
  d.correlation = c;
  d.min_tested_velocity_m_s = min_v;
  d.max_tested_velocity_m_s = max_v;
  d.safe_below_t4_c = safe_t4;
  d.clog_risk_at_velocity_m_s = clog_v;
  d.melt_viscosity_pa_s = viscosity;
  d.observations = std::move(observations);
  return d;
}

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument(what);
}

ThermalAssessment Assess(const CoolingData& d, double v, double t4) {
  ThermalAssessment a;
  a.material = d.material;
  a.velocity_m_s = v;
  a.t4_c = t4;
  // The tested velocities bound the correlation; a tiny slack keeps the tested points themselves
  // in.
  a.extrapolated =
      v < d.min_tested_velocity_m_s * (1 - 1e-9) || v > d.max_tested_velocity_m_s * (1 + 1e-9);
  std::string why;
  a.min_safe_velocity_m_s = *FanVelocityForT4(d, d.safe_below_t4_c, &why);
  const auto& obs = d.observations;
  if (t4 < d.safe_below_t4_c) {
    a.risk = ClogRisk::kSafe;
    a.explanation =
        fmt::format("T4 {:.1f} °C is below the study's criterion {:g} °C", t4, d.safe_below_t4_c);
  } else if (t4 < d.ClogRiskFromT4C()) {
    a.risk = ClogRisk::kMarginal;
    a.explanation = fmt::format(
        "T4 {:.1f} °C is above the criterion {:g} °C but below {:.1f} °C, where the study first "
        "saw problems",
        t4, d.safe_below_t4_c, d.ClogRiskFromT4C());
  } else {
    a.risk = ClogRisk::kClogRisk;
    a.explanation =
        fmt::format("T4 {:.1f} °C is at or above {:.1f} °C, where the study saw problems", t4,
                    d.ClogRiskFromT4C());
  }
  // The nearest tested points on either side, so the user sees the evidence, not only the rule.
  const CoolingObservation* below = nullptr;  // the warmest observation cooler than t4
  const CoolingObservation* above = nullptr;
  for (const auto& o : obs) {
    if (o.t4_c <= t4 && (!below || o.t4_c > below->t4_c)) below = &o;
    if (o.t4_c > t4 && (!above || o.t4_c < above->t4_c)) above = &o;
  }
  for (const auto* o : {below, above}) {
    if (o) {
      a.explanation += fmt::format("; observed {} at {:g} m/s ({:.1f} °C)", o->outcome,
                                   o->velocity_m_s, o->t4_c);
    }
  }
  return a;
}

}  // namespace

Material ParseMaterial(const std::string& name) {
  const std::string n = LowerAscii(name);
  if (n == "pla") return Material::kPla;
  if (n == "abs") return Material::kAbs;
  throw std::invalid_argument("material '" + name + "': expected pla or abs");
}

const char* MaterialName(Material m) { return m == Material::kPla ? "pla" : "abs"; }

double HeatSinkCorrelation::T4C(double v) const {
  return a1_c * std::exp(-b1_s_per_m * v) + a2_c * std::exp(-b2_s_per_m * v);
}

double HeatSinkCorrelation::DT4DV(double v) const {
  return -a1_c * b1_s_per_m * std::exp(-b1_s_per_m * v) -
         a2_c * b2_s_per_m * std::exp(-b2_s_per_m * v);
}

const CoolingData& CoolingDataOf(Material m) {
  static const CoolingData pla =
      Cooling(Material::kPla, {45.5, 9.53, 47.4, 0.41}, 0.112, 0.571, 40, 0.289, 100,
              {{0.571, 37.7, "safe"},
               {0.445, 40.1, "safe"},
               {0.289, 45.0, "problems"},
               {0.112, 60.9, "complete clog"}});
  static const CoolingData abs =
      Cooling(Material::kAbs, {63.2, 8.74, 46.5, 0.26}, 0.048, 0.445, 69, 0.048, 350,
              {{0.445, 42.7, "safe"},
               {0.289, 48.2, "safe"},
               {0.112, 68.9, "safe"},
               {0.048, 87.5, "complete clog"}});
  return m == Material::kPla ? pla : abs;
}

std::optional<double> FanVelocityForT4(const CoolingData& d, double t4_c, std::string* why) {
  const auto& c = d.correlation;
  const double still_air = c.T4C(0);
  if (t4_c == still_air) return 0.0;
  if (!std::isfinite(t4_c) || t4_c > still_air || t4_c <= 0) {
    *why = fmt::format(
        "T4 {:g} °C: no fan velocity gives it (the {} correlation falls from {:.1f} °C in still "
        "air towards 0 °C)",
        t4_c, MaterialName(d.material), still_air);
    return std::nullopt;
  }
  // Bracket [lo, hi] with T4(lo) > t4 ≥ T4(hi); T4 is strictly decreasing and convex.
  double lo = 0, hi = 1;
  while (c.T4C(hi) > t4_c) {
    lo = hi;
    hi *= 2;
  }
  double v = 0.5 * (lo + hi);
  for (int i = 0; i < 200 && hi - lo > 1e-15 * std::max(1.0, hi); ++i) {
    const double f = c.T4C(v) - t4_c;
    if (f > 0)
      lo = v;
    else
      hi = v;
    if (f == 0) break;
    const double newton = v - f / c.DT4DV(v);
    // Newton when it stays inside the bracket, else bisection.
    v = newton > lo && newton < hi ? newton : 0.5 * (lo + hi);
    if (std::abs(f) < 1e-13 * t4_c) break;
  }
  return v;
}

const char* ClogRiskName(ClogRisk r) {
  switch (r) {
    case ClogRisk::kSafe:
      return "safe";
    case ClogRisk::kMarginal:
      return "marginal";
    case ClogRisk::kClogRisk:
      return "clog_risk";
  }
  return "?";
}

ThermalAssessment AssessFanVelocity(Material m, double velocity_m_s) {
  Require(std::isfinite(velocity_m_s) && velocity_m_s >= 0,
          fmt::format("fan velocity {:g} m/s: must be a number ≥ 0", velocity_m_s));
  const CoolingData& d = CoolingDataOf(m);
  return Assess(d, velocity_m_s, d.correlation.T4C(velocity_m_s));
}

ThermalAssessment AssessHeatSinkTemperature(Material m, double t4_c) {
  const CoolingData& d = CoolingDataOf(m);
  std::string why;
  const auto v = FanVelocityForT4(d, t4_c, &why);
  if (!v) throw std::invalid_argument(why);
  return Assess(d, *v, t4_c);
}

double CriticalSoftenedLengthM(double modulus_pa, double filament_radius_m, double pressure_pa) {
  Require(modulus_pa > 0 && filament_radius_m > 0 && pressure_pa > 0,
          fmt::format("critical length: modulus {:g} Pa, radius {:g} m and pressure {:g} Pa must "
                      "be positive",
                      modulus_pa, filament_radius_m, pressure_pa));
  const double pi2 = physics::kPi * physics::kPi;
  return std::sqrt(pi2 * modulus_pa * filament_radius_m * filament_radius_m / (4 * pressure_pa));
}

double HagenPoiseuillePressurePa(double viscosity_pa_s, double flow_m3_s, double length_m,
                                 double radius_m) {
  return 8 * viscosity_pa_s * flow_m3_s * length_m / (physics::kPi * std::pow(radius_m, 4));
}

bool SofteningOptions::Validate(std::string* why) const {
  if (!(modulus_pa > 0 && std::isfinite(modulus_pa)))
    *why = fmt::format("filament modulus {:g} Pa: must be positive", modulus_pa);
  else if (!(viscosity_pa_s > 0 && std::isfinite(viscosity_pa_s)))
    *why = fmt::format("melt viscosity {:g} Pa·s: must be positive", viscosity_pa_s);
  else if (hp_length_m && !(*hp_length_m > 0 && std::isfinite(*hp_length_m)))
    *why = fmt::format("Hagen–Poiseuille length {:g} m: must be positive", *hp_length_m);
  else
    return true;
  return false;
}

std::vector<SofteningStep> CriticalLengths(const ExtruderParams& params,
                                           const std::vector<StepInput>& steps,
                                           const SofteningOptions& o) {
  std::string why;
  Require(o.Validate(&why), why);
  Require(params.Validate(&why), "extruder parameters: " + why);
  CheckSteps(params, steps);
  const double q = physics::FlowRate(params.Values().data());
  const double l = o.hp_length_m.value_or(params.Get(Param::kZone3LengthM));
  std::vector<SofteningStep> out;
  for (const auto& s : steps) {
    SofteningStep r;
    r.step = s.step;
    r.temperature_c = s.temperature_c;
    r.diameter_um = s.diameter_m * 1e6;
    // The filament radius R: the step's measured feedstock when the table has it.
    const auto ps = StepValues(params, s);
    const double r_fil = 0.5 * ps[static_cast<int>(Param::kFilamentDiameterM)];
    r.dp_hagen_poiseuille_pa =
        HagenPoiseuillePressurePa(o.viscosity_pa_s, q, l, 0.5 * s.diameter_m);
    r.l_crt_hagen_poiseuille_mm =
        1e3 * CriticalSoftenedLengthM(o.modulus_pa, r_fil, r.dp_hagen_poiseuille_pa);
    r.dp_power_law_pa = physics::BackPressure(ps.data(), s.diameter_m, s.temperature_c).total;
    r.l_crt_power_law_mm = 1e3 * CriticalSoftenedLengthM(o.modulus_pa, r_fil, r.dp_power_law_pa);
    out.push_back(r);
  }
  return out;
}

}  // namespace clogscope::model
