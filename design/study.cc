#include "design/study.h"

#include <tbb/version.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <nlopt.hpp>
#include <sstream>

#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "results/html.h"
#include "results/plot.h"

namespace hovs::design {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

}  // namespace

nlohmann::json MetricsJson(const Metrics& m) {
  nlohmann::json j;
  j["a"] = m.p.a, j["b"] = m.p.b, j["d"] = m.p.d, j["c"] = m.c;
  j["system_length"] = m.system_length;
  j["rim_z"] = m.rim_z, j["vertex_z"] = m.vertex_z, j["sag"] = m.sag;
  j["upper_bound_deg"] = m.upper_deg, j["lower_bound_deg"] = m.lower_deg, j["vertical_field_deg"] = m.field_deg;
  j["rim_radius_px"] = m.rim_radius_px, j["camera_reflection_radius_px"] = m.reflection_radius_px;
  j["ground_radius_inner"] = m.ground_radius_inner;
  j["ground_radius_outer"] =
      std::isfinite(m.ground_radius_outer) ? nlohmann::json(m.ground_radius_outer) : nlohmann::json("infinite");
  j["plate_height"] = m.plate_height;
  j["upper_px_per_deg"] = m.upper_px_per_deg;
  j["long_range_px_per_deg"] = m.long_range_px_per_deg;
  j["near_ground_mpx"] = m.near_ground_mpx;
  return j;
}

nlohmann::json OptimumJson(const Optimum& o) {
  nlohmann::json j = MetricsJson(o.metrics);
  j["objective"] = o.objective;
  j["max_violation"] = o.max_violation;
  j["feasible"] = o.max_violation <= 0;
  j["method"] = o.method;
  j["evaluations"] = o.evaluations;
  nlohmann::json cs = nlohmann::json::array();
  for (const auto& c : o.constraints)
    cs.push_back(
        {{"name", c.name}, {"value", c.value}, {"limit", c.limit}, {"unit", c.unit}, {"satisfied", c.value <= 0}});
  j["constraints"] = cs;
  return j;
}

nlohmann::json ProblemJson(const DesignConfig& cfg) {
  const DesignProblem& p = cfg.problem;
  nlohmann::json j;
  j["name"] = cfg.name;
  j["source"] = cfg.source;
  j["camera"] = {{"focal_length", p.camera.focal_length},
                 {"pixel_pitch", p.camera.pixel_pitch},
                 {"width", p.camera.width},
                 {"height", p.camera.height},
                 {"lens_aperture", p.camera.lens_aperture}};
  const auto distance = [](double d) { return std::isinf(d) ? nlohmann::json("infinity") : nlohmann::json(d); };
  const ThinLens lens = p.camera.Lens();
  j["lens"] = {{"f_number", p.blur.auto_f_number ? nlohmann::json("auto") : nlohmann::json(lens.f_number)},
               {"aperture_diameter", lens.ApertureDiameter()},
               {"focus_distance", distance(lens.focus_distance)},
               {"sensor_distance", lens.SensorDistance()},
               {"wavelength", lens.wavelength},
               {"relative_irradiance", lens.RelativeIrradiance()}};
  j["blur"] = {{"limit_px", p.blur.limit_px}, {"scene_distance", {p.blur.near, distance(p.blur.far)}}};
  j["mounting_height"] = p.mounting_height;
  j["objective"] = ToString(p.objective);
  j["search"] = {{"a", {p.a.min, p.a.max}},
                 {"b", {p.b.min, p.b.max}},
                 {"d", {p.d.min, p.d.max}},
                 {"grid", {cfg.sweep.na, cfg.sweep.nb, cfg.sweep.nd}},
                 {"integer_mm", cfg.integer_mm}};
  nlohmann::json k = {{"max_upper_elevation_deg", p.constraints.max_upper_elevation_deg},
                      {"rim_margin_px", p.constraints.rim_margin_px},
                      {"rim_limit_px", p.RimLimitPx()}};
  if (p.constraints.min_vertical_field_deg) k["min_vertical_field_deg"] = *p.constraints.min_vertical_field_deg;
  if (p.constraints.min_rim_radius_px) k["min_rim_radius_px"] = *p.constraints.min_rim_radius_px;
  if (p.constraints.max_system_length) k["max_system_length"] = *p.constraints.max_system_length;
  if (p.blur.max_rms_px) k["max_blur_px"] = *p.blur.max_rms_px;
  if (p.constraints.rod_travel) k["rod_travel"] = {p.constraints.rod_travel->min, p.constraints.rod_travel->max};
  j["constraints"] = k;
  j["long_range_elevation_deg"] = p.long_range_elevation_deg;
  j["near_ground_radius"] = p.near_ground_radius;
  return j;
}

