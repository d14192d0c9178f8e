#pragma once

// The extension clogscope._core, one binding file per area. Each Bind* adds its classes and
// functions to the module; module.cc calls them in order (later areas use earlier areas' types).
//
// House rules kept here: attribute and argument names carry their units; expected failures come
// back as results with a reason; contract violations (std::invalid_argument in C++) raise
// ValueError with the same one-line message; long computations release the GIL.

#include <pybind11/pybind11.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <optional>
#include <string>

namespace clogscope::python {

namespace py = pybind11;

// Path arguments take str or any os.PathLike (pathlib.Path).
using Path = std::filesystem::path;

void BindMeasure(py::module_& m);        // measure.cc: options, measurement, measure_frame, Tracker
void BindFrames(py::module_& m);         // frames.cc: images, folders, videos -> arrays
void BindMeasureInputs(py::module_& m);  // measure_inputs.cc: files, folders, videos -> table
void BindCalibrate(py::module_& m);      // calibrate.cc: pins, micrometer
void BindRender(py::module_& m);         // render.cc: synthetic scenes with truth
void BindModel(py::module_& m);          // model.cc: the predictor and its fits
void BindPhysics(py::module_& m);        // physics.cc: thermal, drive, lag
void BindExperiment(py::module_& m);     // experiment.cc: a manifest run
void BindMotion(py::module_& m);         // motion.cc: feed speed between frames

// obj.__init__(**kwargs) for a plain struct bound with def_readwrite: a default-constructed T whose
// named attributes are then set, so Options(band_start_px=20) reads like the command line. An
// unknown name raises TypeError naming it.
template <typename T>
T FromKwargs(const py::kwargs& kwargs) {
  py::object obj = py::cast(T{});
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (!py::hasattr(obj, name.c_str()) || name.rfind('_', 0) == 0)
      throw py::type_error("unknown keyword argument '" + name + "'");
    obj.attr(key) = value;
  }
  return obj.cast<T>();
}

// "Name(field=value, ...)" from the named attributes' reprs: the __repr__ of a plain struct.
std::string ReprOf(const py::handle& obj, const char* type_name,
                   std::initializer_list<const char*> fields);

}  // namespace clogscope::python
