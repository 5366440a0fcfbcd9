// NumPy arrays in and out of the module: inputs checked once (dtype, shape) with errors that name the argument,
// outputs allocated by NumPy and filled without the GIL.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace hovs::python {

namespace py = pybind11;

// An input of N rows of k numbers: an (N, k) array or one k-vector (then single is true), of any real dtype
// (floats, integers), read as C-contiguous float64. TypeError for another dtype (strings, objects, complex,
// booleans), hovs.Error (a ValueError) for another shape; both name `what`.
struct Rows {
  py::array_t<double, py::array::c_style> array;
  py::ssize_t n = 0;
  bool single = false;
  const double* data() const { return array.data(); }
};
Rows AsRows(const py::handle& object, int k, const std::string& what);

// A new float64 array of shape (n, k), or (k) when single; NaN-filled unless `fill` is false (the caller then
// writes every element, from its worker threads: on large outputs the first touch of fresh pages costs as much
// as the projection, and a single-threaded fill would take it under the GIL).
py::array_t<double> NewRows(py::ssize_t n, int k, bool single, bool fill = true);
// A new bool array of shape (n), or a 0-d array when single; false-filled unless `fill` is false.
py::array_t<bool> NewFlags(py::ssize_t n, bool single, bool fill = true);

// An 8-bit image: (H, W) grey, (H, W, 1) grey or (H, W, 3) RGB, uint8, C-contiguous (copied if it is not).
// TypeError for another dtype, hovs.Error for another shape; both name `what`.
struct Image {
  py::array_t<uint8_t, py::array::c_style> array;
  int width = 0, height = 0, channels = 0;
};
Image AsImage(const py::handle& object, const std::string& what);

// A new uint8 image array: (H, W) when channels == 1, else (H, W, channels), filled from `data`.
py::array_t<uint8_t> NewImage(int width, int height, int channels, const uint8_t* data);
// A new float32 (H, W) array filled from `data`.
py::array_t<float> NewFloatImage(int width, int height, const float* data);

// A 4 x 4 rigid transform (rotation and translation; the last row 0 0 0 1) as an array, or an error naming `what`.
py::array_t<double> MatrixFromRotationTranslation(const double* r_row_major, const double* t);

}  // namespace hovs::python