namespace {

// The (a, b) slice of the sweep at the d index nearest to d.
int SliceIndex(const SweepResult& s, double d) {
  if (s.spec.nd == 1) return 0;
  int best = 0;
  for (int i = 1; i < s.spec.nd; ++i)
    if (std::abs(s.D(i) - d) < std::abs(s.D(best) - d)) best = i;
  return best;
}

results::HeatMapFigure SliceFigure(const SweepResult& s, int id, const std::vector<double>& field,
                                   const std::string& title, const std::string& value_label) {
  results::HeatMapFigure f;
  f.title = title;
  f.x_label = "a (mm)";
  f.y_label = "b (mm)";
  f.value_label = value_label;
  f.nx = s.spec.na, f.ny = s.spec.nb;
  f.x0 = s.a.min * 1e3, f.x1 = s.a.max * 1e3, f.y0 = s.b.min * 1e3, f.y1 = s.b.max * 1e3;
  f.values.resize(static_cast<size_t>(f.nx) * f.ny);
  f.shade.resize(f.values.size());
  for (int ib = 0; ib < s.spec.nb; ++ib)
    for (int ia = 0; ia < s.spec.na; ++ia) {
      const size_t k = s.Index(ia, ib, id), o = static_cast<size_t>(ib) * f.nx + ia;
      f.values[o] = field[k];
      f.shade[o] = s.violated[k] != 0;
    }
  f.shade_label = "pale: infeasible";
  return f;
}

std::vector<double> Levels(double lo, double hi, double step) {
  std::vector<double> out;
  for (double v = std::ceil(lo / step) * step; v <= hi; v += step) out.push_back(v);
  return out;
}

void AddMarkers(results::HeatMapFigure* f, const DesignStudy& st) {
  f->markers.push_back(
      {st.continuous.metrics.p.a * 1e3, st.continuous.metrics.p.b * 1e3, "continuous optimum", {0.85, 0.1, 0.1}, 0});
  if (st.integer_mm)
    f->markers.push_back({st.integer_mm->metrics.p.a * 1e3,
                          st.integer_mm->metrics.p.b * 1e3,
                          "integer-mm optimum",
                          {1.0, 0.55, 0.0},
                          3});
  if (st.marked)
    f->markers.push_back(
        {st.marked->metrics.p.a * 1e3, st.marked->metrics.p.b * 1e3, "marked design", {0.0, 0.0, 0.0}, 1});
}

std::vector<std::string> MetricsRow(const std::string& label, const Optimum& o) {
  const Metrics& m = o.metrics;
  return {label,
          FormatNumber("%.4f", m.p.a * 1e3),
          FormatNumber("%.4f", m.p.b * 1e3),
          FormatNumber("%.2f", m.p.d * 1e3),
          FormatNumber("%.4f", m.system_length * 1e3),
          FormatNumber("%.4f", m.upper_deg),
          FormatNumber("%.3f", m.lower_deg),
          FormatNumber("%.3f", m.field_deg),
          FormatNumber("%.2f", m.rim_radius_px),
          FormatNumber("%.1f", m.reflection_radius_px),
          FormatNumber("%.3f", m.sag * 1e3),
          FormatNumber("%.3f", m.ground_radius_inner),
          std::isfinite(m.ground_radius_outer) ? FormatNumber("%.2f", m.ground_radius_outer) : "infinite",
          o.max_violation <= 0 ? "yes" : "NO"};
}

}  // namespace

void AppendConfigAndVersions(results::HtmlPage* page, const std::string& config_text,
                             const std::map<std::string, std::string>& versions) {
  page->Heading("Config");
  page->Preformatted(config_text);
  page->Heading("Versions");
  std::vector<std::vector<std::string>> rows;
  for (const auto& [k, v] : versions) rows.push_back({k, v});
  page->Table({"library", "version"}, rows);
}

double ObjectiveDisplay(Objective o, double value) { return o == Objective::kSmallestSystem ? value * 1e3 : -value; }

std::string ObjectiveLabel(Objective o) {
  switch (o) {
    case Objective::kSmallestSystem: return "2c (mm)";
    case Objective::kWidestField: return "field (deg)";
    case Objective::kLargestRim: return "rim (px)";
    case Objective::kLongRange: return "long-range resolution (px/deg)";
    case Objective::kNearGround: return "near-ground coverage (Mpx)";
  }
  return "objective";
}

