// clogscope.render and the synthetic scenes: frames with exact ground truth, as NumPy arrays
// (synthetic/: RenderFrame, the function `clogscope render` writes its frames with), or written to
// files by the command's own apps::RenderToFiles.
//
#include <fmt/format.h>
#include <pybind11/stl.h>

#include <cstring>

#include "apps/render_command.h"
#include "arrays.h"
#include "bindings.h"
#include "synthetic/synthetic.h"

namespace clogscope::python {
namespace {

using Scene = synthetic::SceneParams;
using Truth = synthetic::FrameTruth;

void ValidateScene(const Scene& s) {
  std::string why;
  if (!s.Validate(&why)) throw py::value_error(why);
}

py::tuple Tint(const double* t) { return py::make_tuple(t[0], t[1], t[2]); }
void SetTint(double* t, const std::vector<double>& v) {
  if (v.size() != 3) throw py::value_error("tint: expected (B, G, R) gains");
  std::copy(v.begin(), v.end(), t);
}

// Frames first..first+count−1 into one N×H×W[×C] array, and their truth; the GIL released while
// rendering.
py::tuple Render(const Scene& scene, int count, int first) {
  ValidateScene(scene);
  if (count < 1) throw py::value_error("frames: must be at least 1");
  if (first < 0) throw py::value_error("first: must not be negative");
  const int channels = scene.colour ? 3 : 1;
  const bool wide = scene.bit_depth == 16;
  std::vector<py::ssize_t> shape = {count, scene.height_px, scene.width_px};
  if (channels > 1) shape.push_back(channels);
  py::array out = wide ? py::array(py::dtype::of<uint16_t>(), shape)
                       : py::array(py::dtype::of<uint8_t>(), shape);
  auto* data = static_cast<unsigned char*>(out.mutable_data());
  const size_t frame_bytes = static_cast<size_t>(out.strides(0));
  std::vector<Truth> truth(count);
  {
    py::gil_scoped_release release;
    for (int i = 0; i < count; ++i) {
      const cv::Mat f = synthetic::RenderFrame(scene, first + i, &truth[i]);
      cv::Mat dst(f.rows, f.cols, f.type(), data + i * frame_bytes);
      f.copyTo(dst);
    }
  }
  return py::make_tuple(out, truth);
}

}  // namespace

void BindRender(py::module_& m) {
  py::enum_<synthetic::RenderTarget>(m, "RenderTarget", "What a rendered scene shows.")
      .value("strand", synthetic::RenderTarget::kStrand, "a strand below a nozzle")
      .value("pin", synthetic::RenderTarget::kPin, "a pin gauge across the frame")
      .value("micrometer", synthetic::RenderTarget::kMicrometer, "a stage micrometer's lines");

  py::class_<Scene>(
      m, "SceneParams",
      "A rendered side view of a nozzle tip and strand with exactly known geometry (the "
      "parameters of `clogscope render`; synthetic/synthetic.h says what each does). Construct "
      "with keywords: SceneParams(strand_width_um=390.1, tilt_deg=4, colour=True).")
      .def(py::init([](const py::kwargs& kw) { return FromKwargs<Scene>(kw); }))
      .def_readwrite("target", &Scene::target)
      .def_readwrite("width_px", &Scene::width_px, "Frame width, px.")
      .def_readwrite("height_px", &Scene::height_px, "Frame height, px.")
      .def_readwrite("scale_um_per_px", &Scene::scale_um_per_px,
                     "Pixel scale of the rendered optics.")
      .def_readwrite("strand_width_um", &Scene::strand_width_um, "Strand (or pin) width, µm.")
      .def_readwrite("tip_x_px", &Scene::tip_x_px)
      .def_readwrite("tip_y_px", &Scene::tip_y_px)
      .def_readwrite("tilt_deg", &Scene::tilt_deg,
                     "Scene and strand tilt (+: leaning to +x going down).")
      .def_readwrite("blur_sigma_px", &Scene::blur_sigma_px, "Gaussian PSF σ, px.")
      .def_readwrite("noise_sigma", &Scene::noise_sigma,
                     "Sensor noise σ, grey levels (8-bit scale).")
      .def_readwrite("background_level", &Scene::background_level)
      .def_readwrite("strand_level", &Scene::strand_level)
      .def_readwrite("nozzle_level", &Scene::nozzle_level)
      .def_readwrite("bed_level", &Scene::bed_level)
      .def_readwrite("gradient_fraction", &Scene::gradient_fraction,
                     "Illumination change across the frame diagonal (0.3 = 30 %).")
      .def_readwrite("gradient_angle_deg", &Scene::gradient_angle_deg)
      .def_readwrite("highlight", &Scene::highlight, "A specular stripe inside the strand.")
      .def_readwrite("highlight_offset_fraction", &Scene::highlight_offset_fraction)
      .def_readwrite("highlight_width_fraction", &Scene::highlight_width_fraction)
      .def_readwrite("highlight_gain", &Scene::highlight_gain)
      .def_readwrite("bed", &Scene::bed, "A print bed bed_gap_um below the tip.")
      .def_readwrite("bed_gap_um", &Scene::bed_gap_um)
      .def_readwrite("nozzle_tip_width_um", &Scene::nozzle_tip_width_um)
      .def_readwrite("nozzle_cone_half_angle_deg", &Scene::nozzle_cone_half_angle_deg)
      .def_readwrite("sway_deg", &Scene::sway_deg, "Per-frame σ of the axis angle, degrees.")
      .def_readwrite("width_jitter_um", &Scene::width_jitter_um,
                     "Per-frame σ of the strand width, µm.")
      .def_readwrite("frame_width_um", &Scene::frame_width_um,
                     "Width schedule: frame i's width in µm (the last entry for later frames); "
                     "empty: strand_width_um.")
      .def_readwrite("surface_texture_amplitude", &Scene::surface_texture_amplitude,
                     "± grey levels of the moving surface texture.")
      .def_readwrite("feed_speed_mm_s", &Scene::feed_speed_mm_s,
                     "Surface texture travelling down the axis (a moving filament), mm/s.")
      .def_readwrite("frame_rate_hz", &Scene::frame_rate_hz,
                     "Frame i is at time i / frame_rate_hz.")
      .def_readwrite("drive_gear", &Scene::drive_gear)
      .def_readwrite("gear_centre_x_px", &Scene::gear_centre_x_px)
      .def_readwrite("gear_centre_y_px", &Scene::gear_centre_y_px)
      .def_readwrite("gear_radius_px", &Scene::gear_radius_px)
      .def_readwrite("gear_teeth", &Scene::gear_teeth)
      .def_readwrite("gear_tooth_depth_px", &Scene::gear_tooth_depth_px)
      .def_readwrite("gear_level", &Scene::gear_level)
      .def_readwrite("gear_surface_speed_mm_s", &Scene::gear_surface_speed_mm_s)
      .def_readwrite("knurl_depth_px", &Scene::knurl_depth_px)
      .def_readwrite("knurl_pitch_px", &Scene::knurl_pitch_px)
      .def_readwrite("knurl_start_px", &Scene::knurl_start_px)
      .def_readwrite("edge_bias_px", &Scene::edge_bias_px,
                     "Objects appear this many px wider than width/scale (the optics' edge bias).")
      .def_readwrite("pitch_um", &Scene::pitch_um, "Micrometer line pitch, µm.")
      .def_readwrite("line_width_um", &Scene::line_width_um)
      .def_readwrite("tick_length_um", &Scene::tick_length_um)
      .def_readwrite("numerals", &Scene::numerals)
      .def_readwrite("dust_specks", &Scene::dust_specks)
      .def_readwrite("dust_fibres", &Scene::dust_fibres)
      .def_readwrite("nozzle", &Scene::nozzle, "False: no nozzle in view (a filament, a needle).")
      .def_readwrite("strand", &Scene::strand, "False: nothing below the nozzle.")
      .def_readwrite("texture_amplitude", &Scene::texture_amplitude)
      .def_readwrite("texture_wavelength_px", &Scene::texture_wavelength_px)
      .def_readwrite("clutter_discs", &Scene::clutter_discs)
      .def_readwrite("clutter_gears", &Scene::clutter_gears)
      .def_readwrite("shading_ambient", &Scene::shading_ambient)
      .def_readwrite("clear_strand", &Scene::clear_strand)
      .def_readwrite("clear_line_gain", &Scene::clear_line_gain)
      .def_readwrite("vignetting", &Scene::vignetting)
      .def_readwrite("colour", &Scene::colour, "BGR frames (an orange strand).")
      .def_readwrite("bit_depth", &Scene::bit_depth, "8 or 16.")
      .def_readwrite("data_bits", &Scene::data_bits,
                     "16 bit only: significant bits (12: values 0..4095; 0: all 16).")
      .def_readwrite("seed", &Scene::seed, "Random seed: same seed and index, same image.")
      .def_readwrite("purge_start_s", &Scene::purge_start_s)
      .def_readwrite("purge_duration_s", &Scene::purge_duration_s)
      .def_readwrite("purge_radius_px", &Scene::purge_radius_px)
      .def_readwrite("occlusion_start_s", &Scene::occlusion_start_s)
      .def_readwrite("occlusion_duration_s", &Scene::occlusion_duration_s)
      .def_property(
          "strand_tint", [](const Scene& s) { return Tint(s.strand_tint); },
          [](Scene& s, const std::vector<double>& v) { SetTint(s.strand_tint, v); },
          "(B, G, R) gains of the strand (colour only).")
      .def_property(
          "background_tint", [](const Scene& s) { return Tint(s.background_tint); },
          [](Scene& s, const std::vector<double>& v) { SetTint(s.background_tint, v); })
      .def_property(
          "nozzle_tint", [](const Scene& s) { return Tint(s.nozzle_tint); },
          [](Scene& s, const std::vector<double>& v) { SetTint(s.nozzle_tint, v); })
      .def("validate", &ValidateScene, "Raises ValueError saying why the scene cannot be rendered.")
      .def("set_silhouette", &Scene::SetSilhouette,
           "Makes this a silhouette on a backlight (dark strand, nozzle and bed on bright).")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(
            self, "SceneParams",
            {"target", "width_px", "height_px", "scale_um_per_px", "strand_width_um", "tilt_deg",
             "blur_sigma_px", "noise_sigma", "edge_bias_px", "colour", "bit_depth", "seed"});
      });

  m.def("random_realistic_scene", &synthetic::RandomRealisticScene, py::arg("seed"),
        "A randomised scene far from the defaults (tilt, blur, clutter, shading, colour, ...): "
        "the robustness tests' scenes. `seed` picks everything.");
  m.def("feedstock_scene", &synthetic::FeedstockScene, py::arg("feed_speed_mm_s"),
        py::arg("gear_surface_speed_mm_s") = py::none(),
        "A 1.75 mm filament at 20 µm/px running down a 640×480 frame with a moving surface "
        "texture (feed_speed_mm_s), optionally a drive gear beside it.");

  py::class_<Truth>(m, "FrameTruth", "The exact geometry of one rendered frame.")
      .def_readonly("frame", &Truth::frame)
      .def_readonly("width_um", &Truth::width_um, "Physical width, µm.")
      .def_readonly("width_px", &Truth::width_px,
                    "Apparent width in the image: width_um / scale + edge bias, px.")
      .def_readonly("angle_deg", &Truth::angle_deg)
      .def_readonly("tip_x_px", &Truth::tip_x_px)
      .def_readonly("tip_y_px", &Truth::tip_y_px)
      .def_readonly("time_s", &Truth::time_s)
      .def_readonly("feed_offset_px", &Truth::feed_offset_px,
                    "How far the surface has moved down the axis since frame 0, px.")
      .def_readonly("gear_angle_rad", &Truth::gear_angle_rad)
      .def("__repr__", [](const py::object& self) {
        return ReprOf(
            self, "FrameTruth",
            {"frame", "width_um", "width_px", "angle_deg", "tip_x_px", "tip_y_px", "time_s"});
      });

  m.def("_render", &Render, py::arg("scene"), py::arg("frames"), py::arg("first"),
        "(frames N×H×W[×3] array, [FrameTruth]); use clogscope.render.");
  m.def(
      "render_frame",
      [](const Scene& scene, int index) {
        ValidateScene(scene);
        Truth t;
        cv::Mat f;
        {
          py::gil_scoped_release release;
          f = synthetic::RenderFrame(scene, index, &t);
        }
        return py::make_tuple(ArrayFromMat(std::move(f)), t);
      },
      py::arg("scene"), py::arg("index") = 0,
      "Renders frame `index` of the scene: (array H×W or H×W×3, uint8 or uint16; FrameTruth). "
      "The same scene, seed and index give the same image.");

  m.def(
      "render_to_files",
      [](const Path& out, const Scene& scene, int frames, double fps, const Path& truth_path,
         double drop_pct, double drop_at_s, const Path& lag_commanded, double lag_k_s,
         double lag_um_per_mm3_s) {
        apps::RenderCommandOptions o;
        o.out = out.string();
        o.scene = scene;
        o.frames = frames;
        o.fps = fps;
        o.truth_path = truth_path.string();
        o.drop_pct = drop_pct;
        o.drop_at_s = drop_at_s;
        o.lag_commanded = lag_commanded.string();
        o.lag_k_s = lag_k_s;
        o.lag_um_per_mm3_s = lag_um_per_mm3_s;
        py::gil_scoped_release release;
        return apps::RenderToFiles(o);
      },
      py::arg("out"), py::arg("scene"), py::kw_only(), py::arg("frames") = 1, py::arg("fps") = 25.0,
      py::arg("truth_path") = "", py::arg("drop_pct") = 0.0, py::arg("drop_at_s") = 0.0,
      py::arg("lag_commanded") = "", py::arg("lag_k_s") = 0.1, py::arg("lag_um_per_mm3_s") = 40.0,
      R"(Writes frames as `clogscope render` does (apps::RenderToFiles): a folder of PNGs
(frame_000000.png ...) or a .avi (MJPEG) / .mp4 (H.264) video at `out`, and the truth JSON
(default DIR/truth.json or NAME.truth.json). drop_pct / drop_at_s: the strand narrows by drop_pct %
at drop_at_s (a clog for watch). lag_commanded: a flow profile CSV the width follows with lag
lag_k_s. Returns the truth file's path. Raises ValueError with the command's message.)");
}

}  // namespace clogscope::python
