#include "model/prediction_run.h"

#include <fmt/format.h>

#include <filesystem>
#include <stdexcept>

#include "common/atomic_file.h"
#include "common/path_check.h"
#include "common/plot.h"
#include "common/provenance.h"
#include "model/io.h"

namespace clogscope::model {

namespace fs = std::filesystem;

ExtruderParams LoadExtruderWithOverrides(const std::string& extruder,
                                         const std::vector<std::string>& set) {
  RequireInputPath("--extruder", extruder, PathExpect::kPresetOrFile);
  ExtruderParams params = LoadExtruder(extruder);
  for (const std::string& kv : set) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw std::invalid_argument("--set '" + kv + "': expected name=value");
    }
    try {
      params.SetByName(kv.substr(0, eq), kv.substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("--set: ") + e.what());
    }
  }
  std::string why;
  if (!params.Validate(&why)) throw std::invalid_argument("extruder parameters: " + why);
  return params;
}

PredictionRun PredictSteps(const ExtruderParams& params, std::vector<StepInput> steps,
                           const FitRequest& fit) {
  if (fit.measured_csv.empty() != fit.params.empty())
    throw std::invalid_argument("--fit and --fit-params go together");
  PredictionRun r;
  r.params = params;
  r.steps = std::move(steps);
  CheckSteps(r.params, r.steps);
  ExtruderParams use = r.params;
  if (!fit.measured_csv.empty()) {
    const auto measured = ReadMeasurements(fit.measured_csv, r.steps);
    FitOptions fo;
    for (const auto& name : fit.params) {
      try {
        fo.params.push_back(ParamByName(name));
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(std::string("--fit-params: ") + e.what());
      }
    }
    r.fit = FitParameters(r.params, r.steps, measured, fo);
    if (!r.fit->usable) return r;
    use = r.fit->fitted;
  }
  r.prediction = Predict(use, r.steps);
  return r;
}

std::vector<std::string> WritePredictionOutputs(const PredictionRun& r, const std::string& out_dir,
                                                bool plots, std::vector<std::string>* warnings) {
  CreateOutputDirectory(out_dir);
  const Provenance prov = CurrentProvenance();
  const auto& pr = r.prediction;
  const FitSummary* fit = r.fit ? &*r.fit : nullptr;
  const ExtruderParams& used = fit ? fit->fitted : r.params;
  std::vector<std::string> written;
  auto path = [&](const char* name) { return (fs::path(out_dir) / name).string(); };
  WriteFileAtomically(path("predictions.csv"), model::PredictionsCsv(pr, prov));
  written.push_back(path("predictions.csv"));
  WriteFileAtomically(path("predictions.json"), model::PredictionsJson(pr, used, prov, fit));
  written.push_back(path("predictions.json"));
  if (fit) {
    WriteFileAtomically(path("fitted_params.yaml"),
                        model::ExtruderToYaml(fit->fitted, prov, fit->values));
    written.push_back(path("fitted_params.yaml"));
  }
  if (!plots) return written;

  auto plot = [&](const PlotSpec& spec, const char* name) {
    std::string why;
    if (PlotToPng(spec, path(name), &why)) {
      written.push_back(path(name));
    } else {
      warnings->push_back(fmt::format("{}: not drawn: {}", name, why));
    }
  };
  const bool absolute = pr.gain_m_s2_per_n.has_value();
  PlotSpec amp;
  amp.title = fmt::format("Bar-mount vibration at {:.1f} Hz against effective nozzle diameter ({})",
                          used.Get(Param::kNaturalFrequencyHz), used.origin);
  amp.x_label = "effective diameter (µm)";
  amp.y_label = absolute ? "amplitude (m/s²)" : "relative amplitude A/A_0";
  PlotSeries model_series{"model", {}, {}, {}, "linespoints"};
  for (const auto& s : pr.steps) {
    model_series.x.push_back(s.diameter_um);
    model_series.y.push_back(absolute ? *s.amplitude_m_s2 : s.relative_amplitude);
  }
  amp.series.push_back(model_series);
  if (fit) {
    PlotSeries measured{"measured", {}, {}, {}, "points pt 7 ps 1.5"};
    for (const auto& res : fit->residuals) {
      if (res.quantity != "amplitude_m_s2" || !absolute) continue;
      for (const auto& s : pr.steps) {
        if (s.step == res.step) {
          measured.x.push_back(s.diameter_um);
          measured.y.push_back(res.measured);
        }
      }
    }
    if (!measured.x.empty()) amp.series.push_back(measured);
  }
  plot(amp, "amplitude_vs_diameter.png");

  PlotSpec spec;
  spec.title = fmt::format("Spectra near the natural frequency (damping ratio {:g})",
                           used.Get(Param::kDampingRatio));
  spec.x_label = "frequency (Hz)";
  spec.y_label = pr.spectrum_absolute ? "acceleration (m/s²)" : "relative amplitude";
  for (size_t i = 0; i < pr.steps.size(); ++i) {
    spec.series.push_back({fmt::format("step {}: {:.0f} °C, {:.1f} µm", pr.steps[i].step,
                                       pr.steps[i].temperature_c, pr.steps[i].diameter_um),
                           pr.spectrum_frequency_hz,
                           pr.spectra[i],
                           {},
                           "lines lw 2"});
  }
  plot(spec, "spectra.png");

  if (fit) {
    PlotSpec res;
    res.title = fmt::format("Fit residuals: RMS {:.2f} %", 100 * fit->rms_relative);
    res.x_label = "step";
    res.y_label = "(model − measured) / measured (%)";
    res.zero_line = true;
    for (const char* q : {"amplitude_m_s2", "current_ma"}) {
      PlotSeries s{q, {}, {}, {}, "points pt 7 ps 1.5"};
      for (const auto& rr : fit->residuals) {
        if (rr.quantity != q) continue;
        s.x.push_back(rr.step);
        s.y.push_back(100 * rr.relative);
      }
      if (!s.x.empty()) res.series.push_back(s);
    }
    plot(res, "fit_residuals.png");
  }
  return written;
}

}  // namespace clogscope::model
