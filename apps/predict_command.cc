#include "apps/predict_command.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "apps/cli_util.h"
#include "common/path_check.h"
#include "model/io.h"
#include "model/prediction_run.h"

namespace clogscope::apps {
namespace {

using model::InfoOf;
using model::Param;

void PrintTable(const model::PredictionRun& r) {
  const auto& pr = r.prediction;
  int measured_feedstock = 0;
  for (const auto& s : pr.steps) measured_feedstock += s.filament_diameter_um.has_value();
  if (measured_feedstock > 0) {
    fmt::print(
        "filament diameter: measured at {} of {} steps (filament_diameter_um), used there for the "
        "filament area and the entry radius R1 instead of the extruder's {:g} mm\n",
        measured_feedstock, pr.steps.size(), 1e3 * r.params.Get(Param::kFilamentDiameterM));
  }
  const bool amp = pr.gain_m_s2_per_n.has_value();
  const bool cur = !pr.steps.empty() && pr.steps[0].current_ma.has_value();
  fmt::print("{:>4} {:>7} {:>9} {:>11} {:>9} {:>9} {:>8}{}{}\n", "step", "T °C", "D µm",
             "dp_total Pa", "F_bp N", "load N", "A/A0", amp ? "   A m/s²" : "",
             cur ? "   I mA" : "");
  for (const auto& s : pr.steps) {
    fmt::print("{:>4} {:>7.1f} {:>9.1f} {:>11.0f} {:>9.4f} {:>9.3f} {:>8.4f}{}{}\n", s.step,
               s.temperature_c, s.diameter_um, s.dp_total_pa, s.f_bp_n, s.load_n,
               s.relative_amplitude, amp ? fmt::format(" {:>8.4f}", *s.amplitude_m_s2) : "",
               cur ? fmt::format(" {:>7.1f}", *s.current_ma) : "");
  }
  fmt::print(
      "feed force {:.2f} N, reference load W0 {:.3f} N, natural frequency {:.1f} Hz "
      "(bar alone: {:.0f} Hz), gain {}\n",
      pr.feed_force_n, pr.reference_load_n, r.params.Get(Param::kNaturalFrequencyHz),
      pr.beam_frequency_hz,
      amp ? fmt::format("{:.6g} m/s² per N ({})", *pr.gain_m_s2_per_n, pr.gain_source)
          : "unknown (relative amplitudes only)");
}

void PrintFit(const model::FitSummary& f) {
  const auto& worst = f.residuals[f.worst_index];
  int beyond = 0;
  for (const auto& r : f.residuals) beyond += std::abs(r.relative) > 3 * f.rms_relative;
  fmt::print(
      "fit {}: {} residuals, RMS {:.2f} %, worst {:+.2f} % (step {} {}), {} of {} beyond 3×RMS, {} "
      "iterations\n",
      f.usable ? "converged" : "NOT USABLE", f.residuals.size(), 100 * f.rms_relative,
      100 * worst.relative, worst.step, worst.quantity, beyond, f.residuals.size(), f.iterations);
  for (const auto& v : f.values) {
    fmt::print("  {} = {:.6g} ± {:.3g}{}  (start {:.6g})\n", InfoOf(v.param).name, v.value, v.sigma,
               v.at_bound ? " AT BOUND" : "", v.initial);
  }
}

}  // namespace

bool PredictCommandOptions::Validate(std::string* why) const {
  if (diameters.empty())
    *why = "--diameters is required";
  else if (out_dir.empty())
    *why = "--out must not be empty";
  else if (fit_measured.empty() != fit_params.empty())
    *why = "--fit and --fit-params go together";
  else if (!CheckTableAndExtruderPaths(diameters, extruder, why))
    return false;
  else if (!fit_measured.empty() && !CheckInputPath("--fit", fit_measured, PathExpect::kFile, why))
    return false;
  else
    return true;
  return false;
}

model::PredictionRun ComputePrediction(const PredictCommandOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw std::invalid_argument(why);
  const model::ExtruderParams params = model::LoadExtruderWithOverrides(o.extruder, o.set);
  return model::PredictSteps(
      params, model::ReadDiameterTable(o.diameters, params.Get(Param::kReferenceTemperatureC)),
      {o.fit_measured, o.fit_params});
}

int RunPredict(int argc, char** argv) {
  CLI::App app{
      "Predict bar-mount vibration and motor current from an effective-diameter table; "
      "optionally fit unknown parameters to measurements.",
      "clogscope predict"};
  PredictCommandOptions o;
  std::string fit_params;
  bool no_plots = false;
  app.add_option("--extruder", o.extruder, "Preset (direct-pla, bowden-pla) or YAML parameter file")
      ->capture_default_str();
  app.add_option("--diameters", o.diameters, "Diameter table CSV (step, temperature_c, mean_um)")
      ->required();
  app.add_option("--set", o.set, "Override a parameter: name=value (repeatable)");
  app.add_option("--out", o.out_dir, "Output directory")->capture_default_str();
  app.add_option("--fit", o.fit_measured,
                 "Measured CSV: step or temperature_c, amplitude_m_s2 and/or current_ma");
  app.add_option("--fit-params", fit_params,
                 "Unknowns to fit, comma-separated (e.g. activation_temperature_k,gain)");
  app.add_flag("--no-plots", no_plots, "Skip the PNG plots");
  app.footer(
      "Examples:\n"
      "  clogscope predict --extruder direct-pla --diameters diameters.csv --out pred/\n"
      "  clogscope predict --extruder bowden-pla --set damping_ratio=0.05 --diameters d.csv\n"
      "  clogscope predict --diameters d.csv --fit accel.csv --fit-params "
      "activation_temperature_k,gain\n"
      "Parameters (SI units; see ../shared/spec/predictor.md): " +
      [] {
        std::string names;
        for (const auto& i : model::AllParams())
          names += std::string(names.empty() ? "" : ", ") + i.name;
        return names + ", load_model (sum|difference)";
      }());
  if (!ParseCommandLine(app, argc, argv)) return 0;  // --help printed
  if (!fit_params.empty()) {
    std::string item;
    std::stringstream ss(fit_params);
    while (std::getline(ss, item, ',')) {
      if (!item.empty()) o.fit_params.push_back(item);
    }
  }
  o.plots = !no_plots;
  const model::PredictionRun r = ComputePrediction(o);
  if (r.fit) PrintFit(*r.fit);
  if (r.fit && !r.fit->usable) {
    spdlog::error("fit not usable: {}; nothing written", r.fit->message);
    return 1;
  }
  PrintTable(r);
  std::vector<std::string> warnings;
  const auto written = model::WritePredictionOutputs(r, o.out_dir, o.plots, &warnings);
  for (const auto& w : warnings) spdlog::warn("{}", w);
  spdlog::info("wrote {}", fmt::join(written, ", "));
  return 0;
}

}  // namespace clogscope::apps
