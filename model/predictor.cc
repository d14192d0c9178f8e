#include "model/predictor.h"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>

#include "model/physics.h"

namespace clogscope::model {
namespace {

std::string Where(const StepInput& s) {
  return s.source_line > 0 ? fmt::format("step {} (line {})", s.step, s.source_line)
                           : fmt::format("step {}", s.step);
}

}  // namespace

std::array<double, kParamCount> StepValues(const ExtruderParams& params, const StepInput& step) {
  std::array<double, kParamCount> v = params.Values();
  UseStepFeedstock(step, v.data());
  return v;
}

void CheckSteps(const ExtruderParams& params, const std::vector<StepInput>& steps) {
  for (const auto& s : steps) {
    if (s.filament_diameter_m && !(*s.filament_diameter_m > 0 && *s.filament_diameter_m < 0.01)) {
      throw std::invalid_argument(fmt::format("{}: filament diameter {:g} µm must be in (0, 10) mm",
                                              Where(s), *s.filament_diameter_m * 1e6));
    }
    const double bore_m = 2 * StepValues(params, s)[static_cast<int>(Param::kNozzleEntryRadiusM)];
    if (!(s.diameter_m > 0) || !std::isfinite(s.diameter_m)) {
      throw std::invalid_argument(
          fmt::format("{}: diameter {:g} µm must be positive", Where(s), s.diameter_m * 1e6));
    }
    if (s.diameter_m >= bore_m) {
      throw std::invalid_argument(
          fmt::format("{}: diameter {:g} µm is not below the entry bore {:g} µm", Where(s),
                      s.diameter_m * 1e6, bore_m * 1e6));
    }
    if (!(s.temperature_c > -physics::kZeroCelsiusInK) || !std::isfinite(s.temperature_c)) {
      throw std::invalid_argument(fmt::format(
          "{}: temperature {:g} °C is at or below absolute zero", Where(s), s.temperature_c));
    }
  }
}

double BeamFrequencyHz(const ExtruderParams& p) {
  const double l = p.Get(Param::kBeamLengthM), w = p.Get(Param::kBeamWidthM);
  const double h = p.Get(Param::kBeamHeightM);
  const double inertia = w * h * h * h / 12.0;
  const double mass_per_m = p.Get(Param::kBeamDensityKgM3) * w * h;
  return std::pow(physics::kPi / l, 2) *
         std::sqrt(p.Get(Param::kBeamModulusPa) * inertia / mass_per_m) / (2 * physics::kPi);
}

double SpectrumAt(double f, double fn, double zeta, double amplitude) {
  const double r = f / fn;
  return amplitude * 2 * zeta / std::sqrt(std::pow(1 - r * r, 2) + std::pow(2 * zeta * r, 2));
}

Prediction Predict(const ExtruderParams& params, const std::vector<StepInput>& steps,
                   int spectrum_points) {
  std::string why;
  if (!params.Validate(&why)) throw std::invalid_argument("extruder parameters: " + why);
  CheckSteps(params, steps);
  const auto& v = params.Values();
  const double* p = v.data();
  Prediction out;
  out.feed_force_n = physics::FeedForce(p);
  out.reference_load_n = physics::ReferenceLoad(p, params.load_model);
  if (!(out.reference_load_n > 0)) {
    throw std::invalid_argument("reference load W_0 is zero (difference model with F_feed = F_bp)");
  }
  out.beam_frequency_hz = BeamFrequencyHz(params);
  if (params.Has(Param::kGainMS2PerN)) {
    out.gain_m_s2_per_n = params.Get(Param::kGainMS2PerN);
    out.gain_source = "given";
  } else if (params.Has(Param::kBaselineAmplitudeMS2)) {
    out.gain_m_s2_per_n = params.Get(Param::kBaselineAmplitudeMS2) / out.reference_load_n;
    out.gain_source = "baseline_amplitude_m_s2";
  }
  const double fn = params.Get(Param::kNaturalFrequencyHz);
  const double zeta = params.Get(Param::kDampingRatio);
  const bool has_current =
      params.Has(Param::kCurrentOffsetMa) && params.Has(Param::kCurrentGainMaPerN);
  const bool has_buckling = params.Has(Param::kFilamentModulusPa);
  for (const auto& s : steps) {
    StepPrediction r;
    r.step = s.step;
    r.temperature_c = s.temperature_c;
    r.diameter_um = s.diameter_m * 1e6;
    // A measured feedstock diameter enters through the filament's area and the entry radius.
    const auto vs = StepValues(params, s);
    const double* ps = vs.data();
    if (s.filament_diameter_m) r.filament_diameter_um = *s.filament_diameter_m * 1e6;
    const auto bp = physics::BackPressure(ps, s.diameter_m, s.temperature_c);
    r.dp1_pa = bp.dp1;
    r.dp2_pa = bp.dp2;
    r.dp3_pa = bp.dp3;
    r.dp_total_pa = bp.total;
    r.f_bp_n = bp.total * physics::FilamentArea(ps);
    r.f_feed_n = out.feed_force_n;
    r.load_n = physics::Load(p, r.f_bp_n, params.load_model);
    r.relative_amplitude = r.load_n / out.reference_load_n;
    r.amplitude_increase_pct = 100.0 * (r.relative_amplitude - 1.0);
    if (out.gain_m_s2_per_n) r.amplitude_m_s2 = *out.gain_m_s2_per_n * r.load_n;
    r.natural_frequency_hz = fn;
    if (has_current) r.current_ma = physics::MotorCurrent(p, r.f_bp_n);
    if (has_buckling) {
      // Pin-ended Euler buckling of the unsupported filament: π² E I / L², I = π d⁴ / 64.
      const double d = vs[static_cast<int>(Param::kFilamentDiameterM)];
      const double l = params.Get(Param::kUnsupportedLengthM);
      const double f_cr = physics::kPi * physics::kPi * params.Get(Param::kFilamentModulusPa) *
                          (physics::kPi * std::pow(d, 4) / 64.0) / (l * l);
      r.buckling_ratio = r.f_bp_n / f_cr;
    }
    out.steps.push_back(r);
  }
  out.spectrum_absolute = out.gain_m_s2_per_n.has_value();
  for (int i = 0; i < spectrum_points; ++i) {
    out.spectrum_frequency_hz.push_back(fn * (0.5 + double(i) / std::max(spectrum_points - 1, 1)));
  }
  for (const auto& r : out.steps) {
    const double amplitude = r.amplitude_m_s2.value_or(r.relative_amplitude);
    std::vector<double> curve;
    for (double f : out.spectrum_frequency_hz) curve.push_back(SpectrumAt(f, fn, zeta, amplitude));
    out.spectra.push_back(std::move(curve));
  }
  return out;
}

}  // namespace clogscope::model
