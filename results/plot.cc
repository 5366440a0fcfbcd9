#include "results/plot.h"

#include <vtkAxis.h>
#include <vtkCellArray.h>
#include <vtkChartHistogram2D.h>
#include <vtkChartLegend.h>
#include <vtkChartXY.h>
#include <vtkColorLegend.h>
#include <vtkColorTransferFunction.h>
#include <vtkContext2D.h>
#include <vtkContextScene.h>
#include <vtkContextView.h>
#include <vtkContourFilter.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkObjectFactory.h>
#include <vtkPNGReader.h>
#include <vtkPNGWriter.h>
#include <vtkPen.h>
#include <vtkPlot.h>
#include <vtkPlotHistogram2D.h>
#include <vtkPlotLine.h>
#include <vtkPlotPoints.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkRenderWindow.h>
#include <vtkRenderer.h>
#include <vtkStripper.h>
#include <vtkTable.h>
#include <vtkTextProperty.h>
#include <vtkUnsignedCharArray.h>
#include <vtkWindowToImageFilter.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/error.h"
#include "core/io.h"

namespace {

struct TextLabel {
  double x, y;
  std::string text;
  std::array<double, 3> rgb;
  int size;
  bool boxed;
};

// Text drawn at data coordinates inside a chart (contour labels, marker names).
class HovsLabelPlot : public vtkPlot {
 public:
  static HovsLabelPlot* New();
  vtkTypeMacro(HovsLabelPlot, vtkPlot) std::vector<TextLabel> labels;

  bool Paint(vtkContext2D* painter) override {
    for (const TextLabel& l : labels) {
      vtkTextProperty* tp = painter->GetTextProp();
      tp->SetColor(l.rgb[0], l.rgb[1], l.rgb[2]);
      tp->SetFontSize(l.size);
      tp->SetBold(l.boxed);
      tp->SetJustificationToLeft();
      tp->SetVerticalJustificationToCentered();
      tp->SetBackgroundColor(1, 1, 1);
      tp->SetBackgroundOpacity(l.boxed ? 0.8 : 0.6);
      painter->DrawString(static_cast<float>(l.x), static_cast<float>(l.y), l.text);
    }
    return true;
  }
  void GetBounds(double bounds[4]) override {
    if (labels.empty()) {
      bounds[0] = bounds[2] = 0;
      bounds[1] = bounds[3] = 1;
      return;
    }
    bounds[0] = bounds[2] = HUGE_VAL;
    bounds[1] = bounds[3] = -HUGE_VAL;
    for (const auto& l : labels) {
      bounds[0] = std::min(bounds[0], l.x), bounds[1] = std::max(bounds[1], l.x);
      bounds[2] = std::min(bounds[2], l.y), bounds[3] = std::max(bounds[3], l.y);
    }
  }
};
vtkStandardNewMacro(HovsLabelPlot)

