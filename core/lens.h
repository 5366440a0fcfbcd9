// The camera's lens as an ideal thin lens: one definition read by design configs, scenes and the turret machine.
//
//   aperture diameter     D = f / N                       (N: the f-number, focus at infinity)
//   sensor distance       s = f d_f / (d_f - f)           (d_f: focus distance, object side, from the lens;
//                                                          s = f when focused at infinity)
//   image scale           s / pixel pitch, px            (the pinhole distance of the projection in force)
//   working f-number      N_w = s / D                     (the cone that reaches the sensor; diffraction uses it)
//   relative irradiance   1 / N^2                         (against f/1; the light figure of a design)
// A lens focused at or inside its focal length forms no real image: Check refuses it.
#pragma once

#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/pinhole.h"

namespace hovs {

struct ThinLens {
  double focal_length = 0.016;                                      // m
  double f_number = 4.0;                                            // N
  double focus_distance = std::numeric_limits<double>::infinity();  // m, object side, from the lens
  double wavelength = 550e-9;                                       // m, for the diffraction MTF

  double ApertureDiameter() const { return focal_length / f_number; }
  double ApertureRadius() const { return 0.5 * ApertureDiameter(); }
  // Sensor distance for a focus distance d (m from the lens; +inf: f).
  double SensorDistanceAt(double d) const {
    return std::isinf(d) ? focal_length : focal_length * d / (d - focal_length);
  }
  double SensorDistance() const { return SensorDistanceAt(focus_distance); }
  double WorkingFNumberAt(double d) const { return SensorDistanceAt(d) / ApertureDiameter(); }
  double RelativeIrradiance() const { return 1.0 / (f_number * f_number); }

  // The pinhole camera of the projection with the lens focused at d: image scale s(d) / pitch, principal point
  // at the image centre.
  PinholeCamera<double> CameraAt(double d, double pixel_pitch, int width, int height) const {
    return PinholeCamera<double>::FromPhysical(SensorDistanceAt(d), pixel_pitch, width, height);
  }
  PinholeCamera<double> Camera(double pixel_pitch, int width, int height) const {
    return CameraAt(focus_distance, pixel_pitch, width, height);
  }

  // Throws hovs::Error(where) naming the value that is not a lens.
  void Check(const std::string& where) const {
    HOVS_REQUIRE(std::isfinite(focal_length) && focal_length > 0 && focal_length <= 10, where,
                 "focal_length must be in (0, 10] m (got ", focal_length, ")");
    HOVS_REQUIRE(std::isfinite(f_number) && f_number >= 0.5 && f_number <= 1000, where,
                 "f_number must be in [0.5, 1000] (got ", f_number, ")");
    HOVS_REQUIRE(!std::isnan(focus_distance) && focus_distance > focal_length, where,
                 "focus_distance must be beyond the focal length ", focal_length,
                 " m (a lens focused inside it forms no image; got ", focus_distance, ")");
    HOVS_REQUIRE(std::isfinite(wavelength) && wavelength >= 100e-9 && wavelength <= 20e-6, where,
                 "wavelength must be in [1e-7, 2e-5] m (got ", wavelength, ")");
  }
};

}  // namespace hovs