std::map<std::string, std::string> DesignVersions() {
  auto v = results::ResultsVersions();
  int maj = 0, min = 0, bug = 0;
  nlopt::version(maj, min, bug);
  v["nlopt"] = std::to_string(maj) + "." + std::to_string(min) + "." + std::to_string(bug);
  v["tbb"] = TBB_VERSION_STRING;
  return v;
}

Optimum EvaluateDesign(const DesignPoint& p, const DesignProblem& problem, const std::string& method) {
  Optimum m;
  m.metrics = Evaluate(p, problem);
  m.constraints = EvaluateConstraints(m.metrics, problem);
  m.objective = ObjectiveValue(m.metrics, problem.objective);
  m.max_violation = MaxViolation(m.constraints);
  m.method = method;
  return m;
}

DesignStudy RunDesignStudy(const DesignConfig& cfg) {
  const auto t = Clock::now();
  SweepResult sweep = Sweep(cfg.problem, cfg.sweep);
  return RunDesignStudy(cfg, std::move(sweep), Since(t));
}

DesignStudy RunDesignStudy(const DesignConfig& cfg, SweepResult sweep, double sweep_seconds) {
  DesignStudy st;
  st.sweep = std::move(sweep);
  st.seconds["sweep"] = sweep_seconds;
  auto t = Clock::now();
  st.continuous = OptimizeContinuous(cfg.problem, st.sweep);
  st.seconds["continuous_optimum"] = Since(t);
  if (cfg.integer_mm) {
    t = Clock::now();
    st.integer_mm = OptimizeIntegerMillimetre(cfg.problem);
    st.seconds["integer_mm_optimum"] = Since(t);
  }
  if (cfg.marked) {
    st.marked = EvaluateDesign(*cfg.marked, cfg.problem, "given in the config");
    st.resolution_marked = RadialResolution(*cfg.marked, cfg.problem.camera, cfg.resolution_samples);
  }
  st.resolution_continuous = RadialResolution(st.continuous.metrics.p, cfg.problem.camera, cfg.resolution_samples);
  t = Clock::now();
  st.optics.push_back(st.integer_mm ? AnalyseOptics(st.integer_mm->metrics.p, cfg.problem, "integer_mm_optimum")
                                    : AnalyseOptics(st.continuous.metrics.p, cfg.problem, "continuous_optimum"));
  const DesignPoint& chosen = st.optics.front().p;
  if (cfg.marked && (std::abs(cfg.marked->a - chosen.a) > 1e-9 || std::abs(cfg.marked->b - chosen.b) > 1e-9 ||
                     std::abs(cfg.marked->d - chosen.d) > 1e-9))
    st.optics.push_back(AnalyseOptics(*cfg.marked, cfg.problem, "marked"));
  st.seconds["optics"] = Since(t);
  return st;
}

nlohmann::json DesignStudyJson(const DesignConfig& cfg, const DesignStudy& st) {
  const SweepResult& s = st.sweep;
  nlohmann::json j;
  j["tool"] = "hovs design";
  j["config"] = ProblemJson(cfg);
  j["config_text"] = cfg.text;
  j["continuous_optimum"] = OptimumJson(st.continuous);
  j["continuous_optimum"]["solver_log"] = st.continuous.solver_log;
  j["integer_mm_optimum"] = st.integer_mm ? OptimumJson(*st.integer_mm) : nlohmann::json(nullptr);
  j["marked_design"] = st.marked ? OptimumJson(*st.marked) : nlohmann::json(nullptr);
  size_t feasible = 0;
  for (uint32_t v : s.violated) feasible += v == 0;
  j["sweep"] = {{"points", s.size()}, {"feasible_points", feasible}, {"constraints", s.constraint_names}};
  if (auto b = s.BestFeasible()) j["sweep"]["best_feasible_objective"] = s.objective[*b];
  nlohmann::json optics = nlohmann::json::array();
  for (const DesignOptics& o : st.optics) optics.push_back(OpticsJson(o));
  j["optics"] = optics;
  j["seconds"] = st.seconds;
  return j;
}

