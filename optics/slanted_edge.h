// The MTF of an image from a slanted edge (ISO 12233 style; optics/README.md): the edge located in every line
// across it (the centroid of the line's derivative), a quadratic fitted to those positions (a catadioptric image
// bends straight edges, so the line of ISO 12233:2000 becomes the polynomial of its 2017 edition), every pixel
// binned by its signed distance from the fitted edge at a quarter pixel (the edge spread function), its
// derivative windowed by a Hamming window (the line spread function), and the magnitude of its Fourier transform,
// normalised at 0 and divided by the derivative's own sinc.
#pragma once

#include <vector>

#include "core/types.h"

namespace hovs::optics {

struct EdgeMtf {
  bool ok = false;
  Vec2d normal = Vec2d(1, 0);   // the edge's unit normal (pixels; mean over the fit)
  std::vector<double> nu, mtf;  // cycles / px, 0 .. 1 in steps of 1 / 128
  double mtf50 = 0;             // cycles / px
  double edge_offset = 0;       // the fitted edge's mean position across the region, px from its first pixel
};

// The edge of a w x h grey region (row-major), with the edge running along y (across_x: intensity changes along
// x) or along x. Needs at least 16 lines along the edge and 16 pixels across it.
EdgeMtf MeasureSlantedEdge(const std::vector<float>& grey, int w, int h, bool across_x);

}  // namespace hovs::optics
