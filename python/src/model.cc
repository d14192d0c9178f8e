// The predictor (model/): extruder parameters, diameter steps in, back-pressure, vibration and
// motor current out; the Ceres fit of unknown parameters to measured amplitudes or currents; and
// the prediction run `predict` and `run` make (model::PredictSteps, apps::ComputePrediction).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "apps/predict_command.h"
#include "bindings.h"
#include "common/provenance.h"
#include "model/fit.h"
#include "model/io.h"
#include "model/parameters.h"
#include "model/prediction_run.h"
#include "model/predictor.h"

namespace clogscope::python {
namespace {

using model::ExtruderParams;
using model::Param;

py::object GetParam(const ExtruderParams& p, const std::string& name) {
  const Param id = model::ParamByName(name);
  if (!p.Has(id)) return py::none();
  return py::float_(p.Get(id));
}

void SetParam(ExtruderParams& p, const std::string& name, const py::object& value) {
  if (value.is_none()) {
    p.Unset(model::ParamByName(name));
    return;
  }
  // Through SetByName, as --set does: the same names and messages (load_model takes a string).
  p.SetByName(name, py::isinstance<py::str>(value) ? value.cast<std::string>()
                                                   : fmt::format("{:.17g}", value.cast<double>()));
}

py::dict ParamsDict(const ExtruderParams& p) {
  py::dict d;
  for (const auto& info : model::AllParams())
    if (p.Has(info.id)) d[info.name] = p.Get(info.id);
  d["load_model"] = model::LoadModelName(p.load_model);
  return d;
}

model::StepInput MakeStep(int step, double temperature_c, std::optional<double> diameter_um,
                          std::optional<double> diameter_m,
                          std::optional<double> filament_diameter_um) {
  if (diameter_um.has_value() == diameter_m.has_value())
    throw py::value_error("step " + std::to_string(step) + ": give diameter_um or diameter_m");
  model::StepInput s;
  s.step = step;
  s.temperature_c = temperature_c;
  s.diameter_m = diameter_um ? *diameter_um * 1e-6 : *diameter_m;
  if (filament_diameter_um) s.filament_diameter_m = *filament_diameter_um * 1e-6;
  return s;
}

}  // namespace

void BindModel(py::module_& m) {
  py::class_<ExtruderParams>(
      m, "ExtruderParams",
      "Every parameter of the predictor, SI units, by name (model::ExtruderParams): get(name), "
      "set(name, value), to_dict(). Make one with load_extruder.")
      .def("get", &GetParam, py::arg("name"),
           "The value (SI units, as the name says), or None when an optional one is absent.")
      .def("set", &SetParam, py::arg("name"), py::arg("value"),
           "Sets by name as --set does (None unsets an optional one); 'load_model' takes 'sum' or "
           "'difference'. Raises ValueError naming the parameter.")
      .def("has", [](const ExtruderParams& p,
                     const std::string& n) { return p.Has(model::ParamByName(n)); })
      .def("to_dict", &ParamsDict, "{name: value} of the parameters present, and load_model.")
      .def_readonly("origin", &ExtruderParams::origin, "Preset name or file it came from.")
      .def(
          "validate",
          [](const ExtruderParams& p) {
            std::string why;
            if (!p.Validate(&why)) throw py::value_error(why);
          },
          "Raises ValueError naming the parameter out of its range.")
      .def(
          "to_yaml",
          [](const ExtruderParams& p) { return model::ExtruderToYaml(p, CurrentProvenance()); },
          "The parameter file load_extruder reads back.")
      .def("__repr__", [](const ExtruderParams& p) {
        return fmt::format("ExtruderParams(origin={!r}, {} parameters)", p.origin,
                           py::len(ParamsDict(p)) - 1);
      });

  m.def(
      "parameter_info",
      [] {
        py::list out;
        for (const auto& i : model::AllParams()) {
          out.append(py::dict(py::arg("name") = i.name, py::arg("meaning") = i.meaning,
                              py::arg("optional") = i.optional, py::arg("lower") = i.lower,
                              py::arg("upper") = i.upper));
        }
        return out;
      },
      "Every predictor parameter: name, meaning, optional, and its physical range (SI).");
  m.def("extruder_presets", &ExtruderParams::PresetNames, "The preset names load_extruder takes.");
  m.def(
      "load_extruder",
      [](const Path& extruder, const std::vector<std::string>& set) {
        return model::LoadExtruderWithOverrides(extruder.string(), set);
      },
      py::arg("extruder") = "direct-pla", py::arg("set") = std::vector<std::string>{},
      "A preset ('direct-pla', 'bowden-pla') or YAML parameter file, with 'name=value' "
      "overrides applied in order (as --extruder and --set). Raises ValueError naming the "
      "parameter or file.");

  py::class_<model::StepInput>(m, "StepInput",
                               "One clog stage: the effective diameter and its temperature.")
      .def(py::init(&MakeStep), py::arg("step"), py::arg("temperature_c"), py::kw_only(),
           py::arg("diameter_um") = py::none(), py::arg("diameter_m") = py::none(),
           py::arg("filament_diameter_um") = py::none())
      .def_readwrite("step", &model::StepInput::step)
      .def_readwrite("temperature_c", &model::StepInput::temperature_c)
      .def_readwrite("diameter_m", &model::StepInput::diameter_m)
      .def_property(
          "diameter_um", [](const model::StepInput& s) { return s.diameter_m * 1e6; },
          [](model::StepInput& s, double um) { s.diameter_m = um * 1e-6; })
      .def_readwrite("filament_diameter_m", &model::StepInput::filament_diameter_m,
                     "The step's measured feedstock (replaces the preset's d_f), or None.")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "StepInput", {"step", "temperature_c", "diameter_um"});
      });
  m.def(
      "read_diameter_table",
      [](const Path& p, double t) { return model::ReadDiameterTable(p.string(), t); },
      py::arg("path"), py::arg("default_temperature_c"),
      "The steps of a diameter table (diameters.csv of run, or any CSV with step, mean_um and "
      "optionally temperature_c). Raises ValueError naming the file and line.");

  py::class_<model::StepPrediction>(m, "StepPrediction", "predictor.md §8, one step.")
      .def_readonly("step", &model::StepPrediction::step)
      .def_readonly("temperature_c", &model::StepPrediction::temperature_c)
      .def_readonly("diameter_um", &model::StepPrediction::diameter_um)
      .def_readonly("dp1_pa", &model::StepPrediction::dp1_pa)
      .def_readonly("dp2_pa", &model::StepPrediction::dp2_pa)
      .def_readonly("dp3_pa", &model::StepPrediction::dp3_pa)
      .def_readonly("dp_total_pa", &model::StepPrediction::dp_total_pa,
                    "Back-pressure: the zones' drops with the Arrhenius shift, Pa.")
      .def_readonly("f_bp_n", &model::StepPrediction::f_bp_n, "Back-pressure force, N.")
      .def_readonly("f_feed_n", &model::StepPrediction::f_feed_n)
      .def_readonly("load_n", &model::StepPrediction::load_n)
      .def_readonly("relative_amplitude", &model::StepPrediction::relative_amplitude, "A / A_0.")
      .def_readonly("amplitude_increase_pct", &model::StepPrediction::amplitude_increase_pct)
      .def_readonly("amplitude_m_s2", &model::StepPrediction::amplitude_m_s2,
                    "When the gain is known, else None.")
      .def_readonly("natural_frequency_hz", &model::StepPrediction::natural_frequency_hz)
      .def_readonly("current_ma", &model::StepPrediction::current_ma,
                    "Motor current when I_0 and its gain are known, else None.")
      .def_readonly("buckling_ratio", &model::StepPrediction::buckling_ratio)
      .def_readonly("filament_diameter_um", &model::StepPrediction::filament_diameter_um)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "StepPrediction",
                      {"step", "diameter_um", "dp_total_pa", "relative_amplitude", "current_ma"});
      });

  py::class_<model::Prediction>(m, "Prediction", "The predictor's output for a list of steps.")
      .def_readonly("steps", &model::Prediction::steps, "StepPrediction per step.")
      .def_readonly("reference_load_n", &model::Prediction::reference_load_n)
      .def_readonly("feed_force_n", &model::Prediction::feed_force_n)
      .def_readonly("beam_frequency_hz", &model::Prediction::beam_frequency_hz)
      .def_readonly("gain_m_s2_per_n", &model::Prediction::gain_m_s2_per_n)
      .def_readonly("gain_source", &model::Prediction::gain_source)
      .def_readonly("spectrum_frequency_hz", &model::Prediction::spectrum_frequency_hz)
      .def_readonly("spectra", &model::Prediction::spectra)
      .def_readonly("spectrum_absolute", &model::Prediction::spectrum_absolute);
  m.def(
      "predict",
      [](const ExtruderParams& p, const std::vector<model::StepInput>& steps) {
        return model::Predict(p, steps);
      },
      py::arg("params"), py::arg("steps"),
      "Runs the predictor (model::Predict) on steps (StepInput list). Raises ValueError naming "
      "the step or parameter.");

  py::class_<model::Measurement>(m, "MeasuredResponse",
                                 "What was measured at one step, for fits: the accelerometer's "
                                 "amplitude and/or the motor current.")
      .def(py::init([](int step, std::optional<double> amplitude_m_s2,
                       std::optional<double> current_ma) {
             return model::Measurement{step, amplitude_m_s2, current_ma, 0};
           }),
           py::arg("step"), py::kw_only(), py::arg("amplitude_m_s2") = py::none(),
           py::arg("current_ma") = py::none())
      .def_readwrite("step", &model::Measurement::step)
      .def_readwrite("amplitude_m_s2", &model::Measurement::amplitude_m_s2)
      .def_readwrite("current_ma", &model::Measurement::current_ma);
  m.def(
      "read_measurements",
      [](const Path& p, const std::vector<model::StepInput>& steps) {
        return model::ReadMeasurements(p.string(), steps);
      },
      py::arg("path"), py::arg("steps"),
      "Measured amplitude_m_s2 and/or current_ma by step or temperature_c (CSV).");

  py::class_<model::FittedValue>(m, "FittedValue")
      .def_property_readonly(
          "name", [](const model::FittedValue& v) { return model::InfoOf(v.param).name; })
      .def_readonly("initial", &model::FittedValue::initial)
      .def_readonly("value", &model::FittedValue::value)
      .def_readonly("sigma", &model::FittedValue::sigma,
                    "From the covariance scaled by the residual variance; NaN when not separable.")
      .def_readonly("at_bound", &model::FittedValue::at_bound)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "FittedValue", {"name", "value", "sigma", "at_bound"});
      });
  py::class_<model::FitResidual>(m, "FitResidual")
      .def_readonly("step", &model::FitResidual::step)
      .def_readonly("quantity", &model::FitResidual::quantity)
      .def_readonly("measured", &model::FitResidual::measured)
      .def_readonly("model", &model::FitResidual::model)
      .def_readonly("relative", &model::FitResidual::relative, "(model − measured) / measured.");
  py::class_<model::FitSummary>(m, "FitSummary",
                                "A fit's outcome: usable False with message when the solver did "
                                "not converge or the unknowns cannot be told apart.")
      .def_readonly("usable", &model::FitSummary::usable)
      .def_readonly("message", &model::FitSummary::message)
      .def_readonly("values", &model::FitSummary::values, "FittedValue per unknown.")
      .def_readonly("residuals", &model::FitSummary::residuals)
      .def_readonly("rms_relative", &model::FitSummary::rms_relative)
      .def_readonly("worst_relative", &model::FitSummary::worst_relative)
      .def_readonly("iterations", &model::FitSummary::iterations)
      .def_readonly("fitted", &model::FitSummary::fitted, "The parameters with the fitted values.")
      .def_readonly("solver_report", &model::FitSummary::solver_report)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "FitSummary", {"usable", "message", "values", "rms_relative"});
      });
  m.def(
      "fit_parameters",
      [](const ExtruderParams& start, const std::vector<model::StepInput>& steps,
         const std::vector<model::Measurement>& measured, const std::vector<std::string>& unknowns,
         int max_iterations) {
        model::FitOptions o;
        for (const auto& n : unknowns) o.params.push_back(model::ParamByName(n));
        o.max_iterations = max_iterations;
        std::string why;
        if (!o.Validate(&why)) throw py::value_error(why);
        py::gil_scoped_release release;
        return model::FitParameters(start, steps, measured, o);
      },
      py::arg("start"), py::arg("steps"), py::arg("measured"), py::arg("unknowns"),
      py::arg("max_iterations") = 200,
      R"(Fits the named unknown parameters (e.g. ['consistency_pa_sn', 'gain']) to measured
amplitudes or currents (model::FitParameters: Ceres, relative residuals, each unknown bounded to
its physical range). Returns a FitSummary (values with σ, residuals; fitted holds the parameters).
Raises ValueError for no unknowns, more unknowns than measurements, a measurement without a step.)");

  py::class_<model::PredictionRun>(m, "PredictionRun",
                                   "What `predict` computes: parameters, steps, fit, prediction.")
      .def_readonly("params", &model::PredictionRun::params)
      .def_readonly("steps", &model::PredictionRun::steps)
      .def_readonly("fit", &model::PredictionRun::fit, "FitSummary, or None without a fit.")
      .def_readonly("prediction", &model::PredictionRun::prediction);
  m.def(
      "predict_steps",
      [](const ExtruderParams& p, std::vector<model::StepInput> steps, const Path& measured_csv,
         const std::vector<std::string>& fit_params) {
        py::gil_scoped_release release;
        return model::PredictSteps(p, std::move(steps), {measured_csv.string(), fit_params});
      },
      py::arg("params"), py::arg("steps"), py::kw_only(), py::arg("measured_csv") = "",
      py::arg("fit_params") = std::vector<std::string>{},
      "The prediction `run` makes from its steps (model::PredictSteps): with measured_csv and "
      "fit_params, the unknowns fitted first. Returns a PredictionRun.");
  m.def(
      "predict_table",
      [](const Path& diameters, const Path& extruder, const std::vector<std::string>& set,
         const Path& fit_measured, const std::vector<std::string>& fit_params) {
        apps::PredictCommandOptions o;
        o.diameters = diameters.string();
        o.extruder = extruder.string();
        o.set = set;
        o.fit_measured = fit_measured.string();
        o.fit_params = fit_params;
        py::gil_scoped_release release;
        return apps::ComputePrediction(o);
      },
      py::arg("diameters"), py::kw_only(), py::arg("extruder") = "direct-pla",
      py::arg("set") = std::vector<std::string>{}, py::arg("fit_measured") = "",
      py::arg("fit_params") = std::vector<std::string>{},
      "`clogscope predict --diameters` without its files (apps::ComputePrediction): the table "
      "read, the extruder loaded with its overrides, fitted when asked, predicted. Returns a "
      "PredictionRun.");
}

}  // namespace clogscope::python
