// Surface textures of the renderer, evaluated at (s, t) in metres on a rectangle's own plane (s along its
// x edge, t along its y edge, origin at its centre). Procedural textures (checkerboard, value noise) are exact
// at any scale, so the only anti-aliasing is the renderer's supersampling and ground truth stays sharp.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace hovs::raytrace {

using Rgb = std::array<float, 3>;

// An image sampled bilinearly; (0, 0) at the centre of the top-left pixel, stretched over the rectangle.
struct ImageTexture {
  int width = 0, height = 0, channels = 3;
  std::vector<float> pixels;  // linear RGB in [0, 1], row-major
  std::string source;

  // Reads any format OpenImageIO reads. Throws hovs::Error naming the file.
  static ImageTexture Load(const std::string& path);
  // From an 8-bit single-channel image (e.g. an ArUco board drawn by OpenCV).
  static ImageTexture FromGray8(const uint8_t* data, int width, int height, const std::string& source);
  Rgb Sample(double x, double y) const;  // pixel coordinates
};

struct Texture {
  enum class Kind { kSolid, kChecker, kImage, kNoise };
  Kind kind = Kind::kSolid;
  Rgb colour_a = {0.8f, 0.8f, 0.8f};  // solid colour; checker's dark squares; noise's low end
  Rgb colour_b = {1, 1, 1};           // checker's light squares; noise's high end
  // Checker: squares of `square` metres, squares_x by squares_y, centred; outside them the margin colour.
  double square = 0.03;
  int squares_x = 9, squares_y = 7;
  Rgb margin = {1, 1, 1};
  // Image: the texture covers width x height metres of the surface (centred).
  std::shared_ptr<const ImageTexture> image;
  double image_width = 1, image_height = 1;
  // Noise: value noise with `octaves` octaves (1..12; more count as 12), base cell `scale` metres, deterministic
  // from `seed`.
  double scale = 0.05;
  int octaves = 4;
  uint32_t seed = 1;

  Rgb Eval(double s, double t) const;
  // Eval at n points into interleaved RGB (rgb[3 i + c]), the checkerboard and the noise vectorised: the
  // renderer's runs of samples on one rectangle. For double points bit-identical to Eval; for single-precision
  // points (the renderer's colour samples) the noise's cell positions come from float arithmetic.
  void EvalInto(int n, const double* s, const double* t, float* rgb) const;
  void EvalInto(int n, const float* s, const float* t, float* rgb) const;
};

}  // namespace hovs::raytrace
