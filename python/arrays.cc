#include "python/arrays.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.h"

namespace hovs::python {

namespace {

// Real numbers only: a bool array is almost always a mask passed by mistake, and complex or object arrays have no
// meaning as coordinates.
void RequireRealDtype(const py::array& a, const std::string& what) {
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(what + ": expected an array of real numbers (float or integer), got dtype " +
                         std::string(py::str(a.dtype())));
}

std::string ShapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += (d ? ", " : "") + std::to_string(a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

Rows AsRows(const py::handle& object, int k, const std::string& what) {
  // Lists and tuples are accepted as NumPy would read them.
  const py::array a = py::array::ensure(object);
  if (!a) throw py::type_error(what + ": expected an array of shape (N, " + std::to_string(k) + ")");
  RequireRealDtype(a, what);
  Rows r;
  if (a.ndim() == 1 && a.shape(0) == k) {
    r.single = true, r.n = 1;
  } else if (a.ndim() == 2 && a.shape(1) == k) {
    r.n = a.shape(0);
  } else {
    throw Error(what,
                "expected shape (N, " + std::to_string(k) + ") or (" + std::to_string(k) + ",), got " + ShapeText(a));
  }
  r.array = py::array_t<double, py::array::c_style>::ensure(a);
  if (!r.array) throw py::type_error(what + ": cannot be read as float64");
  return r;
}

py::array_t<double> NewRows(py::ssize_t n, int k, bool single, bool fill) {
  py::array_t<double> a = single ? py::array_t<double>({py::ssize_t(k)}) : py::array_t<double>({n, py::ssize_t(k)});
  if (fill) std::fill_n(a.mutable_data(), a.size(), std::numeric_limits<double>::quiet_NaN());
  return a;
}

py::array_t<bool> NewFlags(py::ssize_t n, bool single, bool fill) {
  py::array_t<bool> a = single ? py::array_t<bool>(std::vector<py::ssize_t>{}) : py::array_t<bool>({n});
  if (fill) std::fill_n(a.mutable_data(), a.size(), false);
  return a;
}

Image AsImage(const py::handle& object, const std::string& what) {
  const py::array a = py::array::ensure(object);
  if (!a) throw py::type_error(what + ": expected a NumPy image array");
  if (a.dtype().kind() != 'u' || a.dtype().itemsize() != 1)
    throw py::type_error(what + ": expected a uint8 image, got dtype " + std::string(py::str(a.dtype())));
  Image im;
  if (a.ndim() == 2) {
    im.channels = 1;
  } else if (a.ndim() == 3 && (a.shape(2) == 1 || a.shape(2) == 3)) {
    im.channels = int(a.shape(2));
  } else {
    throw Error(what, "expected an image of shape (H, W), (H, W, 1) or (H, W, 3), got " + ShapeText(a));
  }
  HOVS_REQUIRE(a.shape(0) > 0 && a.shape(1) > 0 && a.shape(0) <= 65535 && a.shape(1) <= 65535, what,
               "the image must be 1..65535 pixels a side, got ", ShapeText(a));
  im.height = int(a.shape(0)), im.width = int(a.shape(1));
  im.array = py::array_t<uint8_t, py::array::c_style>::ensure(a);
  return im;
}

py::array_t<uint8_t> NewImage(int width, int height, int channels, const uint8_t* data) {
  py::array_t<uint8_t> a = channels == 1
                               ? py::array_t<uint8_t>({py::ssize_t(height), py::ssize_t(width)})
                               : py::array_t<uint8_t>({py::ssize_t(height), py::ssize_t(width), py::ssize_t(channels)});
  std::memcpy(a.mutable_data(), data, size_t(a.size()));
  return a;
}

py::array_t<float> NewFloatImage(int width, int height, const float* data) {
  py::array_t<float> a({py::ssize_t(height), py::ssize_t(width)});
  std::memcpy(a.mutable_data(), data, size_t(a.size()) * sizeof(float));
  return a;
}

py::array_t<double> MatrixFromRotationTranslation(const double* r, const double* t) {
  py::array_t<double> m({4, 4});
  double* p = m.mutable_data();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) p[4 * i + j] = r[3 * i + j];
    p[4 * i + 3] = t[i];
  }
  p[12] = p[13] = p[14] = 0, p[15] = 1;
  return m;
}

}  // namespace hovs::python
