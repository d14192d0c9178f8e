#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "model/parameters.h"

namespace clogscope::model {

// One clog stage: the effective diameter and the temperature it was measured at.
struct StepInput {
  int step = 0;
  double temperature_c = 0;
  double diameter_m = 0;
  int source_line = 0;  // line in the table it came from (0: not from a file), for messages
  // The feedstock measured at this step (the table's filament_diameter_um): replaces the preset's
  // d_f and the entry radius R1 = d_f / 2 for this step.
  std::optional<double> filament_diameter_m;
};

// The parameter values for one step: `params` with the step's measured filament diameter put in
// (d_f and R1 = d_f / 2) when it has one. T = double or ceres::Jet.
template <typename T>
void UseStepFeedstock(const StepInput& step, T* values) {
  if (!step.filament_diameter_m) return;
  values[static_cast<int>(Param::kFilamentDiameterM)] = T(*step.filament_diameter_m);
  values[static_cast<int>(Param::kNozzleEntryRadiusM)] = T(0.5 * *step.filament_diameter_m);
}
std::array<double, kParamCount> StepValues(const ExtruderParams& params, const StepInput& step);

// predictor.md §8, one row per step.
struct StepPrediction {
  int step = 0;
  double temperature_c = 0;
  double diameter_um = 0;
  double dp1_pa = 0, dp2_pa = 0, dp3_pa = 0;  // zone drops at the reference temperature
  double dp_total_pa = 0;                     // sum with the Arrhenius shift
  double f_bp_n = 0, f_feed_n = 0, load_n = 0;
  double relative_amplitude = 0;  // A / A_0 = W / W_0
  double amplitude_increase_pct = 0;
  std::optional<double> amplitude_m_s2;  // when the gain is known
  double natural_frequency_hz = 0;
  std::optional<double> current_ma;      // when I_0 and g are known
  std::optional<double> buckling_ratio;  // F_bp / F_cr when filament modulus and length are given
  std::optional<double> filament_diameter_um;  // the step's measured feedstock, when used
};

struct Prediction {
  std::vector<StepPrediction> steps;
  double reference_load_n = 0;  // W_0 at D_0 and T_0
  double feed_force_n = 0;
  double beam_frequency_hz = 0;  // bar-only pinned-pinned first mode (far above the mount's mode)
  std::optional<double> gain_m_s2_per_n;
  std::string gain_source;  // "given", "baseline_amplitude_m_s2" or "" (relative amplitudes only)
  // Spectrum near the natural frequency for each step, on a common grid f_n·[0.5, 1.5]; in m/s²
  // when the gain is known, else relative to A_0.
  std::vector<double> spectrum_frequency_hz;
  std::vector<std::vector<double>> spectra;
  bool spectrum_absolute = false;
};

// Checks the inputs and runs the model. Throws std::invalid_argument naming the step (and its line)
// or the parameter when a diameter is not positive or not below the entry bore, a temperature is at
// or below absolute zero, or the parameters do not validate.
Prediction Predict(const ExtruderParams& params, const std::vector<StepInput>& steps,
                   int spectrum_points = 201);

// Bar-only first bending mode (pinned-pinned Euler–Bernoulli): (π/L)² √(EI/m) / 2π.
double BeamFrequencyHz(const ExtruderParams& params);

// Response near the mode: A · 2ζ / √((1 − r²)² + (2ζr)²), r = f / f_n.
double SpectrumAt(double frequency_hz, double natural_frequency_hz, double damping_ratio,
                  double amplitude);

// Throws std::invalid_argument naming the step when a step's values are unusable with `params`.
void CheckSteps(const ExtruderParams& params, const std::vector<StepInput>& steps);

}  // namespace clogscope::model
