// clogscope.measure_frame, clogscope.Tracker and their types: one frame in (a NumPy array, no
// copy), its strand width with σ or a reason out (vision::MeasureStrand, vision::StrandTracker).
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <mutex>

#include "arrays.h"
#include "bindings.h"
#include "vision/scene/frame_status.h"
#include "vision/scene/strand_measure.h"
#include "vision/scene/track.h"

namespace clogscope::python {
namespace {

using vision::FrameStatus;
using vision::StrandMeasurement;
using vision::StrandMeasureOptions;

py::object RoiOf(const cv::Rect& r) {
  if (r.empty()) return py::none();
  return py::make_tuple(r.x, r.y, r.width, r.height);
}

cv::Rect RoiFrom(const py::object& o) {
  if (o.is_none()) return {};
  const auto v = o.cast<std::vector<int>>();
  if (v.size() != 4) throw py::value_error("roi: expected (x, y, width, height) in px, or None");
  return {v[0], v[1], v[2], v[3]};
}

void ValidateOptions(const StrandMeasureOptions& o) {
  std::string why;
  if (!o.Validate(&why)) throw py::value_error("measure options: " + why);
}

// How many measurements are inside the library at once (the GIL released) and the most seen since
// last asked: the tests' evidence that threads measure concurrently. Two atomics per frame.
std::atomic<int> g_inside{0}, g_peak{0};
struct Inside {
  Inside() {
    const int n = ++g_inside;
    int peak = g_peak.load();
    while (n > peak && !g_peak.compare_exchange_weak(peak, n)) {
    }
  }
  ~Inside() { --g_inside; }
};

// The frame as the library sees it; the array stays referenced by the caller meanwhile.
StrandMeasurement MeasureArray(const py::array& frame, const StrandMeasureOptions& options) {
  const cv::Mat view = MatView(frame);
  py::gil_scoped_release release;
  Inside inside;
  return vision::MeasureStrand(view, options);
}

// A StrandTracker for Python: one frame at a time (a lock, since the GIL is released while it
// measures and two threads may share one tracker).
class Tracker {
 public:
  Tracker(const StrandMeasureOptions& options, const vision::X264Settings& encoder)
      : options_(options), tracker_(options) {
    tracker_.SetEncoder(encoder);
  }
  // Without a range, the options' (or the last frame's given one).
  StrandMeasurement Measure(const py::array& frame, std::optional<vision::LumaRange> luma_range) {
    vision::InputFrame in;
    in.image = MatView(frame);
    py::gil_scoped_release release;
    std::lock_guard<std::mutex> lock(mutex_);
    Inside inside;
    if (!luma_range) return tracker_.Measure(in.image);
    in.luma_range = *luma_range;
    return tracker_.Measure(in);
  }
  void Reset() {
    std::lock_guard<std::mutex> lock(mutex_);
    tracker_.Reset();
  }
  const StrandMeasureOptions& options() const { return options_; }
  int full_detections() const { return tracker_.full_detections(); }
  int tracked_frames() const { return tracker_.tracked_frames(); }

