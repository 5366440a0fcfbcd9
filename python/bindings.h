// The pieces of the Python module, one function per area, each defining its classes and functions on `m`.
#pragma once

#include <pybind11/pybind11.h>

#include <string>

#include "core/any_model.h"

namespace hovs::python {

namespace py = pybind11;

// A camera model of any kind (core/any_model.h) and the file it came from.
struct Camera {
  AnyModel model;
  std::string source;
};

void BindCamera(py::module_& m);       // Camera, load_camera
void BindUnwrap(py::module_& m);       // Unwrapper
void BindDataset(py::module_& m);      // Dataset
void BindStudy(py::module_& m);        // design metrics and studies, stereo triangulation
void BindCalibration(py::module_& m);  // calibrate

}  // namespace hovs::python
