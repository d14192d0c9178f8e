#include "model/roller_drive.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <stdexcept>

#include "model/physics.h"

namespace clogscope::model {
namespace {

RollerPreset Roller(int number, const char* kind, double od_mm, double printed, double ks,
                    double ks_sigma, double k, double k_sigma, double a, std::optional<double> b,
                    std::optional<double> c) {
  RollerPreset r;
  r.number = number;
  r.kind = kind;
  r.name = fmt::format("{}-{}", number, kind);
  r.outer_diameter_mm = od_mm;
  r.printed_min_pinch_n = printed;
  r.k_s_pct_n = ks;
  r.k_s_sigma_pct_n = ks_sigma;
  r.k_pct_per_n = k;
  r.k_sigma_pct_per_n = k_sigma;
  r.a_pct_per_n = a;
  r.b_pct_per_n = b;
  r.c_s_per_mm = c;
  return r;
}

std::string Names() {
  std::string names;
  for (const auto& r : RollerPresets()) names += (names.empty() ? "" : ", ") + r.name;
  return names;
}

}  // namespace

const std::vector<RollerPreset>& RollerPresets() {
  static const std::vector<RollerPreset> presets = {
      Roller(1, "straight-knurl", 10.90, 129, 356.8, 15.7, 0.22, 0.01, 0.14, 0.16, 0.08),
      Roller(2, "diamond-knurl", 8.64, 112, 788.5, 19.2, 0.63, 0.02, 0.47, 0.37, 0.32),
      Roller(3, "hobb-goblin", 7.98, 77, 96.0, 3.0, 0.32, 0.01, 0.24, 0.18, 0.32),
      Roller(4, "plain", 8.02, 44, 404.8, 76.3, 2.06, 0.08, 1.24, 2.07, 0.73),
      Roller(5, "straight-knurl", 12.20, 100, 286.8, 18.3, 0.29, 0.02, 0.23, 0.37, 0.83),
      Roller(6, "straight-knurl", 16.20, 129, 627.4, 23.3, 0.38, 0.01, 0.43, {}, {}),
      Roller(7, "straight-knurl", 20.03, 172, 643.0, 34.2, 0.22, 0.02, 0.29, {}, {}),
  };
  return presets;
}

const RollerPreset& RollerByName(const std::string& name) {
  std::string n = name;
  if (!n.empty() && n[0] == '#') n.erase(0, 1);
  const RollerPreset* by_kind = nullptr;
  int kind_matches = 0;
  for (const auto& r : RollerPresets()) {
    if (n == r.name || n == std::to_string(r.number)) return r;
    if (n == r.kind) {
      by_kind = &r;
      ++kind_matches;
    }
  }
  if (kind_matches == 1) return *by_kind;
  throw std::invalid_argument(
      fmt::format("roller '{}': {}; the rollers are {}", name,
                  kind_matches > 1 ? "more than one has that kind" : "no such roller", Names()));
}

MinimalPinch MinimalPinchForce(const RollerPreset& r) {
  MinimalPinch m;
  m.computed_n = std::sqrt(r.k_s_pct_n / (0.1 * r.k_pct_per_n));
  // F ∝ k_s^½ k^−½: relative σ is half the quadrature sum of the relative σ of k_s and k.
  m.sigma_n = m.computed_n * 0.5 *
              std::hypot(r.k_s_sigma_pct_n / r.k_s_pct_n, r.k_sigma_pct_per_n / r.k_pct_per_n);
  m.printed_n = r.printed_min_pinch_n;
  m.agrees = std::abs(m.printed_n - m.computed_n) <= 2 * m.sigma_n + 0.5;
  return m;
}

Slip SlipPinchForm(const RollerPreset& r, double pinch_force_n, double feed_force_n,
                   double k_p_pct) {
  if (!(pinch_force_n > 0) || !std::isfinite(pinch_force_n)) {
    throw std::invalid_argument(fmt::format("pinch force {:g} N: must be positive", pinch_force_n));
  }
  if (!(feed_force_n >= 0) || !std::isfinite(feed_force_n)) {
    throw std::invalid_argument(fmt::format("feed force {:g} N: must be ≥ 0", feed_force_n));
  }
  const double fp2 = pinch_force_n * pinch_force_n;
  Slip s;
  s.pct = k_p_pct + (r.k_s_pct_n / fp2 + r.k_pct_per_n) * feed_force_n;
  s.sigma_pct = feed_force_n * std::hypot(r.k_s_sigma_pct_n / fp2, r.k_sigma_pct_per_n);
  return s;
}

Slip SlipVelocityForm(const RollerPreset& r, double filament_speed_mm_s, double feed_force_n,
                      double k_p_pct) {
  if (!(filament_speed_mm_s >= 0) || !std::isfinite(filament_speed_mm_s)) {
    throw std::invalid_argument(
        fmt::format("filament speed {:g} mm/s: must be ≥ 0", filament_speed_mm_s));
  }
  double gradient = r.a_pct_per_n;
  if (r.b_pct_per_n && r.c_s_per_mm) {
    gradient += *r.b_pct_per_n * std::exp(-*r.c_s_per_mm * filament_speed_mm_s);
  }
  return {k_p_pct + gradient * feed_force_n, 0.0};
}

bool DriveOptions::Validate(std::string* why) const {
  try {
    RollerByName(roller);
  } catch (const std::invalid_argument& e) {
    *why = e.what();
    return false;
  }
  if (!(pinch_force_n > 0) || !std::isfinite(pinch_force_n))
    *why = fmt::format("pinch force {:g} N: must be positive", pinch_force_n);
  else if (!(friction_n >= 0) || !std::isfinite(friction_n))
    *why = fmt::format("friction {:g} N: must be ≥ 0", friction_n);
  else if (!std::isfinite(k_p_pct))
    *why = "slip offset k_p must be a number";
  else
    return true;
  return false;
}

DrivePrediction PredictDrive(const ExtruderParams& params, const std::vector<StepInput>& steps,
                             const DriveOptions& o,
                             const std::vector<std::optional<double>>& measured) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  if (!params.Validate(&why)) throw std::invalid_argument("extruder parameters: " + why);
  CheckSteps(params, steps);
  if (!measured.empty() && measured.size() != steps.size()) {
    throw std::invalid_argument("measured slip: one value (or none) per step expected");
  }
  const auto& p = params.Values();

