// clogscope.open_frames and read_image: the frames of an image, a folder of images or a video as
// NumPy arrays, read by the command line's own frame source (vision::FrameSource: video frames
// decoded straight to their luma plane), for Tracker and measure_frame.
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "vision/io/frame_source.h"

namespace clogscope::python {
namespace {

struct Frame {
  py::array image;  // empty (0×0) when the frame could not be decoded
  std::string source;
  int64_t index = 0;
  double time_s = -1;
  std::string error;
  vision::LumaRange luma_range = vision::LumaRange::kFull;
};

class FrameReader {
 public:
  explicit FrameReader(const Path& path)
      : source_(vision::FrameSource::Open(path.string())), encoder_(source_->encoder()) {}
  Frame Next() {
    vision::InputFrame f;
    bool got = false;
    {
      py::gil_scoped_release release;
      got = source_ && source_->Next(&f);
    }
    if (!got) {
      source_.reset();
      throw py::stop_iteration();
    }
    return {ArrayFromMat(std::move(f.image)), f.source, f.index, f.time_s, f.error, f.luma_range};
  }
  int expected_frames() const { return source_ ? source_->expected_frames() : 0; }
  double fps() const { return source_ ? source_->fps() : 0; }
  const vision::X264Settings& encoder() const { return encoder_; }

 private:
  std::unique_ptr<vision::FrameSource> source_;
  vision::X264Settings encoder_;  // kept when the source goes at the end
};

}  // namespace

void BindFrames(py::module_& m) {
  py::class_<Frame>(m, "Frame", "One frame read from a file, folder or video.")
      .def_readonly("image", &Frame::image,
                    "H×W (video frames: their luma) or H×W×3 BGR, uint8 or uint16; 0×0 when the "
                    "frame could not be decoded (see error).")
      .def_readonly("source", &Frame::source, "The file it came from.")
      .def_readonly("index", &Frame::index, "Frame number within the input, from 0.")
      .def_readonly("time_s", &Frame::time_s, "Position in a video, s; -1 for still images.")
      .def_readonly("error", &Frame::error, "Why image is empty, or a warning.")
      .def_readonly("luma_range", &Frame::luma_range,
                    "Where the image's black and white lie (LumaRange.limited for most video "
                    "luma): give it to Tracker.measure.")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "Frame", {"source", "index", "time_s", "error", "luma_range"});
      });
  py::class_<vision::X264Settings>(m, "X264Settings",
                                   "The settings x264 wrote into a video it encoded "
                                   "(vision/io/encoder_note.h).")
      .def_readonly("found", &vision::X264Settings::found, "The video holds x264's note.")
      .def_readonly("aq_mode", &vision::X264Settings::aq_mode,
                    "Adaptive quantisation mode (-1: not told).")
      .def_readonly("aq_strength", &vision::X264Settings::aq_strength, "(-1: not told)")
      .def_readonly("crf", &vision::X264Settings::crf, "Constant rate factor (-1: not told).")
      .def("__repr__", [](const py::object& self) {
        return ReprOf(self, "X264Settings", {"found", "aq_mode", "aq_strength", "crf"});
      });
  py::class_<FrameReader>(m, "FrameReader",
                          "Iterates over the frames of an image, a folder of images (in name "
                          "order) or a video, as `clogscope measure` reads them.")
      .def("__iter__", [](FrameReader& r) -> FrameReader& { return r; })
      .def("__next__", &FrameReader::Next)
      .def_property_readonly("expected_frames", &FrameReader::expected_frames,
                             "Frames expected (-1: unknown).")
      .def_property_readonly("fps", &FrameReader::fps, "Video frame rate (0: unknown).")
      .def_property_readonly("encoder", &FrameReader::encoder,
                             "x264's settings for a video it encoded (found false otherwise): "
                             "give them to Tracker for the codec's doubt.");
  m.def(
      "open_frames", [](const Path& path) { return std::make_unique<FrameReader>(path); },
      py::arg("path"),
      R"(The frames of an image, a folder of images or a video (vision::FrameSource, as measure
reads them): iterate for Frame objects (image, index, time_s, source).

    frames = clogscope.open_frames("step1.mp4")
    tracker = clogscope.Tracker(encoder=frames.encoder)
    for f in frames:
        m = tracker.measure(f.image, luma_range=f.luma_range)

Raises ValueError naming the path when it cannot be opened.)");
  m.def(
      "read_image",
      [](const Path& path) {
        vision::InputFrame f;
        {
          py::gil_scoped_release release;
          auto source = vision::FrameSource::Open(path.string());
          if (!source->Next(&f)) throw std::invalid_argument(path.string() + ": no frame");
        }
        if (f.image.empty()) throw std::invalid_argument(path.string() + ": " + f.error);
        return ArrayFromMat(std::move(f.image));
      },
      py::arg("path"),
      "The first frame of an image file (or video) as an array, as measure reads it: 8- or "
      "16-bit, grey or BGR. Raises ValueError naming the file when it cannot be read.");
}

}  // namespace clogscope::python