 private:
  StrandMeasureOptions options_;
  vision::StrandTracker tracker_;
  std::mutex mutex_;
};

std::string MeasurementRepr(const StrandMeasurement& m) {
  if (!m.valid()) {
    return fmt::format("Measurement(status={}, detail={!r})", vision::FrameStatusName(m.status),
                       m.detail);
  }
  return fmt::format(
      "Measurement(valid, width_px={:.4f} ± {:.4f}, angle_deg={:.3f}, tip_px=({:.2f}, {:.2f}), "
      "polarity={}, calipers={}/{})",
      m.width_px, m.width_sigma_px, m.angle_deg, m.tip_x_px, m.tip_y_px,
      vision::PolarityName(m.polarity), m.calipers_used, m.calipers_total);
}

}  // namespace

std::string ReprOf(const py::handle& obj, const char* type_name,
                   std::initializer_list<const char*> fields) {
  std::string out = std::string(type_name) + "(";
  bool first = true;
  for (const char* f : fields) {
    out += fmt::format("{}{}={}", first ? "" : ", ", f, std::string(py::repr(obj.attr(f))));
    first = false;
  }
  return out + ")";
}

void BindMeasure(py::module_& m) {
  // The reason column of the per-frame table: the same names (valid is the empty cell).
  py::enum_<FrameStatus> status(m, "FrameStatus",
                                "Why a frame gives no width; `valid` when it does. The names are "
                                "those of the per-frame table's reason column.");
  for (int i = 0; i < vision::kFrameStatusCount; ++i) {
    const auto s = static_cast<FrameStatus>(i);
    status.value(s == FrameStatus::kValid ? "valid" : vision::FrameStatusName(s), s);
  }
  m.attr("Reason") = status;

  py::enum_<vision::LumaRange>(m, "LumaRange", "Where a frame's black and white lie.")
      .value("full", vision::LumaRange::kFull, "0 and full scale: images, full-range video")
      .value("limited", vision::LumaRange::kLimited,
             "16 and 235 of 255: most video luma (as the decoder says)");
  py::enum_<vision::Polarity>(m, "Polarity", "Which way the strand differs from the background.")
      .value("auto", vision::Polarity::kAuto, "measurement option only: decide from the frame")
      .value("bright", vision::Polarity::kBrightOnDark, "a lit strand on a dark background")
      .value("dark", vision::Polarity::kDarkOnBright, "a silhouette on a backlight")
      .value("mixed", vision::Polarity::kMixed,
             "measured only: brighter than the background on one side, darker on the other");
  py::enum_<vision::MeasureTarget>(m, "Target", "What is measured.")
      .value("strand", vision::MeasureTarget::kStrand,
             "a strand below a nozzle tip: the band starts below the tip")
      .value("filament", vision::MeasureTarget::kFilament,
             "a filament, pin or needle with no tip: the band runs along the straight stretch");

  py::class_<StrandMeasureOptions>(
      m, "MeasureOptions",
      "How the strand is found and measured in one frame (vision::StrandMeasureOptions). Lengths "
      "in px of the frame. Construct with keywords: MeasureOptions(band_start_px=20, "
      "polarity=Polarity.dark). The defaults are the command line's at 3 µm/px.")
      .def(py::init([](const py::kwargs& kw) { return FromKwargs<StrandMeasureOptions>(kw); }))
      .def_property(
          "roi", [](const StrandMeasureOptions& o) { return RoiOf(o.roi); },
          [](StrandMeasureOptions& o, const py::object& v) { o.roi = RoiFrom(v); },
          "Region searched, (x, y, width, height) in px; None: the whole frame.")
      .def_readwrite("polarity", &StrandMeasureOptions::polarity,
                     "Polarity.auto, .bright (lit strand) or .dark (silhouette).")
      .def_readwrite("target", &StrandMeasureOptions::target, "Target.strand or .filament.")
      .def_readwrite("band_start_px", &StrandMeasureOptions::band_start_px,
                     "Band start below the nozzle tip, px (50 µm at 3 µm/px).")
      .def_readwrite("band_height_px", &StrandMeasureOptions::band_height_px,
                     "Band height along the strand, px (150 µm at 3 µm/px).")
      .def_readwrite("caliper_spacing_px", &StrandMeasureOptions::caliper_spacing_px,
                     "Thickness of one caliper along the axis, px.")
      .def_readwrite("min_contrast_fraction", &StrandMeasureOptions::min_contrast_fraction,
                     "Edge step below this fraction of full scale: low_contrast.")
      .def_readwrite("max_blur_px", &StrandMeasureOptions::max_blur_px,
                     "Fitted PSF σ above this: out_of_focus, px.")
      .def_readwrite("max_tilt_deg", &StrandMeasureOptions::max_tilt_deg,
                     "Axes leaning more than this from vertical are not strands, degrees.")
      .def_readwrite("min_length_px", &StrandMeasureOptions::min_length_px,
                     "Shortest straight stretch of both edges that counts as a strand, px.")
      .def_readwrite("shading", &StrandMeasureOptions::shading,
                     "Fit a lit cylinder's shading beside each edge when the calipers show it.")
      .def_readwrite("min_caliper_fraction", &StrandMeasureOptions::min_caliper_fraction,
                     "Fewer consistent calipers than this fraction: occluded.")
      .def_readwrite("max_saturated_fraction", &StrandMeasureOptions::max_saturated_fraction,
                     "More clipped pixels at the edges than this fraction: saturated.")
      .def_readwrite("luma_range", &StrandMeasureOptions::luma_range,
                     "LumaRange of the frames (a video frame's: Frame.luma_range): where clipped "
                     "white and black are looked for.")
      .def_readwrite("max_sigma_px", &StrandMeasureOptions::max_sigma_px,
                     "A width whose σ is above max(max_sigma_px, max_sigma_fraction·width) is "
                     "imprecise, px.")
      .def_readwrite("max_sigma_fraction", &StrandMeasureOptions::max_sigma_fraction,
                     "See max_sigma_px (a fraction of the width).")
      .def("validate", &ValidateOptions,
           "Raises ValueError with the reason (the message measure_frame would give) when the "
           "options cannot be used.")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "MeasureOptions",
                      {"roi", "polarity", "target", "band_start_px", "band_height_px",
                       "caliper_spacing_px", "min_contrast_fraction", "max_blur_px", "max_tilt_deg",
                       "min_length_px", "shading", "min_caliper_fraction", "max_saturated_fraction",
                       "luma_range", "max_sigma_px", "max_sigma_fraction"});
      });

  py::class_<vision::Caliper>(m, "Caliper", "One caliper across the band: its edges and width, px.")
      .def_readonly("s_px", &vision::Caliper::s_px, "Slab centre below the tip, px.")
      .def_readonly("left_u_px", &vision::Caliper::left_u_px, "Fitted left edge across the axis.")
      .def_readonly("right_u_px", &vision::Caliper::right_u_px,
                    "Fitted right edge across the axis.")
      .def_readonly("width_px", &vision::Caliper::width_px, "Width corrected for the tilt.")
      .def_readonly("width_sigma_px", &vision::Caliper::width_sigma_px, "Its standard error.")
      .def_readonly("fitted", &vision::Caliper::fitted, "Both edges fitted.")
      .def_readonly("inlier", &vision::Caliper::inlier, "Used in the frame's width.")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "Caliper", {"s_px", "width_px", "width_sigma_px", "inlier"});
      });

  py::class_<StrandMeasurement>(
      m, "Measurement",
      "One frame's result (vision::StrandMeasurement): the width in px with its standard error, "
      "or a status saying why there is none. Geometry in full-frame px.")
      .def_readonly("status", &StrandMeasurement::status,
                    "FrameStatus.valid, or why the frame gives no width.")
      .def_property_readonly(
          "reason", [](const StrandMeasurement& s) { return vision::FrameStatusName(s.status); },
          "The status as the table's reason column writes it ('' when valid).")
      .def_readonly("detail", &StrandMeasurement::detail, "Human-readable reason when not valid.")
      .def_property_readonly("valid", &StrandMeasurement::valid, "True when there is a width.")
      .def_readonly("width_px", &StrandMeasurement::width_px, "Strand width, px.")
      .def_readonly("width_sigma_px", &StrandMeasurement::width_sigma_px,
                    "Standard error of width_px: the calipers' spread and the model's doubt.")
      .def_readonly("model_sigma_px", &StrandMeasurement::model_sigma_px,
                    "The part of width_sigma_px other frames of the scene do not average out: "
                    "an edge model chosen on weak evidence, and the codec.")
      .def_readonly("codec_sigma_px", &StrandMeasurement::codec_sigma_px,
                    "The codec's part: how far a second pass through the video's x264 moved "
                    "the width (0 for other sources).")
      .def_property_readonly(
          "sigma_parts",
          [](const StrandMeasurement& s) {
            std::vector<std::pair<std::string, double>> parts;
            for (const vision::DoubtPart& p : vision::DoubtParts(s))
              parts.emplace_back(p.what, p.sigma_px);
            return parts;
          },
          "width_sigma_px in its parts, largest first: (what, σ px) pairs.")
      .def_readonly("angle_deg", &StrandMeasurement::angle_deg,
                    "Strand axis from image vertical, + leaning to +x going down.")
      .def_readonly("contrast", &StrandMeasurement::contrast,
                    "Median edge step, grey levels of the frame's bit depth.")
      .def_readonly("blur_px", &StrandMeasurement::blur_px, "Median PSF σ, px.")
      .def_readonly("tip_x_px", &StrandMeasurement::tip_x_px,
                    "Nozzle tip on the axis (strand) or top of the stretch (filament), x px.")
      .def_readonly("tip_y_px", &StrandMeasurement::tip_y_px, "The same, y px.")
      .def_readonly("polarity", &StrandMeasurement::polarity, "The polarity measured.")
      .def_readonly("calipers_used", &StrandMeasurement::calipers_used,
                    "Calipers whose widths make the frame's width.")
      .def_readonly("calipers_total", &StrandMeasurement::calipers_total,
                    "Calipers placed across the band.")
      .def_readonly("has_geometry", &StrandMeasurement::has_geometry,
                    "The axis, band and edge lines below are set.")
      .def_readonly("shading_left", &StrandMeasurement::shading_left,
                    "The left edge was fitted with the shading model.")
      .def_readonly("shading_right", &StrandMeasurement::shading_right,
                    "The right edge was fitted with the shading model.")
      .def_readonly("axis_dx", &StrandMeasurement::axis_dx, "Axis direction down the strand, x.")
      .def_readonly("axis_dy", &StrandMeasurement::axis_dy, "Axis direction down the strand, y.")
      .def_readonly("band_start_px", &StrandMeasurement::band_start_px,
                    "Along the axis from the tip.")
      .def_readonly("band_end_px", &StrandMeasurement::band_end_px,
                    "Band end along the axis from the tip, px.")
      .def_readonly("left_u0_px", &StrandMeasurement::left_u0_px,
                    "Left edge line u = left_u0_px + edge_slope·s across the axis.")
      .def_readonly("right_u0_px", &StrandMeasurement::right_u0_px,
                    "Right edge line u = right_u0_px + edge_slope·s across the axis.")
      .def_readonly("edge_slope", &StrandMeasurement::edge_slope,
                    "Both edge lines' slope across the axis per px along it.")
      .def_readonly("straight_start_px", &StrandMeasurement::straight_start_px,
                    "Where along the band the width comes from (a rough filament: its straight "
                    "part), px.")
      .def_readonly("straight_end_px", &StrandMeasurement::straight_end_px)
      .def_readonly("rough_calipers", &StrandMeasurement::rough_calipers,
                    "Filament: calipers whose edges are not straight (knurl marks).")
      .def_readonly("tip_sigma_px", &StrandMeasurement::tip_sigma_px,
                    "Strand: the tip's doubt along the axis where the nozzle's face or the "
                    "object's own end fixed it; -1 where only the followed edges did.")
      .def_readonly("swell_ratio", &StrandMeasurement::swell_ratio,
                    "Widest width between the tip and the band over width_px (die swell).")
      .def_readonly("calipers", &StrandMeasurement::calipers, "The Caliper list across the band.")
      .def("__repr__", &MeasurementRepr)
      .def("__bool__", &StrandMeasurement::valid);

  m.def(
      "measure_frame",
      [](const py::array& frame, std::optional<StrandMeasureOptions> options) {
        return MeasureArray(frame, options ? *options : StrandMeasureOptions{});
      },
      py::arg("frame"), py::arg("options") = py::none(),
      R"(Measures the strand width in one frame (vision::MeasureStrand).

frame: a NumPy array, uint8 or uint16, H×W grey or H×W×3 BGR (H×W×4 BGRA); read in place, no
    copy: C-contiguous or a crop of a larger array (rows at any stride, a row's pixels packed).
    16-bit frames holding 10- or 12-bit data are judged against their data range.
options: MeasureOptions (default: the command line's defaults, a band 50-200 µm below the tip
    at 3 µm/px).

Returns a Measurement: width_px and width_sigma_px when m.valid, else m.status (a FrameStatus:
no_strand, no_tip, occluded, imprecise, ...) and m.detail. The GIL is released while measuring:
several threads may measure at once. Each call searches the frame afresh; for video use Tracker.

Raises ValueError for an array of another type or layout, or options that do not validate
(the message names the problem).)");

  m.def(
      "_peak_concurrent_measurements",
      [](bool reset) { return reset ? g_peak.exchange(0) : g_peak.load(); },
      py::arg("reset") = true,
      "The most measurements seen inside the library at once (GIL released) since the last "
      "reset: evidence for tests that threads measure concurrently.");

  m.def(
      "_time_measure_strand",
      [](const py::array& frame, std::optional<StrandMeasureOptions> options, int repeats) {
        const cv::Mat view = MatView(frame);
        const StrandMeasureOptions o = options ? *options : StrandMeasureOptions{};
        py::gil_scoped_release release;
        const auto t0 = std::chrono::steady_clock::now();
        for (int i = 0; i < repeats; ++i) vision::MeasureStrand(view, o);
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      },
      py::arg("frame"), py::arg("options") = py::none(), py::arg("repeats") = 1,
      "Seconds for `repeats` calls of vision::MeasureStrand on the frame, timed in C++: the "
      "benchmark's reference for measure_frame's overhead (bench/python_overhead.py).");

  py::class_<Tracker>(m, "Tracker",
                      R"(Measures a strand frame after frame (vision::StrandTracker): after the
first frame it looks where the strand was (its edges, tip and band) and searches afresh only
when that fails, so a steady video costs the caliper fits alone and the band does not wander.

    tracker = clogscope.Tracker(options)
    for frame in frames:
        m = tracker.measure(frame)  # a video's Frame f: tracker.measure(f.image, f.luma_range)

encoder: a video's x264 settings (FrameReader.encoder): every width then carries the codec's
doubt, as measure gives it (vision/scene/codec_doubt.h).
)")
      .def(py::init([](std::optional<StrandMeasureOptions> options,
                       std::optional<vision::X264Settings> encoder) {
             const StrandMeasureOptions o = options ? *options : StrandMeasureOptions{};
             ValidateOptions(o);
             return std::make_unique<Tracker>(o, encoder ? *encoder : vision::X264Settings{});
           }),
           py::arg("options") = py::none(), py::arg("encoder") = py::none(),
           "Raises ValueError when the options do not validate.")
      .def("measure", &Tracker::Measure, py::arg("frame"), py::arg("luma_range") = py::none(),
           "Measures the next frame (arrays as measure_frame takes them; GIL released), whose "
           "black and white lie as luma_range says (a video frame's: Frame.luma_range; None: "
           "as the options' luma_range, or the last range given). Returns a Measurement.")
      .def("reset", &Tracker::Reset, "Forgets the strand: the next frame is searched afresh.")
      .def_property_readonly("options", &Tracker::options)
      .def_property_readonly("full_detections", &Tracker::full_detections,
                             "Frames searched afresh so far.")
      .def_property_readonly("tracked_frames", &Tracker::tracked_frames,
                             "Frames measured where the strand was.");
}

}  // namespace clogscope::python
