#include "arrays.h"

#include <fmt/format.h>

#include <string>

namespace clogscope::python {

cv::Mat MatView(const py::array& a, const char* what) {
  const py::dtype dt = a.dtype();
  const py::ssize_t item = dt.itemsize();
  if (dt.kind() != 'u' || (item != 1 && item != 2)) {
    throw py::value_error(fmt::format(
        "{}: dtype {} is not supported: need uint8 or uint16 (e.g. array.astype(numpy.uint16))",
        what, std::string(py::str(static_cast<const py::handle&>(dt)))));
  }
  if (item == 2 && dt.byteorder() == '>') {
    throw py::value_error(fmt::format(
        "{}: big-endian uint16 is not supported: convert with array.astype('=u2')", what));
  }
  if (a.ndim() != 2 && a.ndim() != 3) {
    throw py::value_error(fmt::format(
        "{}: {} dimensions: need H×W (grey) or H×W×C (C = 3 BGR or 4 BGRA)", what, a.ndim()));
  }
  const py::ssize_t rows = a.shape(0), cols = a.shape(1);
  const py::ssize_t channels = a.ndim() == 3 ? a.shape(2) : 1;
  if (channels != 1 && channels != 3 && channels != 4) {
    throw py::value_error(
        fmt::format("{}: {} channels: need 1 (grey), 3 (BGR) or 4 (BGRA) in the last dimension",
                    what, channels));
  }
  if (rows == 0 || cols == 0) throw py::value_error(fmt::format("{}: empty array", what));
  // Pixels of a row packed (channels, then columns); rows at any positive stride.
  if (channels > 1 && a.strides(2) != item) {
    throw py::value_error(fmt::format(
        "{}: the channels of a pixel are not adjacent in memory (stride {} bytes): pass "
        "numpy.ascontiguousarray(frame)",
        what, a.strides(2)));
  }
  if (cols > 1 && a.strides(1) != channels * item) {
    throw py::value_error(fmt::format(
        "{}: the pixels of a row are not adjacent in memory (column stride {} bytes, need {}): "
        "pass numpy.ascontiguousarray(frame)",
        what, a.strides(1), channels * item));
  }
  const py::ssize_t row_bytes = cols * channels * item;
  py::ssize_t step = a.strides(0);
  if (rows == 1) step = row_bytes;
  if (step < row_bytes || step % item != 0) {
    throw py::value_error(
        fmt::format("{}: row stride {} bytes (rows reversed or overlapping): pass "
                    "numpy.ascontiguousarray(frame)",
                    what, a.strides(0)));
  }
  const int type = CV_MAKETYPE(item == 1 ? CV_8U : CV_16U, static_cast<int>(channels));
  // The library only reads frames: the const is dropped for cv::Mat's constructor alone.
  return cv::Mat(static_cast<int>(rows), static_cast<int>(cols), type, const_cast<void*>(a.data()),
                 static_cast<size_t>(step));
}

py::array ArrayFromMat(cv::Mat mat) {
  if (mat.empty()) return py::array_t<uint8_t>(std::vector<py::ssize_t>{0, 0});
  py::dtype dt;
  switch (mat.depth()) {
    case CV_8U:
      dt = py::dtype::of<uint8_t>();
      break;
    case CV_16U:
      dt = py::dtype::of<uint16_t>();
      break;
    case CV_64F:
      dt = py::dtype::of<double>();
      break;
    default:
      mat.convertTo(mat, CV_64F);
      dt = py::dtype::of<double>();
  }
  auto* held = new cv::Mat(std::move(mat));
  py::capsule owner(held, [](void* p) { delete static_cast<cv::Mat*>(p); });
  const py::ssize_t item = static_cast<py::ssize_t>(held->elemSize1());
  const py::ssize_t ch = held->channels();
  std::vector<py::ssize_t> shape = {held->rows, held->cols};
  std::vector<py::ssize_t> strides = {static_cast<py::ssize_t>(held->step[0]), ch * item};
  if (ch > 1) {
    shape.push_back(ch);
    strides.push_back(item);
  }
  return py::array(dt, shape, strides, held->data, owner);
}

}  // namespace clogscope::python
