// clogscope.measure's core: images, folders and videos measured by pipeline::MeasureInputs, the
// function `clogscope measure INPUTS` calls, its per-frame table handed back as CSV text (the
// Python layer reads it into a DataFrame), so the table is the command line's to the byte.
#include "pipeline/measure_inputs.h"

#include <pybind11/stl.h>

#include <sstream>

#include "bindings.h"
#include "calib/calibration_file.h"

namespace clogscope::python {
namespace {

using vision::StrandMeasureOptions;

// The band as `measure` asks for it: the keywords, or else the options' band fields when they are
// not the defaults (so MeasureOptions(band_start_px=…) means what it says), or else the target's
// default at the scale.
pipeline::BandRequest BandFrom(const StrandMeasureOptions& o, std::optional<double> start_um,
                               std::optional<double> height_um, std::optional<double> start_px,
                               std::optional<double> height_px) {
  pipeline::BandRequest band;
  band.start_um = start_um;
  band.height_um = height_um;
  band.start_px = start_px;
  band.height_px = height_px;
  band.start_um_name = "band_start_um";
  band.height_um_name = "band_height_um";
  band.start_px_name = "band_start_px";
  band.height_px_name = "band_height_px";
  const StrandMeasureOptions defaults;
  if (o.band_start_px != defaults.band_start_px && !start_um && !start_px)
    band.start_px = o.band_start_px;
  if (o.band_height_px != defaults.band_height_px && !height_um && !height_px)
    band.height_px = o.band_height_px;
  return band;
}

py::tuple MeasureInputsPy(const std::vector<std::string>& inputs,
                          std::optional<StrandMeasureOptions> options,
                          std::optional<double> scale_um_per_px, const py::object& calibration,
                          std::optional<double> band_start_um, std::optional<double> band_height_um,
                          std::optional<double> band_start_px, std::optional<double> band_height_px,
                          const std::string& overlay_dir, int overlay_every, bool flag_outliers,
                          bool speed, std::optional<vision::FeedSpeedOptions> speed_options,
                          std::optional<std::vector<int>> gear_roi,
                          std::optional<std::pair<double, double>> gear_centre_px,
                          std::optional<double> gear_radius_mm) {
  pipeline::MeasureInputsOptions o;
  o.inputs = inputs;
  if (options) o.strand = *options;
  o.scale_um_per_px = scale_um_per_px;
  if (py::isinstance<py::str>(calibration)) {
    o.calibration = calib::ReadCalibrationFile(calibration.cast<std::string>());
  } else if (!calibration.is_none()) {
    o.calibration = calibration.cast<calib::ScaleCalibration>();
    if (!o.calibration->usable)
      throw py::value_error("calibration not usable: " + o.calibration->message);
  }
  o.band = BandFrom(o.strand, band_start_um, band_height_um, band_start_px, band_height_px);
  o.overlay_dir = overlay_dir;
  o.overlay_every = overlay_every;
  o.flag_outliers = flag_outliers;
  o.feed_speed = speed;
  if (speed_options) o.feed = *speed_options;
  if (gear_roi) {
    if (gear_roi->size() != 4) throw py::value_error("gear_roi: expected (x, y, width, height)");
    o.gear_roi = cv::Rect((*gear_roi)[0], (*gear_roi)[1], (*gear_roi)[2], (*gear_roi)[3]);
  }
  if (gear_centre_px) o.gear_centre_px = cv::Point2d(gear_centre_px->first, gear_centre_px->second);
  o.gear_radius_mm = gear_radius_mm;
  std::ostringstream table;
  pipeline::MeasureSummary summary;
  {
    py::gil_scoped_release release;
    summary = pipeline::MeasureInputs(o, &table);
  }
  return py::make_tuple(table.str(), summary);
}

}  // namespace

void BindMeasureInputs(py::module_& m) {
  py::class_<pipeline::MeasureSummary>(m, "MeasureSummary",
                                       "What measure() read: inputs, frames, time, errors.")
      .def_readonly("inputs_ok", &pipeline::MeasureSummary::inputs_ok)
      .def_readonly("inputs_failed", &pipeline::MeasureSummary::inputs_failed,
                    "Inputs that could not be opened or measured (see errors).")
      .def_readonly("frames", &pipeline::MeasureSummary::frames)
      .def_readonly("valid_frames", &pipeline::MeasureSummary::valid_frames)
      .def_readonly("overlays_written", &pipeline::MeasureSummary::overlays_written)
      .def_readonly("seconds", &pipeline::MeasureSummary::seconds, "Wall-clock time, s.")
      .def_readonly("errors", &pipeline::MeasureSummary::errors,
                    "One line per input that could not be read.")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(
            self, "MeasureSummary",
            {"inputs_ok", "inputs_failed", "frames", "valid_frames", "seconds", "errors"});
      });

  m.def("_measure_inputs", &MeasureInputsPy, py::arg("inputs"), py::arg("options"),
        py::arg("scale_um_per_px"), py::arg("calibration"), py::arg("band_start_um"),
        py::arg("band_height_um"), py::arg("band_start_px"), py::arg("band_height_px"),
        py::arg("overlay_dir"), py::arg("overlay_every"), py::arg("flag_outliers"),
        py::arg("speed"), py::arg("speed_options"), py::arg("gear_roi"), py::arg("gear_centre_px"),
        py::arg("gear_radius_mm"),
        "pipeline::MeasureInputs with the table as CSV text: (text, MeasureSummary). Use "
        "clogscope.measure.");
}

}  // namespace clogscope::python
