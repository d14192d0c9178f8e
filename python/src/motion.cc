// clogscope.feed_speed and FeedSpeedTracker: how far a filament's surface texture moved between
// frames (vision/motion/feed_speed.h), the speed `measure --speed` reports.
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <mutex>
#include <opencv2/imgproc.hpp>

#include "arrays.h"
#include "bindings.h"
#include "vision/motion/feed_speed.h"
#include "vision/scene/strand_measure.h"

namespace clogscope::python {
namespace {

using vision::FeedSpeedOptions;

void ValidateFeed(const FeedSpeedOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw py::value_error("speed options: " + why);
}

cv::Mat Grey(const cv::Mat& frame) {
  if (frame.channels() == 1) return frame;
  cv::Mat grey;
  cv::cvtColor(frame, grey, frame.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

// The shift between two frames along a filament's axis, as one object for Python.
struct FeedShift {
  vision::AxisShift shift;
  double dt_s = 0;
  std::optional<double> scale_um_per_px;
  vision::StrandMeasurement geometry;
  std::optional<double> SpeedMmS() const {
    if (!shift.valid() || !scale_um_per_px) return std::nullopt;
    return shift.shift_px / dt_s * *scale_um_per_px * 1e-3;
  }
  std::optional<double> SigmaMmS() const {
    if (!shift.valid() || !scale_um_per_px) return std::nullopt;
    return shift.sigma_px / dt_s * *scale_um_per_px * 1e-3;
  }
};

FeedShift FeedSpeed(const py::array& a, const py::array& b, double dt_s,
                    std::optional<double> scale_um_per_px,
                    std::optional<vision::StrandMeasurement> geometry,
                    std::optional<FeedSpeedOptions> options) {
  if (!(dt_s > 0 && std::isfinite(dt_s)))
    throw py::value_error("dt_s: the time between the frames must be positive");
  if (scale_um_per_px && !(*scale_um_per_px > 0 && std::isfinite(*scale_um_per_px)))
    throw py::value_error("scale_um_per_px: must be a positive number");
  const FeedSpeedOptions o = options ? *options : FeedSpeedOptions{};
  ValidateFeed(o);
  const cv::Mat va = MatView(a, "frame_a"), vb = MatView(b, "frame_b");
  if (va.size() != vb.size() || va.type() != vb.type())
    throw py::value_error("frame_b: not the size and type of frame_a");
  FeedShift r;
  r.dt_s = dt_s;
  r.scale_um_per_px = scale_um_per_px;
  py::gil_scoped_release release;
  if (geometry) {
    r.geometry = *geometry;
  } else {
    vision::StrandMeasureOptions mo;
    mo.target = vision::MeasureTarget::kFilament;
    mo.band_start_px = 0;
    mo.band_height_px = vision::kWholeStretchPx;
    r.geometry = vision::MeasureStrand(va, mo);
  }
  if (!r.geometry.has_geometry) {
    r.shift.status = vision::FeedShiftStatus::kNoStrand;
    r.shift.detail = "no filament found in frame_a: " + r.geometry.detail;
    return r;
  }
  r.shift = vision::EstimateFeedShift(Grey(va), Grey(vb), r.geometry, o);
  return r;
}

class FeedTracker {
 public:
  explicit FeedTracker(const FeedSpeedOptions& o) : tracker_(o) {}
  vision::FeedSpeedSample Next(const py::array& frame, double time_s,
                               const vision::StrandMeasurement& m) {
    const cv::Mat view = MatView(frame);
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
    return tracker_.Next(view, time_s, m);
  }

 private:
  vision::FeedSpeedTracker tracker_;
  std::mutex mutex_;
};

}  // namespace

void BindMotion(py::module_& m) {
  py::class_<FeedSpeedOptions>(m, "SpeedOptions",
                               "How feed speed is read from a filament's surface texture "
                               "(vision::FeedSpeedOptions); keywords as the attributes.")
      .def(py::init([](const py::kwargs& kw) { return FromKwargs<FeedSpeedOptions>(kw); }))
      .def_readwrite("inner_fraction", &FeedSpeedOptions::inner_fraction,
                     "Share of the width sampled, centred.")
      .def_readwrite("max_shift_px", &FeedSpeedOptions::max_shift_px,
                     "Search range per frame pair, px.")
      .def_readwrite("min_texture_ratio", &FeedSpeedOptions::min_texture_ratio,
                     "Texture σ over the profile's noise σ.")
      .def_readwrite("min_correlation", &FeedSpeedOptions::min_correlation)
      .def_readwrite("highpass_sigma_px", &FeedSpeedOptions::highpass_sigma_px)
      .def_readwrite("smooth_sigma_px", &FeedSpeedOptions::smooth_sigma_px)
      .def_readwrite("baseline_shift_px", &FeedSpeedOptions::baseline_shift_px)
      .def_readwrite("max_baseline_frames", &FeedSpeedOptions::max_baseline_frames)
      .def("validate", &ValidateFeed, "Raises ValueError when the options cannot be used.")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(
            self, "SpeedOptions",
            {"inner_fraction", "max_shift_px", "min_texture_ratio", "min_correlation",
             "highpass_sigma_px", "smooth_sigma_px", "baseline_shift_px", "max_baseline_frames"});
      });

