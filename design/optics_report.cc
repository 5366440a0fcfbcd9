#include "design/optics_report.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include <tbb/parallel_for.h>

#include "core/format.h"
#include "results/plot.h"

namespace hovs::design {
namespace {

constexpr int kAtlasElevations = 64, kAtlasDistances = 32;
constexpr int kTradeElevations = 24, kTradeDistances = 6, kTradePupil = 64;

// The atlas's scene distances: log-spaced from near to far, with +inf as the last when far is infinite (up to
// 1e4 m before it).
std::vector<double> SceneDistances(const BlurSpec& b, int n) {
  if (std::isinf(b.far)) return optics::DistanceGrid(b.near, std::max(1e4, 10 * b.near), n);
  std::vector<double> out;
  for (int k = 0; k < n; ++k) out.push_back(b.near * std::pow(b.far / b.near, double(k) / (n - 1)));
  return out;
}

std::string Distance(double d) { return std::isinf(d) ? "inf" : FormatNumber("%.4g", d); }
std::string DistanceCsv(double d) { return std::isinf(d) ? "inf" : FormatNumber("%.9g", d); }
nlohmann::json DistanceValue(double d) { return std::isinf(d) ? nlohmann::json("infinity") : nlohmann::json(d); }

optics::OpticalSystem SystemOf(const DesignPoint& p, const CameraSpec& camera, int pupil) {
  optics::OpticalSystem sys;
  sys.rig = RigOf(p, camera);
  sys.lens = camera.Lens();
  sys.pixel_pitch = camera.pixel_pitch;
  sys.pupil_samples = pupil;
  return sys;
}

// The worst RMS radius over a coarse field grid at the best single focus, for one f-number.
FNumberTrade TradeAt(const DesignPoint& p, const DesignProblem& problem, const Metrics& m, double f_number) {
  CameraSpec cam = problem.camera;
  cam.lens.f_number = f_number;
  const optics::OpticalSystem sys = SystemOf(p, cam, kTradePupil);
  const auto fields =
      optics::FieldGrid(m.lower_deg, m.upper_deg, kTradeElevations, SceneDistances(problem.blur, kTradeDistances));
  const auto traced = optics::TraceFields(sys, fields);
  const optics::SingleFocus best = optics::BestSingleFocus(sys, traced, 1.5 * cam.focal_length);
  FNumberTrade t;
  t.f_number = f_number, t.best_focus = best.focus_distance, t.worst_rms = best.worst_rms;
  t.airy_radius_px = 1.22 * sys.lens.wavelength * sys.lens.WorkingFNumberAt(best.focus_distance) / cam.pixel_pitch;
  return t;
}

}  // namespace

namespace {

// The smallest f-number (on the coarse trade grid) whose worst RMS radius is within limit_px (the blur falls as
// the aperture closes); 0 when none up to f/256 is.
double FNumberForLimit(const DesignPoint& p, const DesignProblem& problem, const Metrics& m, double limit_px) {
  double lo = 0.5, hi = 256;
  if (!(TradeAt(p, problem, m, hi).worst_rms <= limit_px)) return 0;
  for (int it = 0; it < 12; ++it) {
    const double mid = std::sqrt(lo * hi);
    (TradeAt(p, problem, m, mid).worst_rms <= limit_px ? hi : lo) = mid;
  }
  return hi;
}

DesignOptics AnalyseAt(const DesignPoint& p, const DesignProblem& problem, const std::string& label) {
  DesignOptics o;
  o.label = label, o.p = p;
  o.metrics = Evaluate(p, problem);
  o.lens = problem.camera.Lens();
  const optics::OpticalSystem sys = SystemOf(p, problem.camera, 256);
  const double min_focus = 1.5 * o.lens.focal_length;
  o.distances = SceneDistances(problem.blur, kAtlasDistances);
  const auto fields = optics::FieldGrid(o.metrics.lower_deg, o.metrics.upper_deg, kAtlasElevations, o.distances);
  for (int i = 0; i < kAtlasElevations; ++i) o.elevations.push_back(fields[i * o.distances.size()].elevation_deg);
  const std::vector<optics::TracedField> traced = optics::TraceFields(sys, fields);
  o.best = optics::BestSingleFocus(sys, traced, min_focus);
  o.depth_of_focus = optics::DepthOfFocusOf(sys, traced, o.best, problem.blur.limit_px, min_focus);
  o.focus_given = !std::isinf(o.lens.focus_distance);
  o.focus = o.focus_given ? o.lens.focus_distance : o.best.focus_distance;
  o.atlas.resize(traced.size());
  tbb::parallel_for(size_t(0), traced.size(),
                    [&](size_t i) { o.atlas[i] = optics::BlurOf(sys, traced[i].field, traced[i].bundle, o.focus); });
  for (const auto& b : o.atlas) o.worst_rms = std::max(o.worst_rms, b.spot.rms);

  // The design again with its lens at the best single focus: the image scale s grows as the focus comes closer.
  DesignProblem at_best = problem;
  at_best.camera.lens.focus_distance = o.best.focus_distance;
  o.at_best = Evaluate(p, at_best);
  o.constraints_at_best = EvaluateConstraints(o.at_best, at_best);

  for (int i = 0; i < 16; ++i) {
    const double e = o.metrics.lower_deg + (o.metrics.upper_deg - o.metrics.lower_deg) * (i + 0.5) / 16;
    o.dof.push_back(optics::DepthOfFieldAt(sys, e, o.focus, problem.blur.limit_px, problem.blur.near));
  }

  for (const double n : {2.0, 2.8, 4.0, 5.6, 8.0, 11.0, 16.0, 22.0, 32.0})
    o.trade.push_back(TradeAt(p, problem, o.metrics, n));
  o.f_number_for_limit = FNumberForLimit(p, problem, o.metrics, problem.blur.FNumberLimitPx());

  // Spot diagrams and through-focus curves on a 5 x 3 grid of field points.
  const double far = std::isinf(problem.blur.far) ? optics::kInfinity : problem.blur.far;
  o.spot_distances = {problem.blur.near, std::sqrt(problem.blur.near * std::min(far, 1e4)), far};
  for (int i = 0; i < 5; ++i)
    o.spot_elevations.push_back(o.metrics.lower_deg + (o.metrics.upper_deg - o.metrics.lower_deg) * (i + 0.5) / 5);
  const std::vector<double> pupil = optics::PupilPoints(sys.pupil_samples, sys.lens.ApertureRadius());
  // Through focus about the best single focus: vergences from 0.6 to 1.6 times its own.
  for (int k = 0; k <= 40; ++k) o.through_focus_distances.push_back(o.best.focus_distance / (0.6 + k * 0.025));
  for (const double e : o.spot_elevations) {
    for (const double d : o.spot_distances) {
      const optics::FieldPoint f{e, 0, d};
      const optics::Bundle b = optics::TraceBundle(sys.rig, f.Position(), sys.lens.ApertureRadius(), pupil);
      o.spots.push_back(optics::BlurOf(sys, f, b, o.focus, /*keep_points=*/true));
      if (d == o.spot_distances.back())
        o.through_focus.push_back(optics::ThroughFocus(sys, b, o.through_focus_distances));
    }
  }
  return o;
}

}  // namespace

DesignOptics AnalyseOptics(const DesignPoint& p, const DesignProblem& given, const std::string& label) {
  const double limit = given.blur.FNumberLimitPx();
  DesignProblem problem = given;
  if (given.blur.auto_f_number) {
    const double n = FNumberForLimit(p, given, Evaluate(p, given), limit);
    if (n > 0) problem.camera.lens.f_number = n;
  }
  DesignOptics o = AnalyseAt(p, problem, label);
  // The fine atlas may find a field point the coarse search did not: close the aperture until it holds too.
  for (int it = 0; it < 4 && given.blur.auto_f_number && o.f_number_for_limit > 0 && o.worst_rms > limit; ++it) {
    problem.camera.lens.f_number *= std::min(2.0, 1.02 * o.worst_rms / limit);
    o = AnalyseAt(p, problem, label);
  }
  o.f_number_auto = given.blur.auto_f_number;
  if (given.blur.max_rms_px)
    o.blur_constraint =
        ConstraintValue{"max_blur_px", o.worst_rms - *given.blur.max_rms_px, *given.blur.max_rms_px, "px"};
  return o;
}

FocusPrediction PredictFocus(const DesignPoint& p, const DesignProblem& problem) {
  FocusPrediction out;
  const Metrics m = Evaluate(p, problem);
  out.lower_deg = m.lower_deg, out.upper_deg = m.upper_deg;
  const optics::OpticalSystem sys = SystemOf(p, problem.camera, 256);
  const double min_focus = 1.5 * problem.camera.focal_length;
  const auto traced = optics::TraceFields(sys, optics::FieldGrid(m.lower_deg, m.upper_deg, kAtlasElevations,
                                                                 SceneDistances(problem.blur, kAtlasDistances)));
  out.best = optics::BestSingleFocus(sys, traced, min_focus);
  out.depth = optics::DepthOfFocusOf(sys, traced, out.best, problem.blur.limit_px, min_focus);
  return out;
}

nlohmann::json FocusPredictionJson(const FocusPrediction& f) {
  return {{"best_focus_m", f.best.focus_distance},
          {"worst_rms_px", f.best.worst_rms},
          {"depth_of_focus_m", {f.depth.near_focus, DistanceValue(f.depth.far_focus)}},
          {"tolerance_px", f.depth.tolerance_px},
          {"field_deg", {f.lower_deg, f.upper_deg}}};
}

std::string BlurCsvHeader(bool with_mirror) {
  return std::string(with_mirror ? "mirror," : "") +
         "a_mm,b_mm,elevation_deg,distance_m,focus_distance_m,f_number,rms_radius_px,radial_rms_px,tangential_rms_px,"
         "ee80_px,mtf_nyquist_radial,mtf_nyquist_tangential,mtf50_radial,mtf50_tangential,centroid_u,centroid_v,"
         "rays,lost\n";
}

std::string BlurCsvRows(const DesignOptics& o, const std::string& mirror) {
  std::ostringstream csv;
  for (const optics::FieldBlur& b : o.atlas) {
    if (!mirror.empty()) csv << mirror << ',';
    csv << FormatNumber("%.6g", o.p.a * 1e3) << ',' << FormatNumber("%.6g", o.p.b * 1e3) << ','
        << FormatNumber("%.6f", b.field.elevation_deg) << ',' << DistanceCsv(b.field.distance) << ','
        << FormatNumber("%.6f", o.focus) << ',' << FormatNumber("%.4g", o.lens.f_number) << ',';
    if (b.spot.Valid()) {
      csv << FormatNumber("%.5f", b.spot.rms) << ',' << FormatNumber("%.5f", b.spot.radial_rms) << ','
          << FormatNumber("%.5f", b.spot.tangential_rms) << ',' << FormatNumber("%.5f", b.spot.ee80) << ','
          << FormatNumber("%.5f", b.mtf_nyquist_radial) << ',' << FormatNumber("%.5f", b.mtf_nyquist_tangential) << ','
          << FormatNumber("%.5f", b.mtf50_radial) << ',' << FormatNumber("%.5f", b.mtf50_tangential) << ','
          << FormatNumber("%.4f", b.spot.centroid.x()) << ',' << FormatNumber("%.4f", b.spot.centroid.y());
    } else {
      csv << "nan,nan,nan,nan,nan,nan,nan,nan,nan,nan";  // no ray of the bundle reached the lens
    }
    csv << ',' << b.rays << ',' << b.lost << '\n';
  }
  return csv.str();
}

nlohmann::json OpticsJson(const DesignOptics& o) {
  nlohmann::json j;
  j["design"] = o.label;
  j["a"] = o.p.a, j["b"] = o.p.b, j["d"] = o.p.d;
  j["f_number"] = o.lens.f_number;
  j["focus_distance"] = o.focus;
  j["focus_given"] = o.focus_given;
  j["best_single_focus"] = {
      {"focus_distance", o.best.focus_distance},
      {"sensor_distance", o.lens.SensorDistanceAt(o.best.focus_distance)},
      {"worst_rms_px", o.best.worst_rms},
      {"rim_radius_px", o.at_best.rim_radius_px},
      {"feasible", MaxViolation(o.constraints_at_best) <= 0},
      {"depth_of_focus", {o.depth_of_focus.near_focus, DistanceValue(o.depth_of_focus.far_focus)}},
      {"depth_of_focus_tolerance_px", o.depth_of_focus.tolerance_px}};
  if (o.best.worst_field < o.atlas.size()) {
    const auto& f = o.atlas[o.best.worst_field].field;
    j["best_single_focus"]["worst_at"] = {{"elevation_deg", f.elevation_deg}, {"distance", DistanceValue(f.distance)}};
  }
  nlohmann::json c = nlohmann::json::array();
  for (const auto& g : o.constraints_at_best) c.push_back({{"name", g.name}, {"value", g.value}, {"unit", g.unit}});
  j["best_single_focus"]["constraints"] = c;
  j["worst_rms_px"] = o.worst_rms;
  j["rim_radius_px_at_focus_in_force"] = o.metrics.rim_radius_px;
  nlohmann::json dof = nlohmann::json::array();
  for (const auto& d : o.dof)
    dof.push_back({{"elevation_deg", d.elevation_deg},
                   {"sharp", d.sharp},
                   {"near", d.sharp ? nlohmann::json(d.near) : nlohmann::json(nullptr)},
                   {"far", d.sharp ? DistanceValue(d.far) : nlohmann::json(nullptr)}});
  j["depth_of_field"] = dof;
  nlohmann::json trade = nlohmann::json::array();
  for (const auto& t : o.trade)
    trade.push_back({{"f_number", t.f_number},
                     {"best_focus", t.best_focus},
                     {"worst_rms_px", t.worst_rms},
                     {"airy_radius_px", t.airy_radius_px}});
  j["f_number_trade"] = trade;
  j["f_number_for_limit"] = o.f_number_for_limit > 0 ? nlohmann::json(o.f_number_for_limit) : nlohmann::json(nullptr);
  j["f_number_chosen_by_design"] = o.f_number_auto;
  if (o.blur_constraint)
    j["max_blur_px"] = {
        {"limit_px", o.blur_constraint->limit}, {"worst_rms_px", o.worst_rms}, {"met", o.blur_constraint->value <= 0}};
  return j;
}

namespace {

// The blur atlas: RMS radius over log distance x elevation, the blur limit's contour.
std::string AtlasFigure(const DesignOptics& o, const DesignProblem& problem, const std::filesystem::path& fig,
                        const std::string& prefix) {
  const size_t nd = o.distances.size(), ne = o.elevations.size();
  // Blur atlas: log10 distance across (the last column, +inf, drawn one step past the last finite one).
  results::HeatMapFigure f;
  f.title = "RMS blur radius (px) at focus " + FormatNumber("%.4f", o.focus) + " m, f/" +
            FormatNumber("%.3g", o.lens.f_number) + "; contour: the " + FormatNumber("%.3g", problem.blur.limit_px) +
            " px limit (depth of field)";
  f.x_label = "log10 scene distance from F1 (m); last column: infinity";
  f.y_label = "elevation (deg)";
  f.value_label = "RMS radius (px)";
  f.nx = static_cast<int>(nd), f.ny = static_cast<int>(ne);
  const double x0 = std::log10(o.distances.front());
  const double step = nd > 2 ? (std::log10(o.distances[nd - 2]) - x0) / (nd - 2) : 1.0;
  f.x0 = x0, f.x1 = x0 + step * (nd - 1);
  f.y0 = o.elevations.front(), f.y1 = o.elevations.back();
  f.values.resize(nd * ne);
  for (size_t i = 0; i < ne; ++i)
    for (size_t k = 0; k < nd; ++k) {
      const auto& b = o.atlas[i * nd + k];
      f.values[i * nd + k] = b.spot.Valid() ? b.spot.rms : 0.0;
    }
  const double hi = *std::max_element(f.values.begin(), f.values.end());
  for (double l : {0.5, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0})
    if (l <= hi) f.contour_levels.push_back(l);
  f.contour_format = "%.1f";
  f.overlays.push_back({f.values, problem.blur.limit_px, "blur limit", {1, 1, 1}, 3.0});
  const std::string name = (prefix + "blur_atlas.png");
  results::WritePng(f, fig / name);
  return name;
}

// Spot diagrams on the 5 x 3 grid (radial across, tangential up), each scaled to its cell.
std::string SpotFigure(const DesignOptics& o, const DesignProblem& /*problem*/, const std::filesystem::path& fig,
                       const std::string& prefix) {
  // Spot diagrams: each spot drawn about its grid position (column: distance, row: elevation), scaled to fit.
  double extent = 1e-9;
  for (const auto& s : o.spots)
    for (const Vec2d& q : s.spot.points) extent = std::max(extent, (q - s.spot.centroid).cwiseAbs().maxCoeff());
  const double scale = 0.45 / extent;
  results::LineFigure f;
  f.title = "Spot diagrams at focus " + FormatNumber("%.4f", o.focus) + " m (each cell +-" +
            FormatNumber("%.3g", extent) + " px)";
  f.x_label = "scene distance (column: near, middle, far)";
  f.y_label = "elevation (row, deg)";
  const std::array<std::array<double, 3>, 3> colours = {{{0.8, 0.1, 0.1}, {0.1, 0.5, 0.1}, {0.1, 0.2, 0.8}}};
  for (size_t j = 0; j < o.spot_distances.size(); ++j) {
    results::Series s;
    s.name = "distance " + Distance(o.spot_distances[j]) + " m";
    s.rgb = colours[j % 3], s.points = true, s.marker_size = 3;
    for (size_t i = 0; i < o.spot_elevations.size(); ++i) {
      const auto& b = o.spots[i * o.spot_distances.size() + j].spot;
      for (const Vec2d& q : b.points) {
        const Vec2d d = q - b.centroid;
        // Radial along x, tangential along y.
        const Vec2d rt(d.dot(b.radial_dir), d.dot(Vec2d(-b.radial_dir.y(), b.radial_dir.x())));
        s.x.push_back(double(j) + scale * rt.x());
        s.y.push_back(o.spot_elevations[i] +
                      scale * rt.y() *
                          (o.spot_elevations.size() > 1 ? (o.spot_elevations[1] - o.spot_elevations[0]) : 1.0));
      }
    }
    f.series.push_back(s);
  }
  const std::string name = (prefix + "spot_diagrams.png");
  results::WritePng(f, fig / name);
  return name;
}

// The series of spot elevation i: radial as a line, tangential as points (not in the legend), coloured from blue
// (lowest elevation) to red.
std::pair<results::Series, results::Series> ElevationSeries(const DesignOptics& o, size_t i) {
  const size_t n = o.spot_elevations.size();
  const double t = n > 1 ? double(i) / (n - 1) : 0.0;
  results::Series r;
  r.name = "elevation " + FormatNumber("%.1f", o.spot_elevations[i]) + " deg";
  r.rgb = {0.9 * t, 0.2, 0.9 * (1 - t)};
  results::Series g = r;
  g.name += " tangential", g.points = true, g.in_legend = false;
  return {r, g};
}

// Through-focus curves at the farthest distance.
std::string ThroughFocusFigure(const DesignOptics& o, const DesignProblem& /*problem*/,
                               const std::filesystem::path& fig, const std::string& prefix) {
  results::LineFigure f;
  f.title = "Through focus at the farthest scene distance (solid: radial RMS, points: tangential RMS)";
  f.x_label = "focus distance from the lens (m)";
  f.y_label = "RMS size (px)";
  for (size_t i = 0; i < o.through_focus.size(); ++i) {
    auto [r, g] = ElevationSeries(o, i);
    for (const auto& s : o.through_focus[i]) {
      r.x.push_back(s.focus_distance), r.y.push_back(s.radial_rms);
      g.x.push_back(s.focus_distance), g.y.push_back(s.tangential_rms);
    }
    f.series.push_back(r), f.series.push_back(g);
  }
  const std::string name = (prefix + "through_focus.png");
  results::WritePng(f, fig / name);
  return name;
}

// MTF curves (geometric x diffraction) at the farthest distance.
std::string MtfFigure(const DesignOptics& o, const DesignProblem& problem, const std::filesystem::path& fig,
                      const std::string& prefix) {
  results::LineFigure f;
  f.title = "MTF (geometric x diffraction) at the farthest distance (solid: radial, points: tangential)";
  f.x_label = "spatial frequency (cycles / px)";
  f.y_label = "MTF";
  const optics::OpticalSystem sys = SystemOf(o.p, problem.camera, 256);
  const double nw = sys.lens.WorkingFNumberAt(o.focus);
  for (size_t i = 0; i < o.spot_elevations.size(); ++i) {
    const auto& b = o.spots[i * o.spot_distances.size() + o.spot_distances.size() - 1].spot;
    auto [r, g] = ElevationSeries(o, i);
    const Vec2d tan(-b.radial_dir.y(), b.radial_dir.x());
    for (int k = 0; k <= 50; ++k) {
      const double nu = k / 50.0;
      const double diff = optics::DiffractionMtf(nu, sys.pixel_pitch, sys.lens.wavelength, nw);
      r.x.push_back(nu), r.y.push_back(optics::GeometricMtf(b, b.radial_dir, nu) * diff);
      g.x.push_back(nu), g.y.push_back(optics::GeometricMtf(b, tan, nu) * diff);
    }
    f.series.push_back(r), f.series.push_back(g);
  }
  const std::string name = (prefix + "mtf.png");
  results::WritePng(f, fig / name);
  return name;
}

// Worst blur at the best single focus against f-number.
std::string TradeFigure(const DesignOptics& o, const DesignProblem& problem, const std::filesystem::path& fig,
                        const std::string& prefix) {
  results::LineFigure f;
  f.title = "Worst RMS blur over the field at the best single focus, against f-number";
  f.x_label = "f-number";
  f.y_label = "px";
  results::Series w, a, limit;
  w.name = "worst geometric RMS radius", w.rgb = {0.8, 0.1, 0.1};
  a.name = "Airy radius (diffraction)", a.rgb = {0.1, 0.2, 0.8};
  limit.name = "blur limit", limit.rgb = {0.3, 0.3, 0.3}, limit.line_width = 1;
  for (const auto& t : o.trade) {
    w.x.push_back(t.f_number), w.y.push_back(t.worst_rms);
    a.x.push_back(t.f_number), a.y.push_back(t.airy_radius_px);
    limit.x.push_back(t.f_number), limit.y.push_back(problem.blur.limit_px);
  }
  f.series = {w, a, limit};
  const std::string name = (prefix + "f_number_trade.png");
  results::WritePng(f, fig / name);
  return name;
}

}  // namespace

std::vector<std::string> WriteOpticsFigures(const DesignOptics& o, const DesignProblem& problem,
                                            const std::filesystem::path& dir, const std::string& prefix) {
  const std::filesystem::path fig = dir / "figures";
  std::filesystem::create_directories(fig);
  std::vector<std::string> names;
  for (const auto& figure : {AtlasFigure, SpotFigure, ThroughFocusFigure, MtfFigure, TradeFigure})
    names.push_back(figure(o, problem, fig, prefix));
  return names;
}

std::string OpticsSummary(const DesignOptics& o, const DesignProblem& problem) {
  std::ostringstream s;
  const std::string range = "scene distances " + Distance(problem.blur.near) + " m to " + Distance(problem.blur.far) +
                            (std::isinf(problem.blur.far) ? "" : " m");
  s << "  optics (" << o.label << ", f/" << FormatNumber("%.3g", o.lens.f_number) << "): best single focus "
    << FormatNumber("%.4f", o.best.focus_distance)
    << " m (s = " << FormatNumber("%.3f", o.lens.SensorDistanceAt(o.best.focus_distance) * 1e3)
    << " mm), worst RMS blur " << FormatNumber("%.2f", o.best.worst_rms) << " px over the field for " << range << "\n";
  s << "    depth of focus (worst RMS within " << FormatNumber("%.3g", o.depth_of_focus.tolerance_px)
    << " px of the best): focus " << FormatNumber("%.4f", o.depth_of_focus.near_focus) << " to "
    << Distance(o.depth_of_focus.far_focus) << " m\n";
  const bool ok = MaxViolation(o.constraints_at_best) <= 0;
  s << "    at that focus the rim is at " << FormatNumber("%.1f", o.at_best.rim_radius_px) << " px (limit "
    << FormatNumber("%.1f", problem.RimLimitPx()) << " px): " << (ok ? "every constraint holds" : "INFEASIBLE");
  for (const auto& g : o.constraints_at_best)
    if (g.value > 0) s << " [" << g.name << " by " << FormatNumber("%.1f", g.value) << " " << g.unit << "]";
  if (o.f_number_auto)
    s << "\n    f-number chosen by the design (lens.f_number: auto): f/" << FormatNumber("%.3g", o.lens.f_number)
      << (o.f_number_for_limit > 0 ? "" : " (NOT MET: no f-number up to f/256 meets the blur limit)");
  if (o.blur_constraint)
    s << "\n    constraint max_blur_px: worst RMS blur " << FormatNumber("%.2f", o.worst_rms) << " px at focus "
      << FormatNumber("%.4f", o.focus) << " m against " << FormatNumber("%.3g", o.blur_constraint->limit)
      << " px: " << (o.blur_constraint->value <= 0 ? "met" : "NOT MET");
  s << "\n    f-number for a worst RMS blur <= " << FormatNumber("%.3g", problem.blur.FNumberLimitPx()) << " px: ";
  if (o.f_number_for_limit > 0) {
    ThinLens at = o.lens;
    at.f_number = o.f_number_for_limit;
    const double airy = 1.22 * at.wavelength * at.WorkingFNumberAt(o.best.focus_distance) / problem.camera.pixel_pitch;
    s << "f/" << FormatNumber("%.1f", o.f_number_for_limit) << " (geometric; its Airy radius is "
      << FormatNumber("%.1f", airy) << " px)\n";
  } else {
    s << "none up to f/256\n";
  }
  return s.str();
}

void AppendOpticsSection(results::HtmlPage* page, const DesignOptics& o, const DesignProblem& problem,
                         const std::vector<std::string>& figures) {
  page->Heading("Optics: focus, blur, depth of field (" + o.label + ")");
  std::string text = OpticsSummary(o, problem);
  page->Preformatted(text);
  page->Paragraph(
      "Every spot is traced exactly: from the scene point via the mirror (law of reflection solved per pupil "
      "point, 256 points uniform by area) through the thin lens to the sensor; the image scale is s / pitch for "
      "the focus in force. Blur figures at focus " +
      FormatNumber("%.4f", o.focus) + " m (" +
      (o.focus_given ? "the config's lens.focus_distance" : "the best single focus; the config focuses at infinity") +
      "). Radial and tangential: along and across the direction from the image centre.");
  std::vector<std::vector<std::string>> rows;
  for (const auto& d : o.dof)
    rows.push_back({FormatNumber("%.2f", d.elevation_deg), d.sharp ? FormatNumber("%.4g", d.near) : "not sharp",
                    d.sharp ? Distance(d.far) : "-"});
  page->Heading("Depth of field per elevation (RMS radius <= " + FormatNumber("%.3g", problem.blur.limit_px) + " px)",
                3);
  page->Table({"elevation (deg)", "near limit (m from F1)", "far limit (m)"}, rows);
  std::vector<std::vector<std::string>> trade;
  for (const auto& t : o.trade)
    trade.push_back({FormatNumber("%.3g", t.f_number), FormatNumber("%.4f", t.best_focus),
                     FormatNumber("%.2f", t.worst_rms), FormatNumber("%.2f", t.airy_radius_px),
                     FormatNumber("%.4f", 1.0 / (t.f_number * t.f_number))});
  page->Heading("Worst blur at the best single focus against f-number", 3);
  page->Table({"f-number", "best focus (m)", "worst RMS (px)", "Airy radius (px)", "relative irradiance (1/N^2)"},
              trade);
  for (const auto& f : figures) page->Figure("figures/" + f, f, 640);
}

}  // namespace hovs::design
