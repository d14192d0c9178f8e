// The clog physics of three more studies (docs/clog-physics.md): hot-end cooling and the critical
// softened length (model/thermal.h), roller-drive slip (model/roller_drive.h), and extrusion lag
// with its fit of K (model/extrusion_lag.h, lag_fit.h), as `thermal`, `drive` and `lag` call them.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "model/extrusion_lag.h"
#include "model/lag_fit.h"
#include "model/lag_io.h"
#include "model/roller_drive.h"
#include "model/thermal.h"

namespace clogscope::python {
namespace {

model::FlowProfile MakeProfile(const std::vector<double>& time_s,
                               const std::vector<double>& flow_mm3_s) {
  if (time_s.size() != flow_mm3_s.size())
    throw py::value_error("time_s and flow_mm3_s: not the same length");
  model::FlowProfile p{time_s, flow_mm3_s};
  std::string why;
  if (!p.Validate(&why)) throw py::value_error("profile: " + why);
  return p;
}

}  // namespace

void BindPhysics(py::module_& m) {
  // Thermal.
  py::enum_<model::Material>(m, "Material")
      .value("pla", model::Material::kPla)
      .value("abs", model::Material::kAbs);
  py::enum_<model::ClogRisk>(m, "ClogRisk")
      .value("safe", model::ClogRisk::kSafe)
      .value("marginal", model::ClogRisk::kMarginal)
      .value("clog_risk", model::ClogRisk::kClogRisk);
  py::class_<model::ThermalAssessment>(m, "ThermalAssessment",
                                       "A fan velocity or heat-sink temperature judged against "
                                       "the cooling study.")
      .def_readonly("material", &model::ThermalAssessment::material)
      .def_readonly("velocity_m_s", &model::ThermalAssessment::velocity_m_s)
      .def_readonly("t4_c", &model::ThermalAssessment::t4_c, "Heat-sink temperature, °C.")
      .def_readonly("extrapolated", &model::ThermalAssessment::extrapolated)
      .def_readonly("risk", &model::ThermalAssessment::risk)
      .def_readonly("explanation", &model::ThermalAssessment::explanation)
      .def_readonly("min_safe_velocity_m_s", &model::ThermalAssessment::min_safe_velocity_m_s)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "ThermalAssessment",
                      {"material", "velocity_m_s", "t4_c", "risk", "min_safe_velocity_m_s"});
      });
  auto material = [](const std::string& name) { return model::ParseMaterial(name); };
  m.def(
      "assess_fan_velocity",
      [material](const std::string& name, double v) {
        return model::AssessFanVelocity(material(name), v);
      },
      py::arg("material"), py::arg("velocity_m_s"),
      "Heat-sink temperature T4 from the study's correlation at a fan air velocity (m/s) and the "
      "clog risk it means ('pla' or 'abs'). Raises ValueError for a negative velocity.");
  m.def(
      "assess_heat_sink_temperature",
      [material](const std::string& name, double t4_c) {
        return model::AssessHeatSinkTemperature(material(name), t4_c);
      },
      py::arg("material"), py::arg("t4_c"),
      "The same from a measured heat-sink temperature (°C): the velocity that gives it.");
  m.def(
      "heat_sink_temperature_c",
      [material](const std::string& name, double v) {
        return model::CoolingDataOf(material(name)).correlation.T4C(v);
      },
      py::arg("material"), py::arg("velocity_m_s"),
      "T4(V) = a1·exp(−b1·V) + a2·exp(−b2·V), °C: the study's correlation.");
  m.def("critical_softened_length_m", &model::CriticalSoftenedLengthM, py::arg("modulus_pa"),
        py::arg("filament_radius_m"), py::arg("pressure_pa"),
        "Pin-ended Euler buckling of the softened filament: √(π² E R² / (4 ΔP)), m.");
  m.def("hagen_poiseuille_pressure_pa", &model::HagenPoiseuillePressurePa,
        py::arg("viscosity_pa_s"), py::arg("flow_m3_s"), py::arg("length_m"), py::arg("radius_m"),
        "8 μ Q l / (π r⁴), Pa.");
  py::class_<model::SofteningStep>(m, "SofteningStep", "L_crt at one step, both ways.")
      .def_readonly("step", &model::SofteningStep::step)
      .def_readonly("temperature_c", &model::SofteningStep::temperature_c)
      .def_readonly("diameter_um", &model::SofteningStep::diameter_um)
      .def_readonly("dp_hagen_poiseuille_pa", &model::SofteningStep::dp_hagen_poiseuille_pa)
      .def_readonly("l_crt_hagen_poiseuille_mm", &model::SofteningStep::l_crt_hagen_poiseuille_mm)
      .def_readonly("dp_power_law_pa", &model::SofteningStep::dp_power_law_pa)
      .def_readonly("l_crt_power_law_mm", &model::SofteningStep::l_crt_power_law_mm);
  m.def(
      "critical_lengths",
      [](const model::ExtruderParams& p, const std::vector<model::StepInput>& steps,
         double modulus_pa, double viscosity_pa_s, std::optional<double> hp_length_m) {
        return model::CriticalLengths(p, steps, {modulus_pa, viscosity_pa_s, hp_length_m});
      },
      py::arg("params"), py::arg("steps"), py::kw_only(), py::arg("modulus_pa"),
      py::arg("viscosity_pa_s"), py::arg("hp_length_m") = py::none(),
      "The critical softened length at every step (model::CriticalLengths, as `thermal "
      "--diameters`): a SofteningStep list.");

  // Roller drive.
  py::class_<model::RollerPreset>(m, "RollerPreset", "One roller of the slip study.")
      .def_readonly("number", &model::RollerPreset::number)
      .def_readonly("name", &model::RollerPreset::name)
      .def_readonly("kind", &model::RollerPreset::kind)
      .def_readonly("outer_diameter_mm", &model::RollerPreset::outer_diameter_mm)
      .def_readonly("k_s_pct_n", &model::RollerPreset::k_s_pct_n)
      .def_readonly("k_pct_per_n", &model::RollerPreset::k_pct_per_n)
      .def("__repr__",
           [](const model::RollerPreset& r) { return fmt::format("RollerPreset({!r})", r.name); });
  m.def("roller_presets", &model::RollerPresets, "The study's rollers.");
  py::class_<model::Slip>(m, "Slip")
      .def_readonly("pct", &model::Slip::pct, "Slip, %.")
      .def_readonly("sigma_pct", &model::Slip::sigma_pct)
      .def("__repr__", [](const model::Slip& s) {
        return fmt::format("Slip(pct={:.4g} ± {:.2g})", s.pct, s.sigma_pct);
      });
  m.def(
      "slip",
      [](const std::string& roller, double pinch_force_n, double feed_force_n, double k_p_pct,
         std::optional<double> filament_speed_mm_s) {
        const auto& r = model::RollerByName(roller);
        if (filament_speed_mm_s)
          return model::SlipVelocityForm(r, *filament_speed_mm_s, feed_force_n, k_p_pct);
        return model::SlipPinchForm(r, pinch_force_n, feed_force_n, k_p_pct);
      },
      py::arg("roller"), py::arg("pinch_force_n"), py::arg("feed_force_n"), py::kw_only(),
      py::arg("k_p_pct") = 0.0, py::arg("filament_speed_mm_s") = py::none(),
      "Slip in % with σ: s = k_p + (k_s / F_p² + k)·F_f (pinch-force form), or with "
      "filament_speed_mm_s the feed-velocity form. Raises ValueError for a pinch force ≤ 0.");
  py::class_<model::DriveStep>(m, "DriveStep", "Predicted slip at one step.")
      .def_readonly("step", &model::DriveStep::step)
      .def_readonly("temperature_c", &model::DriveStep::temperature_c)
      .def_readonly("diameter_um", &model::DriveStep::diameter_um)
      .def_readonly("f_bp_n", &model::DriveStep::f_bp_n)
      .def_readonly("feed_force_n", &model::DriveStep::feed_force_n)
      .def_readonly("slip_pinch", &model::DriveStep::slip_pinch)
      .def_readonly("slip_velocity", &model::DriveStep::slip_velocity)
      .def_readonly("commanded_flow_mm3_s", &model::DriveStep::commanded_flow_mm3_s)
      .def_readonly("delivered_flow_mm3_s", &model::DriveStep::delivered_flow_mm3_s)
      .def_readonly("measured_slip_pct", &model::DriveStep::measured_slip_pct);
  py::class_<model::DrivePrediction>(m, "DrivePrediction")
      .def_readonly("roller", &model::DrivePrediction::roller)
      .def_readonly("filament_speed_mm_s", &model::DrivePrediction::filament_speed_mm_s)
      .def_readonly("pinch_below_minimum", &model::DrivePrediction::pinch_below_minimum)
      .def_readonly("velocity_form_extrapolated",
                    &model::DrivePrediction::velocity_form_extrapolated)
      .def_readonly("steps", &model::DrivePrediction::steps);
  m.def(
      "predict_drive",
      [](const model::ExtruderParams& p, const std::vector<model::StepInput>& steps,
         const std::string& roller, double pinch_force_n, double friction_n, double k_p_pct,
         const std::vector<std::optional<double>>& measured_slip_pct) {
        model::DriveOptions o{roller, pinch_force_n, friction_n, k_p_pct};
        std::string why;
        if (!o.Validate(&why)) throw py::value_error(why);
        return model::PredictDrive(p, steps, o, measured_slip_pct);
      },
      py::arg("params"), py::arg("steps"), py::kw_only(), py::arg("roller") = "3-hobb-goblin",
      py::arg("pinch_force_n"), py::arg("friction_n") = 0.0, py::arg("k_p_pct") = 0.0,
      py::arg("measured_slip_pct") = std::vector<std::optional<double>>{},
      "Slip at every step of a diameter table (model::PredictDrive, as `drive --diameters`).");

  // Extrusion lag.
  py::class_<model::FlowProfile>(m, "FlowProfile",
                                 "A commanded flow, piecewise linear through its knots (mm³/s "
                                 "against s); two knots at one time make a step.")
      .def(py::init(&MakeProfile), py::arg("time_s"), py::arg("flow_mm3_s"))
      .def_readonly("time_s", &model::FlowProfile::time_s)
      .def_readonly("flow_mm3_s", &model::FlowProfile::flow_mm3_s)
      .def("at", &model::FlowProfile::At, py::arg("t_s"));
  m.def("profile_from_moves", &model::ProfileFromMoves, py::arg("start_s"), py::arg("flow_mm3_s"),
        "Rows (t_i, q_i) where q_i holds until t_(i+1), as G-code moves do.");
  m.def(
      "read_flow_profile",
      [](const Path& path, const std::string& form, double filament_diameter_mm) {
        return model::ReadFlowProfile(path.string(), model::ParseProfileForm(form),
                                      filament_diameter_mm);
      },
      py::arg("path"), py::arg("form") = "moves", py::arg("filament_diameter_mm") = 1.75,
      "A profile CSV (time_s with flow_mm3_s or filament_speed_mm_s), as `lag --commanded`.");
  m.def(
      "simulate_lag",
      [](const model::FlowProfile& p, double k_s, double k_la_s, double dt_s,
         std::optional<std::vector<double>> times_s) {
        if (!(k_s > 0)) throw py::value_error("k_s: must be positive");
        const std::vector<double> t = times_s ? *times_s : model::SimulationTimes(p, k_s, dt_s);
        return py::make_tuple(t, model::OutletFlow(p, k_s, k_la_s, t));
      },
      py::arg("profile"), py::arg("k_s"), py::kw_only(), py::arg("k_la_s") = 0.0,
      py::arg("dt_s") = 0.001, py::arg("times_s") = py::none(),
      "The outlet flow of the first-order lag K·dQ_out/dt + Q_out = Q_in (with linear advance "
      "k_la_s): (times_s, outlet_mm3_s), at times_s or from the profile's start − 5K to its end + "
      "5K every dt_s. As `lag --k-s`.");
  py::class_<model::LagFitSummary>(m, "LagFit", "K fitted to a width series, every number ± σ.")
      .def_readonly("usable", &model::LagFitSummary::usable)
      .def_readonly("message", &model::LagFitSummary::message)
      .def_readonly("k_s", &model::LagFitSummary::k_s)
      .def_readonly("k_sigma_s", &model::LagFitSummary::k_sigma_s)
      .def_readonly("gain", &model::LagFitSummary::gain, "Width per mm³/s (the widths' unit).")
      .def_readonly("gain_sigma", &model::LagFitSummary::gain_sigma)
      .def_readonly("offset_s", &model::LagFitSummary::offset_s)
      .def_readonly("offset_sigma_s", &model::LagFitSummary::offset_sigma_s)
      .def_readonly("k_la_s", &model::LagFitSummary::k_la_s, "Linear advance to set: K.")
      .def_readonly("rms", &model::LagFitSummary::rms)
      .def_readonly("samples_used", &model::LagFitSummary::samples_used)
      .def_readonly("outliers", &model::LagFitSummary::outliers)
      .def_readonly("fitted_width", &model::LagFitSummary::fitted_width)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "LagFit", {"usable", "k_s", "k_sigma_s", "gain", "offset_s", "rms"});
      });
  m.def(
      "fit_lag",
      [](const model::FlowProfile& p, const std::vector<double>& time_s,
         const std::vector<double>& width, double max_offset_s, double min_k_s, double max_k_s) {
        if (time_s.size() != width.size())
          throw py::value_error("time_s and width: not the same length");
        std::vector<model::WidthSample> samples;
        for (size_t i = 0; i < time_s.size(); ++i) samples.push_back({time_s[i], width[i]});
        model::LagFitOptions o;
        o.max_offset_s = max_offset_s;
        o.min_k_s = min_k_s;
        o.max_k_s = max_k_s;
        std::string why;
        if (!o.Validate(&why)) throw py::value_error(why);
        py::gil_scoped_release release;
        return model::FitLag(p, samples, o);
      },
      py::arg("profile"), py::arg("time_s"), py::arg("width"), py::kw_only(),
      py::arg("max_offset_s") = 0.5, py::arg("min_k_s") = 1e-3, py::arg("max_k_s") = 10.0,
      R"(Fits the extrusion lag K to a width series (model::FitLag, as `lag --frames`):
width(t) = gain · Q_out(t − offset; K). time_s and width (any unit: the gain carries it) from the
valid frames. Returns a LagFit. Raises ValueError for fewer than 8 samples, times not ascending, or
a profile that does not overlap the samples or does not change there.)");
}

}  // namespace clogscope::python
