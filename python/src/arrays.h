#pragma once

// NumPy arrays in and out of the library's cv::Mat, without copying pixels.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>

namespace clogscope::python {

namespace py = pybind11;

// A cv::Mat over the array's own memory (no copy): 2-D (grey) or H×W×C with C = 1, 3 (BGR) or 4
// (BGRA), uint8 or uint16 in native byte order; rows at any positive stride (a crop of a larger
// array), the pixels of a row packed. Anything else raises ValueError naming `what` and the
// problem. The array must outlive the Mat (the caller holds it).
cv::Mat MatView(const py::array& array, const char* what = "frame");

// A NumPy array owning `mat`'s pixels (no copy: the Mat's buffer is kept alive by the array):
// H×W for one channel, H×W×C otherwise; uint8, uint16 or float64.
py::array ArrayFromMat(cv::Mat mat);

}  // namespace clogscope::python
