// clogscope.calibrate_pins, calibrate_micrometer and the calibration's types: the pixel scale ± σ
// and edge bias from reference images (pipeline::CalibrateFromTargets, as `clogscope calibrate`),
// or from widths measured elsewhere (calib::FitPinScale), and the calibration file.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "calib/calibration_file.h"
#include "calib/pixel_scale.h"
#include "common/provenance.h"
#include "pipeline/calibrate_targets.h"

namespace clogscope::python {
namespace {

using calib::ScaleCalibration;

pipeline::TargetCalibration Calibrate(pipeline::TargetCalibrationOptions o) {
  std::string why;
  if (!o.Validate(&why)) throw py::value_error(why);
  py::gil_scoped_release release;
  return pipeline::CalibrateFromTargets(o);
}

std::string CalibrationRepr(const ScaleCalibration& c) {
  if (!c.usable) return fmt::format("ScaleCalibration(not usable: {!r})", c.message);
  return fmt::format(
      "ScaleCalibration({}, scale_um_per_px={:.6f} ± {:.6f}, edge_bias_px={:+.4f} ± {:.4f}, "
      "targets={}, rms_residual_um={:.3f})",
      c.method, c.scale_um_per_px, c.scale_sigma_um_per_px, c.edge_bias_px, c.edge_bias_sigma_px,
      c.targets, c.rms_residual_um);
}

}  // namespace

void BindCalibrate(py::module_& m) {
  py::class_<calib::TargetResidual>(m, "TargetResidual",
                                    "One reference target against the fitted scale.")
      .def_readonly("name", &calib::TargetResidual::name, "Pin image, or 'line k'.")
      .def_readonly("nominal_um", &calib::TargetResidual::nominal_um,
                    "Pin diameter, or the line's position on the scale, µm.")
      .def_readonly("measured_px", &calib::TargetResidual::measured_px)
      .def_readonly("model_px", &calib::TargetResidual::model_px)
      .def_readonly("residual_px", &calib::TargetResidual::residual_px, "measured − model, px.")
      .def_readonly("residual_um", &calib::TargetResidual::residual_um)
      .def_readonly("outlier", &calib::TargetResidual::outlier)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "TargetResidual", {"name", "nominal_um", "residual_px", "outlier"});
      });

  py::class_<ScaleCalibration>(
      m, "ScaleCalibration",
      "A fitted pixel scale (calib::ScaleCalibration): width_um = (width_px − edge_bias_px) · "
      "scale_um_per_px, each with its σ. `usable` is False with `message` saying why when the fit "
      "cannot be trusted. Also what measure() takes as calibration=.")
      .def(py::init([](double scale_um_per_px, double scale_sigma_um_per_px, double edge_bias_px,
                       double edge_bias_sigma_px) {
             if (!(scale_um_per_px > 0 && std::isfinite(scale_um_per_px)))
               throw py::value_error("scale_um_per_px: must be a positive number");
             ScaleCalibration c;
             c.usable = true;
             c.method = "given";
             c.scale_um_per_px = scale_um_per_px;
             c.scale_sigma_um_per_px = scale_sigma_um_per_px;
             c.edge_bias_px = edge_bias_px;
             c.edge_bias_sigma_px = edge_bias_sigma_px;
             return c;
           }),
           py::arg("scale_um_per_px"), py::arg("scale_sigma_um_per_px") = 0.0,
           py::arg("edge_bias_px") = 0.0, py::arg("edge_bias_sigma_px") = 0.0,
           "A calibration from known numbers (method 'given').")
      .def_readonly("usable", &ScaleCalibration::usable)
      .def_readonly("message", &ScaleCalibration::message, "Why not usable, or notes.")
      .def_readonly("method", &ScaleCalibration::method, "'pins', 'micrometer' or 'given'.")
      .def_readonly("scale_um_per_px", &ScaleCalibration::scale_um_per_px)
      .def_readonly("scale_sigma_um_per_px", &ScaleCalibration::scale_sigma_um_per_px)
      .def_readonly("edge_bias_px", &ScaleCalibration::edge_bias_px,
                    "How much wider than width/scale objects appear (blur, diffraction), px.")
      .def_readonly("edge_bias_sigma_px", &ScaleCalibration::edge_bias_sigma_px)
      .def_readonly("edge_bias_fitted", &ScaleCalibration::edge_bias_fitted)
      .def_readonly("distortion_px", &ScaleCalibration::distortion_px,
                    "Micrometer: second-order term per index², px.")
      .def_readonly("distortion_sigma_px", &ScaleCalibration::distortion_sigma_px)
      .def_readonly("distortion_fitted", &ScaleCalibration::distortion_fitted)
      .def_readonly("rms_residual_px", &ScaleCalibration::rms_residual_px)
      .def_readonly("rms_residual_um", &ScaleCalibration::rms_residual_um)
      .def_readonly("worst_residual_px", &ScaleCalibration::worst_residual_px)
      .def_readonly("worst_residual_um", &ScaleCalibration::worst_residual_um)
      .def_readonly("outliers", &ScaleCalibration::outliers)
      .def_readonly("targets", &ScaleCalibration::targets)
      .def_readonly("residuals", &ScaleCalibration::residuals,
                    "One TargetResidual per target (clogscope.residual_table makes a DataFrame).")
      .def("to_um", &ScaleCalibration::ToMicrons, py::arg("width_px"),
           "A width in px to µm: (width_px − edge_bias_px) · scale_um_per_px.")
      .def("sigma_um", &ScaleCalibration::MicronsSigma, py::arg("width_px"),
           py::arg("width_sigma_px"),
           "The σ in µm of that width: its own σ and the calibration's, in quadrature.")
      .def(
          "save",
          [](const ScaleCalibration& c, const Path& path) {
            calib::WriteCalibrationFile(path.string(), c, CurrentProvenance(), {});
          },
          py::arg("path"), "Writes the calibration file (YAML) `measure --calib` reads.")
      .def("__repr__", &CalibrationRepr);

  m.def(
      "read_calibration", [](const Path& p) { return calib::ReadCalibrationFile(p.string()); },
      py::arg("path"),
      "Reads a calibration file written by `clogscope calibrate` (or ScaleCalibration.save). "
      "Raises ValueError naming the file when it cannot be used.");

  m.def(
      "calibrate_pins",
      [](const Path& pins_csv, std::optional<vision::StrandMeasureOptions> options) {
        pipeline::TargetCalibrationOptions o;
        o.pins_csv = pins_csv.string();
        if (options) o.pin_measure = *options;
        const auto r = Calibrate(o);
        return py::make_tuple(r.calibration, r.notes);
      },
      py::arg("pins_csv"), py::arg("options") = py::none(),
      R"(The pixel scale and edge bias from images of pin gauges, as `clogscope calibrate --pins`.

pins_csv: a CSV with columns image,diameter_um[,tolerance_um] (image paths relative to the CSV).
options: MeasureOptions for reading the pins (roi, polarity); each pin is measured as a filament.

Returns (calibration, notes): a ScaleCalibration (scale_um_per_px ± scale_sigma_um_per_px,
edge_bias_px ± edge_bias_sigma_px, one TargetResidual per pin in .residuals; usable False with a
message when the fit cannot be trusted) and one line per pin measured. Raises ValueError naming the
image or row for an unreadable image, a pin not found, too few distinct diameters.)");

  m.def(
      "calibrate_micrometer",
      [](const std::vector<Path>& images, double pitch_um, bool fit_distortion,
         std::optional<double> expect_scale_um_per_px,
         std::optional<vision::StrandMeasureOptions> options) {
        pipeline::TargetCalibrationOptions o;
        for (const Path& p : images) o.micrometer_images.push_back(p.string());
        o.pitch_um = pitch_um;
        o.fit_distortion = fit_distortion;
        o.expect_scale_um_per_px = expect_scale_um_per_px;
        if (options) o.pin_measure = *options;
        const auto r = Calibrate(o);
        return py::make_tuple(r.calibration, r.notes);
      },
      py::arg("images"), py::arg("pitch_um"), py::kw_only(), py::arg("fit_distortion") = false,
      py::arg("expect_scale_um_per_px") = py::none(), py::arg("options") = py::none(),
      R"(The pixel scale from images of a stage micrometer, as `clogscope calibrate --micrometer`.

images: image paths; pitch_um: the line pitch, µm; fit_distortion: add a second-order term;
expect_scale_um_per_px: refuse a result more than 25 % from it; options: MeasureOptions (its roi).

Returns (calibration, notes) as calibrate_pins (no edge bias: a micrometer gives the scale only).
Raises ValueError naming the image for lines not found or a pitch that does not fit.)");

  py::class_<calib::PinObservation>(m, "PinObservation",
                                    "A pin of certified diameter and the width measured for it.")
      .def(py::init([](double diameter_um, double width_px, double width_sigma_px,
                       double tolerance_um, std::string name) {
             return calib::PinObservation{std::move(name), diameter_um, tolerance_um, width_px,
                                          width_sigma_px};
           }),
           py::arg("diameter_um"), py::arg("width_px"), py::arg("width_sigma_px") = 0.0,
           py::arg("tolerance_um") = 0.0, py::arg("name") = "")
      .def_readwrite("name", &calib::PinObservation::name)
      .def_readwrite("diameter_um", &calib::PinObservation::diameter_um)
      .def_readwrite("tolerance_um", &calib::PinObservation::tolerance_um,
                     "Certified tolerance, taken as one σ; 0: none given.")
      .def_readwrite("width_px", &calib::PinObservation::width_px)
      .def_readwrite("width_sigma_px", &calib::PinObservation::width_sigma_px)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "PinObservation", {"diameter_um", "width_px", "width_sigma_px"});
      });

  m.def(
      "fit_pin_scale",
      [](const std::vector<calib::PinObservation>& pins, double outlier_threshold_sigma) {
        calib::ScaleFitOptions o;
        o.outlier_threshold_sigma = outlier_threshold_sigma;
        std::string why;
        if (!o.Validate(&why)) throw py::value_error(why);
        py::gil_scoped_release release;
        return calib::FitPinScale(pins, o);
      },
      py::arg("pins"), py::arg("outlier_threshold_sigma") = 4.0,
      R"(Fits width_px = diameter_um / scale + edge_bias jointly over pins whose widths were
measured already (calib::FitPinScale, the fit behind calibrate_pins): a list of PinObservation.
Returns a ScaleCalibration. Raises ValueError naming the pin for no pins, a non-positive diameter
or width, or fewer distinct diameters than unknowns.)");
}

}  // namespace clogscope::python
