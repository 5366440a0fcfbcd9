// The blur prediction checked against the renderer: slanted-edge targets (ISO 12233 style) rendered through the
// thin lens at a grid of elevations x scene distances, their MTF measured from the rendered pixels
// (optics/slanted_edge.h) and compared with the MTF the exact spot predicts (optics/blur.h) times the pixel's own.
//
// Each target is a plane facing the viewpoint F1, a 2 x 2 checkerboard turned 5 deg in its plane: the edge along
// the azimuth images as a tangential curve (its spread is the radial MTF), the edge along the elevation as a
// radial one (the tangential MTF). A region of the image on each edge, away from the corner, is rendered alone
// (RenderOptions::region), with many samples per pixel over the pixel and the aperture, no sensor noise. The
// renderer traces geometric rays, so the prediction is the geometric MTF (no diffraction) times the pixel's box.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "design/design.h"

namespace hovs::study {

struct EdgeCheckOptions {
  design::DesignPoint mirror{0.048, 0.044, 0.080};
  design::CameraSpec camera;                      // its lens (f-number, focus) is the one rendered (below)
  std::vector<double> elevations_deg;             // empty: 5 evenly inside the field
  std::vector<double> distances{1.0, 5.0, 50.0};  // from F1, m
  int samples = 400;                              // per pixel (a square: stratified)
  int region = 48;                                // px, the square rendered on each edge
  uint64_t seed = 1;
  double tolerance = 0.10;  // relative MTF50 agreement required
  void Check(const std::string& where) const;
};

struct EdgeResult {
  double elevation_deg = 0, distance = 0;
  std::string direction;                           // "radial" or "tangential"
  double predicted_rms = 0;                        // the spot's RMS radius there, px
  double predicted_mtf50 = 0, measured_mtf50 = 0;  // cycles / px
  double relative_error = 0;                       // |measured - predicted| / predicted
  bool ok = false;                                 // the edge was measured and within the tolerance
  std::string note;                                // why a measurement failed
};

struct EdgeCheck {
  EdgeCheckOptions options;
  std::vector<EdgeResult> results;
  double focus_distance = 0;
  double max_relative_error = 0;
  int passed = 0;
  double seconds = 0;
  bool AllPass() const { return passed == static_cast<int>(results.size()) && !results.empty(); }
};

// A lens focused at infinity is rendered at the best single focus over the field for 1 m .. infinity instead
// (EdgeCheck::options holds the focus used).
EdgeCheck RunEdgeCheck(const EdgeCheckOptions& options);
nlohmann::json EdgeCheckJson(const EdgeCheck& check);
std::string EdgeCheckSummary(const EdgeCheck& check);
// Writes out/ atomically: edge_check.json (with the versions), edges.csv, summary.txt. Returns the summary.
std::string WriteEdgeCheck(const EdgeCheck& check, const std::filesystem::path& out,
                           const std::map<std::string, std::string>& versions);

}  // namespace hovs::study
