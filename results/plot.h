// Figures for reports, drawn with VTK's charts offscreen and written as PNG. Rendering needs an X display
// (run under `xvfb-run -a`); without one, the functions throw hovs::Error saying so.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace hovs::results {

struct Marker {
  double x = 0, y = 0;
  std::string label;
  std::array<double, 3> rgb = {0, 0, 0};
  int style = 0;  // 0 circle, 1 cross, 2 plus, 3 square, 4 diamond
};

// A contour of another field on the same grid (e.g. a constraint boundary drawn over the objective).
struct ContourOverlay {
  std::vector<double> values;  // nx * ny, same layout as HeatMapFigure::values
  double level = 0;
  std::string label;
  std::array<double, 3> rgb = {1, 1, 1};
  double line_width = 3.0;
};

// Many small markers (e.g. the integer-millimetre grid).
struct PointSet {
  std::vector<double> x, y;
  std::string label;
  std::array<double, 3> rgb = {0, 0, 0};
  int style = 0;
  double size = 5;
};

// A scalar field on a regular grid drawn as a heat map with contour lines, an optional shaded region
// (e.g. infeasible designs) and markers.
struct HeatMapFigure {
  std::string title, x_label, y_label, value_label;
  int nx = 0, ny = 0;                     // grid size
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;  // coordinates of the first and last grid nodes
  std::vector<double> values;             // ny rows of nx values (row j at y = y0 + j (y1 - y0) / (ny - 1))
  std::vector<double> contour_levels;     // labelled contour lines
  std::string contour_format = "%.0f";
  std::vector<uint8_t> shade;  // optional, nx * ny: 1 = shaded (drawn pale)
  std::string shade_label;     // what the shading means (shown in the title line)
  std::vector<ContourOverlay> overlays;
  std::vector<PointSet> point_sets;
  std::vector<Marker> markers;  // listed in a key in the top-left corner
  int width = 900, height = 720;
};

struct Series {
  std::string name;
  std::vector<double> x, y;
  std::array<double, 3> rgb = {0.1, 0.3, 0.8};
  double line_width = 2.0;
  bool points = false;  // a scatter of markers (marker_size px) instead of a line
  double marker_size = 4.0;
  bool in_legend = true;  // false: drawn but not listed (many runs of one kind)
};

struct LineFigure {
  std::string title, x_label, y_label;
  std::vector<Series> series;
  int width = 900, height = 560;
};

// Write the figure to a PNG file (atomically). Throws hovs::Error naming the file on failure.
void WritePng(const HeatMapFigure& figure, const std::filesystem::path& path);
void WritePng(const LineFigure& figure, const std::filesystem::path& path);

// Statistics of a PNG file, to check that a figure holds a picture (tests, reports).
struct ImageStats {
  int width = 0, height = 0, channels = 0;
  double mean = 0, stddev = 0;    // over all channels, 0..255
  double non_white_fraction = 0;  // pixels not (near) white
};
ImageStats PngStats(const std::filesystem::path& path);

// True when an X display is available for rendering.
bool CanRender();

}  // namespace hovs::results
