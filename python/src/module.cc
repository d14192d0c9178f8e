// clogscope._core: the extension behind the Python package clogscope (python/clogscope).
#include <pybind11/pybind11.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <opencv2/core.hpp>
#include <opencv2/core/utils/logger.hpp>
#include <string>

#include "apps/cli_util.h"
#include "bindings.h"
#include "calib/solver_log.h"
#include "common/version.h"

namespace clogscope::python {
namespace {

// The level of the library's log lines on standard error ("warn" unless CLOGSCOPE_LOG says).
void SetLogLevel(const std::string& level) {
  if (level != "trace" && level != "debug" && level != "info" && level != "warn" &&
      level != "error" && level != "critical" && level != "off") {
    throw py::value_error("log level '" + level + "': expected debug, info, warn, error or off");
  }
  apps::SetUpLogging(level);
  const bool debug = level == "debug" || level == "trace";
  cv::utils::logging::setLogLevel(debug ? cv::utils::logging::LOG_LEVEL_DEBUG
                                        : cv::utils::logging::LOG_LEVEL_SILENT);
  calib::SetSolverLogging(debug);
}

}  // namespace
}  // namespace clogscope::python

PYBIND11_MODULE(_core, m) {
  namespace py = pybind11;
  using namespace clogscope::python;
  m.doc() = "ClogScope's measurement, calibration and physics (the extension; import clogscope).";
  m.attr("__version__") = clogscope::kVersion;
  const char* level = std::getenv("CLOGSCOPE_LOG");
  SetLogLevel(level ? level : "warn");
  m.def("set_log_level", &SetLogLevel, py::arg("level"),
        "Sets how much the library logs to standard error: 'debug', 'info' (what the command "
        "line prints), 'warn' (the default: frames without a width, per reason), 'error' or "
        "'off'.");
  // An OpenCV error (an input no check foresaw) as one line, as the command line words it.
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const cv::Exception& e) {
      PyErr_SetString(PyExc_RuntimeError,
                      ("image library error in " + e.func + ": " + e.err).c_str());
    }
  });
  BindMeasure(m);
  BindFrames(m);
  BindMotion(m);
  BindCalibrate(m);
  BindMeasureInputs(m);
  BindRender(m);
  BindModel(m);
  BindPhysics(m);
  BindExperiment(m);
}