  DrivePrediction out;
  out.roller = RollerByName(o.roller);
  out.min_pinch = MinimalPinchForce(out.roller);
  out.pinch_below_minimum = o.pinch_force_n < out.min_pinch.computed_n;
  out.velocity_form_extrapolated = !VelocityFormFitted(o.pinch_force_n);
  const double q_m3_s = physics::FlowRate(p.data());
  out.filament_speed_mm_s = 1e3 * q_m3_s / physics::FilamentArea(p.data());
  for (size_t i = 0; i < steps.size(); ++i) {
    const auto& s = steps[i];
    DriveStep d;
    d.step = s.step;
    d.temperature_c = s.temperature_c;
    d.diameter_um = s.diameter_m * 1e6;
    d.f_bp_n =
        physics::BackPressureForce(StepValues(params, s).data(), s.diameter_m, s.temperature_c);
    d.feed_force_n = d.f_bp_n + o.friction_n;
    d.slip_pinch = SlipPinchForm(out.roller, o.pinch_force_n, d.feed_force_n, o.k_p_pct);
    d.slip_velocity =
        SlipVelocityForm(out.roller, out.filament_speed_mm_s, d.feed_force_n, o.k_p_pct);
    d.commanded_flow_mm3_s = q_m3_s * 1e9;
    // The gear turns for the commanded flow; the filament moves (1 − s) of that.
    d.flow_deficit_pct = d.slip_pinch.pct;
    d.delivered_flow_mm3_s = d.commanded_flow_mm3_s * (1 - d.slip_pinch.pct / 100);
    if (!measured.empty()) d.measured_slip_pct = measured[i];
    out.steps.push_back(d);
  }
  return out;
}

}  // namespace clogscope::model