    void RequireDisplay(const std::filesystem::path& path) {
  if (!hovs::results::CanRender())
    throw hovs::Error(path.string(), "cannot draw figures: no X display (DISPLAY is unset); run under `xvfb-run -a`");
}

// Renders the view and writes it to path through a temporary file.
void Save(vtkContextView* view, int width, int height, const std::filesystem::path& path) {
  view->GetRenderWindow()->SetOffScreenRendering(1);
  view->GetRenderWindow()->SetMultiSamples(0);
  view->GetRenderWindow()->SetSize(width, height);
  view->GetRenderer()->SetBackground(1, 1, 1);
  view->GetRenderWindow()->Render();
  vtkNew<vtkWindowToImageFilter> grab;
  grab->SetInput(view->GetRenderWindow());
  grab->ReadFrontBufferOff();
  grab->Update();
  const std::filesystem::path parent = path.has_parent_path() ? path.parent_path() : ".";
  const std::filesystem::path tmp = parent / ("." + path.filename().string() + ".tmp.png");
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(tmp.c_str());
  writer->SetInputConnection(grab->GetOutputPort());
  writer->Write();
  std::error_code ec;
  if (writer->GetErrorCode() != 0 || !std::filesystem::exists(tmp) || std::filesystem::file_size(tmp, ec) < 100) {
    std::filesystem::remove(tmp, ec);
    throw hovs::Error(path.string(), "the PNG writer failed");
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw hovs::Error(path.string(), "cannot rename into place: " + ec.message());
}

void StyleAxes(vtkChartXY* chart, const std::string& title, const std::string& xl, const std::string& yl) {
  chart->SetTitle(title);
  chart->GetTitleProperties()->SetFontSize(16);
  chart->GetTitleProperties()->SetBold(true);
  chart->GetAxis(vtkAxis::BOTTOM)->SetTitle(xl);
  chart->GetAxis(vtkAxis::LEFT)->SetTitle(yl);
  for (int a : {vtkAxis::BOTTOM, vtkAxis::LEFT}) {
    chart->GetAxis(a)->GetTitleProperties()->SetFontSize(14);
    chart->GetAxis(a)->GetLabelProperties()->SetFontSize(12);
  }
}

std::string Format(const std::string& fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt.c_str(), v);
  return buf;
}

// A perceptually ordered colour map (viridis control points).
void Viridis(vtkColorTransferFunction* tf, double lo, double hi) {
  static const double pts[][3] = {{0.267, 0.005, 0.329}, {0.283, 0.141, 0.458}, {0.254, 0.265, 0.530},
                                  {0.207, 0.372, 0.553}, {0.164, 0.471, 0.558}, {0.128, 0.567, 0.551},
                                  {0.135, 0.659, 0.518}, {0.267, 0.749, 0.441}, {0.478, 0.821, 0.318},
                                  {0.741, 0.873, 0.150}, {0.993, 0.906, 0.144}};
  const int n = 11;
  if (!(hi > lo)) hi = lo + 1;
  for (int i = 0; i < n; ++i) tf->AddRGBPoint(lo + (hi - lo) * i / (n - 1), pts[i][0], pts[i][1], pts[i][2]);
  tf->Build();
}

// Contour lines of `image` at `levels`, as chart lines, each labelled at its middle (with the level formatted,
// or with a fixed label).
void AddContours(vtkChartXY* chart, vtkImageData* image, const std::vector<double>& levels,
                 const std::array<double, 3>& rgb, double width, const std::string& format, const std::string& label,
                 HovsLabelPlot* labels, double label_at = 0.5) {
  if (levels.empty()) return;
  vtkNew<vtkContourFilter> contour;
  contour->SetInputData(image);
  for (size_t i = 0; i < levels.size(); ++i) contour->SetValue(static_cast<int>(i), levels[i]);
  vtkNew<vtkStripper> stripper;
  stripper->SetInputConnection(contour->GetOutputPort());
  stripper->JoinContiguousSegmentsOn();
  stripper->Update();
  vtkPolyData* lines = stripper->GetOutput();
  vtkDataArray* scalars = lines->GetPointData()->GetScalars();
  vtkCellArray* cells = lines->GetLines();
  vtkNew<vtkIdList> ids;
  cells->InitTraversal();
  bool labelled = false;
  while (cells->GetNextCell(ids)) {
    if (ids->GetNumberOfIds() < 2) continue;
    vtkNew<vtkTable> table;
    vtkNew<vtkFloatArray> xs, ys;
    xs->SetName("x");
    ys->SetName("y");
    table->AddColumn(xs);
    table->AddColumn(ys);
    table->SetNumberOfRows(ids->GetNumberOfIds());
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) {
      double p[3];
      lines->GetPoint(ids->GetId(k), p);
      table->SetValue(k, 0, p[0]);
      table->SetValue(k, 1, p[1]);
    }
    vtkPlot* line = chart->AddPlot(vtkChart::LINE);
    line->SetInputData(table, 0, 1);
    line->SetColor(static_cast<unsigned char>(255 * rgb[0]), static_cast<unsigned char>(255 * rgb[1]),
                   static_cast<unsigned char>(255 * rgb[2]), 235);
    line->SetWidth(static_cast<float>(width));
    if (!label.empty() && labelled) continue;
    const vtkIdType mid = ids->GetId(std::clamp<vtkIdType>(
        static_cast<vtkIdType>(label_at * (ids->GetNumberOfIds() - 1)), 0, ids->GetNumberOfIds() - 1));
    double p[3];
    lines->GetPoint(mid, p);
    const std::string text = label.empty() ? Format(format, scalars ? scalars->GetTuple1(mid) : 0.0) : label;
    labels->labels.push_back({p[0], p[1], text, {0.05, 0.05, 0.05}, label.empty() ? 11 : 12, !label.empty()});
    labelled = true;
  }
}

}  // namespace