std::string WriteDesignReport(const DesignConfig& cfg, const DesignStudy& st, const std::filesystem::path& out_dir) {
  StagedDirectory stage(out_dir, "design", {cfg.source});
  const auto& dir = stage.staging();
  const SweepResult& s = st.sweep;
  const auto versions = DesignVersions();

  WriteFileAtomic(dir / "config.yaml", cfg.text);

  // Sweep CSV.
  {
    std::ostringstream csv;
    csv << "# hovs design sweep; config " << cfg.source << "; lengths in metres, angles in degrees\n";
    csv << "a,b,d,system_length,upper_bound_deg,lower_bound_deg,vertical_field_deg,rim_radius_px,objective,feasible";
    for (const auto& n : s.constraint_names) csv << ",violates_" << n;
    csv << "\n";
    char buf[256];
    for (int id = 0; id < s.spec.nd; ++id)
      for (int ib = 0; ib < s.spec.nb; ++ib)
        for (int ia = 0; ia < s.spec.na; ++ia) {
          const size_t k = s.Index(ia, ib, id);
          std::snprintf(buf, sizeof buf, "%.7g,%.7g,%.7g,%.7g,%.6g,%.6g,%.6g,%.6g,%.8g,%d", s.A(ia), s.B(ib), s.D(id),
                        s.system_length[k], s.upper_deg[k], s.lower_deg[k], s.field_deg[k], s.rim_px[k], s.objective[k],
                        s.violated[k] == 0 ? 1 : 0);
          csv << buf;
          for (size_t c = 0; c < s.constraint_names.size(); ++c) csv << ',' << ((s.violated[k] >> c) & 1u);
          csv << '\n';
        }
    WriteFileAtomic(dir / "sweep.csv", csv.str());
  }
  // Radial resolution CSV.
  {
    std::ostringstream csv;
    csv << "design,elevation_deg,rho_px,px_per_deg\n";
    const auto put = [&](const char* name, const std::vector<ResolutionSample>& r) {
      for (const auto& x : r)
        csv << name << ',' << FormatNumber("%.6f", x.elevation_deg) << ',' << FormatNumber("%.4f", x.rho_px) << ','
            << FormatNumber("%.5f", x.px_per_deg) << '\n';
    };
    put("continuous_optimum", st.resolution_continuous);
    put("marked", st.resolution_marked);
    WriteFileAtomic(dir / "radial_resolution.csv", csv.str());
  }

  // Blur of the analysed designs.
  {
    std::string csv = BlurCsvHeader(/*with_mirror=*/true);
    for (const DesignOptics& o : st.optics) csv += BlurCsvRows(o, o.label);
    WriteFileAtomic(dir / "blur.csv", csv);
  }

  // Figures.
  std::filesystem::create_directories(dir / "figures");
  const int slice = SliceIndex(s, st.continuous.metrics.p.d);
  {
    auto f = SliceFigure(s, slice, s.field_deg, "Vertical field of view over (a, b)", "field (deg)");
    f.contour_levels = Levels(*std::min_element(s.field_deg.begin(), s.field_deg.end()),
                              *std::max_element(s.field_deg.begin(), s.field_deg.end()), 10.0);
    AddMarkers(&f, st);
    results::WritePng(f, dir / "figures" / "vertical_field.png");
  }
  {
    auto f = SliceFigure(s, slice, s.upper_deg, "Upper bound of the field (elevation of the rim ray)", "upper (deg)");
    f.contour_levels = Levels(-30, 30, 5.0);
    f.contour_format = "%+.0f";
    AddMarkers(&f, st);
    results::WritePng(f, dir / "figures" / "upper_bound.png");
  }
  {
    auto f = SliceFigure(s, slice, s.rim_px, "Rim radius in the image", "rim radius (px)");
    f.contour_levels = Levels(0, 3000, 100.0);
    f.contour_levels.push_back(cfg.problem.RimLimitPx());
    AddMarkers(&f, st);
    results::WritePng(f, dir / "figures" / "rim_radius.png");
  }
  {
    std::vector<double> mm(s.system_length.size());
    for (size_t i = 0; i < mm.size(); ++i) mm[i] = s.system_length[i] * 1e3;
    auto f = SliceFigure(s, slice, mm, "System length 2c (viewpoint to pinhole)", "2c (mm)");
    f.contour_levels = Levels(0, 400, 10.0);
    AddMarkers(&f, st);
    results::WritePng(f, dir / "figures" / "system_length.png");
  }
  {
    // The feasible region around the optimum, finely sampled, with the integer-millimetre designs.
    DesignProblem zoom = cfg.problem;
    const Metrics& o = st.continuous.metrics;
    zoom.a = {std::max(cfg.problem.a.min, o.p.a - 0.005), std::min(cfg.problem.a.max, o.p.a + 0.005)};
    zoom.b = {std::max(cfg.problem.b.min, o.p.b - 0.005), std::min(cfg.problem.b.max, o.p.b + 0.005)};
    zoom.d = {o.p.d, o.p.d};
    if (!zoom.a.Fixed() && !zoom.b.Fixed()) {
      const SweepResult z = Sweep(zoom, SweepSpec{161, 161, 1});
      std::vector<double> objective(z.size()), upper(z.size()), rim(z.size());
      for (size_t i = 0; i < z.size(); ++i) {
        objective[i] = ObjectiveDisplay(cfg.problem.objective, z.objective[i]);
        upper[i] = z.upper_deg[i];
        rim[i] = z.rim_px[i];
      }
      const std::string label = ObjectiveLabel(cfg.problem.objective);
      auto f = SliceFigure(z, 0, objective, "Feasible region near the optimum", label);
      const double lo = *std::min_element(objective.begin(), objective.end());
      const double hi = *std::max_element(objective.begin(), objective.end());
      f.contour_levels = Levels(lo, hi, (hi - lo) > 20 ? 2.0 : 1.0);
      f.overlays.push_back(
          {upper, cfg.problem.constraints.max_upper_elevation_deg, "upper bound limit", {0.9, 0.1, 0.1}, 3.0});
      f.overlays.push_back({rim, cfg.problem.RimLimitPx(), "rim radius limit", {1.0, 0.55, 0.0}, 3.0});
      results::PointSet ok{{}, {}, "feasible integer-mm design", {0, 0, 0}, 0, 5};
      results::PointSet bad{{}, {}, "infeasible integer-mm design", {0.45, 0.45, 0.45}, 1, 6};
      for (int a = static_cast<int>(std::ceil(zoom.a.min * 1e3)); a <= zoom.a.max * 1e3; ++a)
        for (int b = static_cast<int>(std::ceil(zoom.b.min * 1e3)); b <= zoom.b.max * 1e3; ++b) {
          const DesignPoint p{a * 1e-3, b * 1e-3, o.p.d};
          const bool feasible = MaxViolation(EvaluateConstraints(Evaluate(p, cfg.problem), cfg.problem)) <= 0;
          (feasible ? ok : bad).x.push_back(a);
          (feasible ? ok : bad).y.push_back(b);
        }
      f.point_sets = {ok, bad};
      AddMarkers(&f, st);
      results::WritePng(f, dir / "figures" / "feasible_region.png");
    }
  }
  {
    results::LineFigure f;
    f.title = "Radial resolution over the vertical field";
    f.x_label = "elevation (deg)";
    f.y_label = "pixels per degree of elevation";
    const auto series = [](const std::string& name, const std::vector<ResolutionSample>& r, std::array<double, 3> rgb) {
      results::Series x;
      x.name = name;
      x.rgb = rgb;
      for (const auto& p : r) x.x.push_back(p.elevation_deg), x.y.push_back(p.px_per_deg);
      return x;
    };
    f.series.push_back(series("continuous optimum", st.resolution_continuous, {0.85, 0.1, 0.1}));
    if (!st.resolution_marked.empty())
      f.series.push_back(series("marked design", st.resolution_marked, {0.1, 0.1, 0.1}));
    results::WritePng(f, dir / "figures" / "radial_resolution.png");
  }

  // JSON.
  nlohmann::json j = DesignStudyJson(cfg, st);
  j["versions"] = versions;
  WriteFileAtomic(dir / "design.json", j.dump(2) + "\n");

  // Summary and HTML.
  std::ostringstream sum;
  sum << "hovs design: " << cfg.name << " (objective " << ToString(cfg.problem.objective) << ")\n";
  const auto line = [&](const std::string& label, const Optimum& o) {
    sum << "  " << label << std::string(label.size() < 20 ? 20 - label.size() : 0, ' ')
        << " a = " << FormatNumber("%.4f", o.metrics.p.a * 1e3)
        << " mm, b = " << FormatNumber("%.4f", o.metrics.p.b * 1e3)
        << " mm, d = " << FormatNumber("%.1f", o.metrics.p.d * 1e3)
        << " mm, 2c = " << FormatNumber("%.3f", o.metrics.system_length * 1e3) << " mm, field "
        << FormatNumber("%.3f", o.metrics.lower_deg) << " .. " << FormatNumber("%.3f", o.metrics.upper_deg)
        << " deg, rim " << FormatNumber("%.1f", o.metrics.rim_radius_px) << " px"
        << (o.max_violation <= 0 ? "" : "  [INFEASIBLE]") << "\n";
  };
  line("continuous optimum", st.continuous);
  if (st.integer_mm)
    line("integer-mm optimum", *st.integer_mm);
  else if (cfg.integer_mm)
    sum << "  integer-mm optimum   none: no integer-millimetre design is feasible\n";
  if (st.marked) line("marked design", *st.marked);
  for (const DesignOptics& o : st.optics) sum << OpticsSummary(o, cfg.problem);
  sum << "  sweep: " << s.size() << " designs, " << j["sweep"]["feasible_points"].get<size_t>()
      << " feasible; report in " << out_dir.string() << "\n";
  WriteFileAtomic(dir / "summary.txt", sum.str());

  results::HtmlPage page("hovs design study: " + cfg.name);
  page.Paragraph(
      "Mirror design of a hyperboloid catadioptric unit with the camera pinhole at the second focus, after "
      "the article's section 3.1. Objective: " +
      std::string(ToString(cfg.problem.objective)) +
      ". Every quantity is computed by hovs' core mirror and camera models.");
  page.Heading("Designs");
  std::vector<std::vector<std::string>> rows = {MetricsRow("continuous optimum", st.continuous)};
  if (st.integer_mm) rows.push_back(MetricsRow("integer-mm optimum", *st.integer_mm));
  if (st.marked) rows.push_back(MetricsRow("marked design", *st.marked));
  page.Table({"design", "a (mm)", "b (mm)", "d (mm)", "2c (mm)", "upper (deg)", "lower (deg)", "field (deg)",
              "rim (px)", "camera reflection (px)", "sag (mm)", "ground from (m)", "ground to (m)", "feasible"},
             rows);
  page.Heading("Constraints (g <= 0 is satisfied)", 3);
  std::vector<std::vector<std::string>> crow;
  const auto add_c = [&](const std::string& label, const Optimum& o) {
    for (const auto& c : o.constraints)
      crow.push_back({label, c.name, FormatNumber("%.9g", c.value) + " " + c.unit,
                      FormatNumber("%.6g", c.limit) + " " + c.unit, c.value <= 0 ? "yes" : "NO"});
  };
  add_c("continuous optimum", st.continuous);
  if (st.integer_mm) add_c("integer-mm optimum", *st.integer_mm);
  if (st.marked) add_c("marked design", *st.marked);
  page.Table({"design", "constraint", "g", "limit", "satisfied"}, crow);
  page.Heading("Figures");
  page.Paragraph("Heat maps over (a, b) at d = " + FormatNumber("%.1f", s.D(slice) * 1e3) +
                 " mm; pale regions violate at least one constraint. Markers: red circle the continuous optimum, "
                 "orange square the integer-millimetre optimum, black cross the marked design.");
  page.Figure("figures/vertical_field.png", "Vertical field of view (the article's Fig. 3)", 540);
  page.Figure("figures/upper_bound.png", "Upper bound of the field; the 0 deg contour is the horizon constraint", 540);
  page.Figure("figures/rim_radius.png", "Rim radius in the image (the article's Fig. 4-5)", 540);
  page.Figure("figures/system_length.png", "System length 2c", 540);
  page.Figure(
      "figures/feasible_region.png",
      "Feasible region near the optimum: constraint boundaries, integer-millimetre designs (the article's Fig. 4)",
      540);
  page.Figure("figures/radial_resolution.png", "Radial resolution over the vertical field", 540);
  for (const DesignOptics& o : st.optics)
    AppendOpticsSection(&page, o, cfg.problem, WriteOpticsFigures(o, cfg.problem, dir, o.label + "_"));
  page.Heading("Solver log");
  std::string log;
  for (const auto& l : st.continuous.solver_log) log += l + "\n";
  page.Preformatted(log + "chosen: " + st.continuous.method);
  page.Heading("Files");
  page.Paragraph("design.json (every figure, the config and versions), sweep.csv (" + std::to_string(s.size()) +
                 " designs), radial_resolution.csv, blur.csv (the blur atlas of each analysed design: one row per "
                 "elevation and scene distance), config.yaml, summary.txt.");
  AppendConfigAndVersions(&page, cfg.text, versions);
  WriteFileAtomic(dir / "index.html", page.Render());

  stage.Commit();
  return sum.str();
}

}  // namespace hovs::design
