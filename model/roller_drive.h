#pragma once

// Roller-drive slip against feed and pinch force (roller filament drive study, PLA, seven driving
// rollers) and its coupling to the predictor's back-pressure. Equations: docs/clog-physics.md §2.
#include <optional>
#include <string>
#include <vector>

#include "model/parameters.h"
#include "model/predictor.h"

namespace clogscope::model {

// One roller of the study. Slip s in %: s = k_p + (k_s / F_p² + k)·F_f (pinch-force form) or, for
// 80–130 N of pinch, s = k_p + (a + b·exp(−c·v_fil))·F_f (feed-velocity form, v_fil in mm/s).
struct RollerPreset {
  int number = 0;
  std::string name;  // "3-hobb-goblin": number and kind, as --roller takes it
  std::string kind;
  double outer_diameter_mm = 0;
  double printed_min_pinch_n = 0;  // F_p,min as the study prints it
  double k_s_pct_n = 0, k_s_sigma_pct_n = 0;
  double k_pct_per_n = 0, k_sigma_pct_per_n = 0;
  double a_pct_per_n = 0;
  std::optional<double> b_pct_per_n, c_s_per_mm;  // absent: no speed dependence
};

const std::vector<RollerPreset>& RollerPresets();
// By name ("3-hobb-goblin"), number ("3" or "#3") or kind when unique ("hobb-goblin"). Throws
// std::invalid_argument listing the names otherwise.
const RollerPreset& RollerByName(const std::string& name);

// F_p,min = √(k_s / (0.1·k)): where the pinch term k_s/F_p² has fallen to 10 % of k. σ from k_s's
// and k's σ. `agrees` when the printed value is within 2σ plus its rounding (0.5 N).
struct MinimalPinch {
  double computed_n = 0, sigma_n = 0;
  double printed_n = 0;
  bool agrees = true;
};
MinimalPinch MinimalPinchForce(const RollerPreset& roller);

// Slip in % with its σ from k_s and k (pinch form only). Throws std::invalid_argument for a pinch
// force ≤ 0 or a negative feed force.
struct Slip {
  double pct = 0;
  double sigma_pct = 0;
};
Slip SlipPinchForm(const RollerPreset& roller, double pinch_force_n, double feed_force_n,
                   double k_p_pct = 0);
Slip SlipVelocityForm(const RollerPreset& roller, double filament_speed_mm_s, double feed_force_n,
                      double k_p_pct = 0);
// The velocity form was fitted for these pinch forces.
constexpr double kVelocityFormMinPinchN = 80, kVelocityFormMaxPinchN = 130;
inline bool VelocityFormFitted(double pinch_force_n) {
  return pinch_force_n >= kVelocityFormMinPinchN && pinch_force_n <= kVelocityFormMaxPinchN;
}

struct DriveOptions {
  std::string roller = "3-hobb-goblin";
  double pinch_force_n = 0;
  double friction_n = 0;  // added to the back-pressure force: the feed force the drive supplies
  double k_p_pct = 0;     // test-stand offset, per printer
  bool Validate(std::string* why) const;  // also that the roller exists
};

struct DriveStep {
  int step = 0;
  double temperature_c = 0;
  double diameter_um = 0;
  double f_bp_n = 0;
  double feed_force_n = 0;  // F_bp + friction
  Slip slip_pinch;
  Slip slip_velocity;  // feed-velocity form (σ 0: the study gives none for a, b, c)
  double commanded_flow_mm3_s = 0;
  double delivered_flow_mm3_s = 0;  // (1 − s)·commanded, pinch form
  double flow_deficit_pct = 0;      // = s
  std::optional<double> measured_slip_pct;
};

struct DrivePrediction {
  RollerPreset roller;
  MinimalPinch min_pinch;
  double filament_speed_mm_s = 0;  // commanded, Q / A_fil
  bool pinch_below_minimum = false;
  bool velocity_form_extrapolated = false;  // pinch outside the 80–130 N it was fitted for
  std::vector<DriveStep> steps;
};

// Predicted slip at every step of a diameter table; `measured_slip_pct` (by step, may be empty)
// is carried through for comparison. Throws std::invalid_argument for unusable options or steps.
DrivePrediction PredictDrive(const ExtruderParams& params, const std::vector<StepInput>& steps,
                             const DriveOptions& options,
                             const std::vector<std::optional<double>>& measured_slip_pct = {});

}  // namespace clogscope::model