namespace hovs::results {

ImageStats PngStats(const std::filesystem::path& path) {
  RequireFile(path, "PNG file");
  vtkNew<vtkPNGReader> reader;
  HOVS_REQUIRE(reader->CanReadFile(path.c_str()), path.string(), "not a PNG file");
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* img = reader->GetOutput();
  int dims[3];
  img->GetDimensions(dims);
  ImageStats s;
  s.width = dims[0], s.height = dims[1], s.channels = img->GetNumberOfScalarComponents();
  vtkDataArray* a = img->GetPointData()->GetScalars();
  const vtkIdType n = a->GetNumberOfTuples();
  double sum = 0, sum2 = 0;
  vtkIdType non_white = 0;
  for (vtkIdType i = 0; i < n; ++i) {
    bool white = true;
    for (int c = 0; c < s.channels; ++c) {
      const double v = a->GetComponent(i, c);
      sum += v, sum2 += v * v;
      if (c < 3 && v < 245) white = false;
    }
    non_white += !white;
  }
  const double count = static_cast<double>(n) * s.channels;
  s.mean = sum / count;
  s.stddev = std::sqrt(std::max(0.0, sum2 / count - s.mean * s.mean));
  s.non_white_fraction = static_cast<double>(non_white) / n;
  return s;
}

bool CanRender() {
  const char* d = std::getenv("DISPLAY");
  return d != nullptr && d[0] != '\0';
}

void WritePng(const HeatMapFigure& f, const std::filesystem::path& path) {
  RequireDisplay(path);
  HOVS_REQUIRE(f.nx >= 2 && f.ny >= 2 && f.values.size() == static_cast<size_t>(f.nx) * f.ny, path.string(),
               "heat map needs an nx x ny grid of values");
  HOVS_REQUIRE(f.shade.empty() || f.shade.size() == f.values.size(), path.string(), "shade mask size mismatch");
  const double dx = (f.x1 - f.x0) / (f.nx - 1), dy = (f.y1 - f.y0) / (f.ny - 1);

  vtkNew<vtkImageData> image;
  image->SetExtent(0, f.nx - 1, 0, f.ny - 1, 0, 0);
  image->SetOrigin(f.x0, f.y0, 0);
  image->SetSpacing(dx, dy, 1);
  image->AllocateScalars(VTK_DOUBLE, 1);
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  auto* px = static_cast<double*>(image->GetScalarPointer(0, 0, 0));
  for (size_t i = 0; i < f.values.size(); ++i) {
    px[i] = f.values[i];
    if (std::isfinite(f.values[i])) lo = std::min(lo, f.values[i]), hi = std::max(hi, f.values[i]);
  }
  HOVS_REQUIRE(std::isfinite(lo), path.string(), "heat map has no finite value");

  vtkNew<vtkContextView> view;
  vtkNew<vtkChartHistogram2D> chart;
  view->GetScene()->AddItem(chart);
  chart->SetInputData(image);
  vtkNew<vtkColorTransferFunction> tf;
  Viridis(tf, lo, hi);
  chart->SetTransferFunction(tf);
  if (auto* legend = vtkColorLegend::SafeDownCast(chart->GetLegend())) legend->SetTitle(f.value_label);
  StyleAxes(chart, f.shade_label.empty() ? f.title : f.title + "\n(" + f.shade_label + ")", f.x_label, f.y_label);

  if (!f.shade.empty()) {
    vtkNew<vtkImageData> mask;
    mask->SetExtent(0, f.nx - 1, 0, f.ny - 1, 0, 0);
    mask->SetOrigin(f.x0, f.y0, 0);
    mask->SetSpacing(dx, dy, 1);
    mask->AllocateScalars(VTK_DOUBLE, 1);
    auto* mp = static_cast<double*>(mask->GetScalarPointer(0, 0, 0));
    for (size_t i = 0; i < f.shade.size(); ++i) mp[i] = f.shade[i] ? 1.0 : 0.0;
    vtkNew<vtkLookupTable> lut;
    lut->SetNumberOfTableValues(2);
    lut->SetTableRange(0, 1);
    lut->SetTableValue(0, 0, 0, 0, 0);
    lut->SetTableValue(1, 1, 1, 1, 0.62);
    vtkNew<vtkPlotHistogram2D> shade;
    shade->SetInputData(mask);
    shade->SetTransferFunction(lut);
    chart->AddPlot(shade);
  }

  vtkNew<HovsLabelPlot> labels;
  AddContours(chart, image, f.contour_levels, {1, 1, 1}, 1.4, f.contour_format, "", labels);
  for (size_t oi = 0; oi < f.overlays.size(); ++oi) {
    const ContourOverlay& o = f.overlays[oi];
    HOVS_REQUIRE(o.values.size() == f.values.size(), path.string(), "overlay '", o.label, "' has the wrong size");
    vtkNew<vtkImageData> other;
    other->SetExtent(0, f.nx - 1, 0, f.ny - 1, 0, 0);
    other->SetOrigin(f.x0, f.y0, 0);
    other->SetSpacing(dx, dy, 1);
    other->AllocateScalars(VTK_DOUBLE, 1);
    std::copy(o.values.begin(), o.values.end(), static_cast<double*>(other->GetScalarPointer(0, 0, 0)));
    AddContours(chart, other, {o.level}, o.rgb, o.line_width, "", o.label, labels, oi % 2 == 0 ? 0.12 : 0.88);
  }
  static const int styles[] = {vtkPlotPoints::CIRCLE, vtkPlotPoints::CROSS, vtkPlotPoints::PLUS, vtkPlotPoints::SQUARE,
                               vtkPlotPoints::DIAMOND};
  const auto add_points = [&](const std::vector<double>& xs, const std::vector<double>& ys, const std::string& name,
                              const std::array<double, 3>& rgb, int style, double size, double width) {
    vtkNew<vtkTable> table;
    vtkNew<vtkDoubleArray> cx, cy;
    cx->SetName("x");
    cy->SetName(name.c_str());
    table->AddColumn(cx);
    table->AddColumn(cy);
    table->SetNumberOfRows(static_cast<vtkIdType>(xs.size()));
    for (size_t i = 0; i < xs.size(); ++i) {
      table->SetValue(static_cast<vtkIdType>(i), 0, xs[i]);
      table->SetValue(static_cast<vtkIdType>(i), 1, ys[i]);
    }
    auto* points = vtkPlotPoints::SafeDownCast(chart->AddPlot(vtkChart::POINTS));
    points->SetInputData(table, 0, 1);
    points->SetColor(static_cast<unsigned char>(255 * rgb[0]), static_cast<unsigned char>(255 * rgb[1]),
                     static_cast<unsigned char>(255 * rgb[2]), 255);
    points->SetMarkerStyle(styles[std::clamp(style, 0, 4)]);
    points->SetMarkerSize(static_cast<float>(size));
    points->SetWidth(static_cast<float>(width));
  };
  for (const PointSet& ps : f.point_sets) {
    if (ps.x.empty()) continue;
    add_points(ps.x, ps.y, ps.label, ps.rgb, ps.style, ps.size, 1.5);
  }
  // Markers, and a key in the top-left corner (marker symbol + label) so labels never overlap.
  for (size_t k = 0; k < f.markers.size(); ++k) {
    const Marker& m = f.markers[k];
    add_points({m.x}, {m.y}, m.label, m.rgb, m.style, 14, 3);
    const double kx = f.x0 + 0.03 * (f.x1 - f.x0), ky = f.y1 - (0.04 + 0.05 * k) * (f.y1 - f.y0);
    add_points({kx}, {ky}, m.label, m.rgb, m.style, 12, 3);
    labels->labels.push_back({kx + 0.025 * (f.x1 - f.x0), ky, m.label, m.rgb, 13, true});
  }
  for (size_t k = 0; k < f.point_sets.size(); ++k) {
    const PointSet& ps = f.point_sets[k];
    if (ps.label.empty()) continue;
    const double kx = f.x0 + 0.03 * (f.x1 - f.x0), ky = f.y1 - (0.04 + 0.05 * (f.markers.size() + k)) * (f.y1 - f.y0);
    add_points({kx}, {ky}, ps.label, ps.rgb, ps.style, ps.size + 2, 1.5);
    labels->labels.push_back({kx + 0.025 * (f.x1 - f.x0), ky, ps.label, ps.rgb, 13, true});
  }
  chart->AddPlot(labels);
  for (int a : {vtkAxis::BOTTOM, vtkAxis::LEFT}) chart->GetAxis(a)->SetBehavior(vtkAxis::FIXED);
  chart->GetAxis(vtkAxis::BOTTOM)->SetRange(f.x0, f.x1);
  chart->GetAxis(vtkAxis::LEFT)->SetRange(f.y0, f.y1);
  Save(view, f.width, f.height, path);
}

void WritePng(const LineFigure& f, const std::filesystem::path& path) {
  RequireDisplay(path);
  HOVS_REQUIRE(!f.series.empty(), path.string(), "line figure has no series");
  vtkNew<vtkContextView> view;
  vtkNew<vtkChartXY> chart;
  view->GetScene()->AddItem(chart);
  StyleAxes(chart, f.title, f.x_label, f.y_label);
  for (const Series& s : f.series) {
    HOVS_REQUIRE(s.x.size() == s.y.size() && s.x.size() >= (s.points ? 1u : 2u), path.string(), "series '", s.name,
                 "' needs matching x and y with ", s.points ? "one" : "two", " or more points");
    vtkNew<vtkTable> table;
    vtkNew<vtkDoubleArray> xs, ys;
    xs->SetName("x");
    ys->SetName(s.name.c_str());
    table->AddColumn(xs);
    table->AddColumn(ys);
    table->SetNumberOfRows(static_cast<vtkIdType>(s.x.size()));
    for (size_t i = 0; i < s.x.size(); ++i) {
      table->SetValue(static_cast<vtkIdType>(i), 0, s.x[i]);
      table->SetValue(static_cast<vtkIdType>(i), 1, s.y[i]);
    }
    vtkPlot* line = chart->AddPlot(s.points ? vtkChart::POINTS : vtkChart::LINE);
    line->SetInputData(table, 0, 1);
    line->SetColor(static_cast<unsigned char>(255 * s.rgb[0]), static_cast<unsigned char>(255 * s.rgb[1]),
                   static_cast<unsigned char>(255 * s.rgb[2]), 255);
    line->SetWidth(static_cast<float>(s.line_width));
    line->SetLegendVisibility(s.in_legend);
    if (s.points) {
      auto* points = vtkPlotPoints::SafeDownCast(line);
      points->SetMarkerStyle(vtkPlotPoints::CIRCLE);
      points->SetMarkerSize(static_cast<float>(s.marker_size));
    }
  }
  chart->SetShowLegend(true);
  chart->GetLegend()->SetHorizontalAlignment(vtkChartLegend::RIGHT);
  chart->GetLegend()->SetVerticalAlignment(vtkChartLegend::TOP);
  chart->GetLegend()->GetLabelProperties()->SetFontSize(12);
  Save(view, f.width, f.height, path);
}

}  // namespace hovs::results