  py::enum_<vision::FeedShiftStatus>(m, "ShiftStatus", "Why a frame pair gives no shift.")
      .value("valid", vision::FeedShiftStatus::kValid)
      .value("no_texture", vision::FeedShiftStatus::kNoTexture)
      .value("too_fast", vision::FeedShiftStatus::kTooFast)
      .value("no_strand", vision::FeedShiftStatus::kNoStrand);

  py::class_<FeedShift>(m, "FeedShift",
                        "The surface's shift between two frames and the speed it gives.")
      .def_property_readonly("status", [](const FeedShift& f) { return f.shift.status; })
      .def_property_readonly("valid", [](const FeedShift& f) { return f.shift.valid(); })
      .def_property_readonly("detail", [](const FeedShift& f) { return f.shift.detail; })
      .def_property_readonly(
          "shift_px", [](const FeedShift& f) { return f.shift.shift_px; },
          "How far the surface moved down the axis from frame_a to frame_b.")
      .def_property_readonly("sigma_px", [](const FeedShift& f) { return f.shift.sigma_px; })
      .def_property_readonly("correlation", [](const FeedShift& f) { return f.shift.correlation; })
      .def_property_readonly("texture_ratio",
                             [](const FeedShift& f) { return f.shift.texture_ratio; })
      .def_readonly("dt_s", &FeedShift::dt_s)
      .def_property_readonly(
          "speed_px_s", [](const FeedShift& f) { return f.shift.shift_px / f.dt_s; }, "px/s.")
      .def_property_readonly(
          "sigma_px_s", [](const FeedShift& f) { return f.shift.sigma_px / f.dt_s; }, "px/s.")
      .def_property_readonly("speed_mm_s", &FeedShift::SpeedMmS,
                             "mm/s (None without a scale or a valid shift).")
      .def_property_readonly("sigma_mm_s", &FeedShift::SigmaMmS)
      .def_readonly("geometry", &FeedShift::geometry,
                    "The filament's Measurement the frames were sampled along.")
      .def("__repr__", [](const FeedShift& f) {
        if (!f.shift.valid())
          return fmt::format("FeedShift(status={}, detail={!r})",
                             vision::FeedShiftStatusName(f.shift.status), f.shift.detail);
        return fmt::format("FeedShift(shift_px={:.4f} ± {:.4f}, speed_px_s={:.3f})",
                           f.shift.shift_px, f.shift.sigma_px, f.shift.shift_px / f.dt_s);
      });

  m.def("feed_speed", &FeedSpeed, py::arg("frame_a"), py::arg("frame_b"), py::arg("dt_s"),
        py::kw_only(), py::arg("scale_um_per_px") = py::none(), py::arg("geometry") = py::none(),
        py::arg("options") = py::none(),
        R"(The feed speed of a filament between two frames (vision::EstimateFeedShift): its surface
texture's shift along the axis over dt_s, the time between them in s.

frame_a, frame_b: arrays as measure_frame takes them, same size and type (colour read as grey).
scale_um_per_px: gives speed_mm_s. geometry: the filament's Measurement in frame_a (default:
frame_a measured with Target.filament along its whole straight stretch). options: SpeedOptions.

Returns a FeedShift: shift_px ± sigma_px, speed_px_s, speed_mm_s, or a status (no_texture,
too_fast, no_strand) when there is none. Raises ValueError for frames of another type or size.)");

  py::class_<vision::FeedSpeedSample>(m, "FeedSpeedSample", "One frame's feed speed.")
      .def_readonly("valid", &vision::FeedSpeedSample::valid)
      .def_property_readonly(
          "reason",
          [](const vision::FeedSpeedSample& s) {
            return s.valid ? std::string() : std::string(vision::SpeedReasonName(s.reason));
          },
          "When not valid: first_frame, no_time, bad_time, no_strand, no_texture, too_fast.")
      .def_readonly("detail", &vision::FeedSpeedSample::detail)
      .def_readonly("shift_px", &vision::FeedSpeedSample::shift_px)
      .def_readonly("sigma_px", &vision::FeedSpeedSample::sigma_px)
      .def_readonly("dt_s", &vision::FeedSpeedSample::dt_s)
      .def_readonly("baseline_frames", &vision::FeedSpeedSample::baseline_frames)
      .def_property_readonly("speed_px_s", &vision::FeedSpeedSample::SpeedPxPerS)
      .def_property_readonly("sigma_px_s", &vision::FeedSpeedSample::SigmaPxPerS)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "FeedSpeedSample",
                      {"valid", "reason", "shift_px", "sigma_px", "dt_s", "baseline_frames"});
      });

  py::class_<FeedTracker>(m, "FeedSpeedTracker",
                          "Feed speed frame by frame along a video (vision::FeedSpeedTracker), "
                          "as `measure --speed`: next(frame, time_s, measurement) with each "
                          "frame's Measurement (from a Tracker with Target.filament).")
      .def(py::init([](std::optional<FeedSpeedOptions> o) {
             const FeedSpeedOptions opt = o ? *o : FeedSpeedOptions{};
             ValidateFeed(opt);
             return std::make_unique<FeedTracker>(opt);
           }),
           py::arg("options") = py::none())
      .def("next", &FeedTracker::Next, py::arg("frame"), py::arg("time_s"), py::arg("measurement"),
           "The frame's FeedSpeedSample (time_s: its own timestamp, s; < 0 for none).");
}

}  // namespace clogscope::python
