#include "design/family.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "design/study.h"
#include "results/html.h"
#include "results/plot.h"

namespace hovs::design {
namespace {

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Distinct colours for up to 16 members.
std::array<double, 3> Colour(size_t i) {
  static const std::array<double, 3> kColours[] = {{0.10, 0.10, 0.10}, {0.85, 0.15, 0.10}, {0.10, 0.45, 0.85},
                                                   {0.15, 0.65, 0.20}, {0.80, 0.50, 0.00}, {0.55, 0.25, 0.70}};
  return kColours[i % (sizeof kColours / sizeof kColours[0])];
}

std::string Mm(double metres, const char* format = "%.2f") { return FormatNumber(format, metres * 1e3); }

std::vector<std::string> TableRow(const FamilyMirror& f) {
  const Metrics& m = f.Chosen().metrics;
  return {f.member.name,
          ToString(f.member.objective),
          Mm(m.p.a),
          Mm(m.p.b),
          Mm(m.p.d, "%.1f"),
          Mm(m.system_length),
          FormatNumber("%.2f", m.upper_deg),
          FormatNumber("%.2f", m.lower_deg),
          FormatNumber("%.2f", m.field_deg),
          FormatNumber("%.1f", m.rim_radius_px),
          FormatNumber("%.2f", m.upper_px_per_deg),
          m.long_range_px_per_deg > 0 ? FormatNumber("%.2f", m.long_range_px_per_deg) : "outside",
          FormatNumber("%.3f", m.near_ground_mpx),
          FormatNumber("%.3f", m.ground_radius_inner),
          std::isfinite(m.ground_radius_outer) ? FormatNumber("%.2f", m.ground_radius_outer) : "infinite",
          Mm(m.plate_height)};
}

const std::vector<std::string> kTableHeader = {"mirror",
                                               "objective",
                                               "a (mm)",
                                               "b (mm)",
                                               "d (mm)",
                                               "2c (mm)",
                                               "upper (deg)",
                                               "lower (deg)",
                                               "field (deg)",
                                               "rim (px)",
                                               "top px/deg",
                                               "long-range px/deg",
                                               "near ground (Mpx)",
                                               "ground from (m)",
                                               "ground to (m)",
                                               "plate height (mm)"};

void WriteFamilyFigures(const DesignConfig& cfg, const MirrorFamily& family, const std::filesystem::path& figures) {
  std::filesystem::create_directories(figures);
  {
    results::LineFigure f;
    f.title = "Radial resolution of the turret's mirrors over their vertical fields";
    f.x_label = "elevation (deg)";
    f.y_label = "pixels per degree of elevation";
    for (size_t i = 0; i < family.mirrors.size(); ++i) {
      const FamilyMirror& m = family.mirrors[i];
      results::Series s;
      s.name =
          m.member.name + " (" + Mm(m.Chosen().metrics.p.a, "%.1f") + " / " + Mm(m.Chosen().metrics.p.b, "%.1f") + ")";
      s.rgb = Colour(i);
      for (const auto& p : m.resolution) s.x.push_back(p.elevation_deg), s.y.push_back(p.px_per_deg);
      f.series.push_back(s);
    }
    results::WritePng(f, figures / "family_resolution.png");
  }
  {
    results::LineFigure f;
    f.title = "Rod positions: plate height above the pinhole, per mirror";
    f.x_label = "mirror (order of the family list)";
    f.y_label = "plate height (mm)";
    const double n = static_cast<double>(family.mirrors.size());
    if (cfg.problem.constraints.rod_travel) {
      const Range& t = *cfg.problem.constraints.rod_travel;
      for (const auto& [v, name] :
           {std::pair<double, const char*>{t.min, "rod travel minimum"}, {t.max, "rod travel maximum"}})
        f.series.push_back({name, {0.5, n + 0.5}, {v * 1e3, v * 1e3}, {0.6, 0.6, 0.6}, 1.5, false, 4.0});
    }
    for (size_t i = 0; i < family.mirrors.size(); ++i) {
      results::Series s;
      s.name = family.mirrors[i].member.name;
      s.rgb = Colour(i);
      s.points = true;
      s.marker_size = 9;
      s.x = {static_cast<double>(i + 1)};
      s.y = {family.mirrors[i].Chosen().metrics.plate_height * 1e3};
      f.series.push_back(s);
    }
    results::WritePng(f, figures / "rod_positions.png");
  }
}

}  // namespace

MirrorFamily RunFamilyStudy(const DesignConfig& cfg) {
  HOVS_REQUIRE(!cfg.family.empty(), cfg.source, "no 'family' list: nothing to design");
  MirrorFamily out;
  for (const FamilyMember& member : cfg.family) {
    FamilyMirror f;
    f.member = member;
    f.problem = cfg.problem;
    f.problem.objective = member.objective;
    const auto t = Clock::now();
    try {
      const SweepResult sweep = Sweep(f.problem, cfg.sweep);
      f.continuous = OptimizeContinuous(f.problem, sweep);
      if (cfg.integer_mm) f.integer_mm = OptimizeIntegerMillimetre(f.problem);
    } catch (const Error& e) {
      throw Error(cfg.source + " (family mirror '" + member.name + "', objective " + ToString(member.objective) + ")",
                  e.what());
    }
    out.seconds[member.name] = Since(t);
    f.resolution = RadialResolution(f.Chosen().metrics.p, cfg.problem.camera, cfg.resolution_samples);
    f.optics = AnalyseOptics(f.Chosen().metrics.p, f.problem, member.name);
    out.mirrors.push_back(std::move(f));
  }
  for (size_t i = 0; i < out.mirrors.size(); ++i)
    for (size_t j = i + 1; j < out.mirrors.size(); ++j) {
      const DesignPoint &p = out.mirrors[i].Chosen().metrics.p, &q = out.mirrors[j].Chosen().metrics.p;
      if (std::abs(p.a - q.a) < 1e-4 && std::abs(p.b - q.b) < 1e-4 && std::abs(p.d - q.d) < 1e-4)
        out.coincident.push_back({out.mirrors[i].member.name, out.mirrors[j].member.name});
    }
  return out;
}

nlohmann::json FamilyJson(const DesignConfig& cfg, const MirrorFamily& family) {
  nlohmann::json j;
  j["tool"] = "hovs design (turret family)";
  j["config"] = ProblemJson(cfg);
  j["config"].erase("objective");
  j["config_text"] = cfg.text;
  nlohmann::json mirrors = nlohmann::json::array();
  for (const FamilyMirror& f : family.mirrors) {
    nlohmann::json m;
    m["name"] = f.member.name;
    m["objective"] = ToString(f.member.objective);
    m["objective_label"] = ObjectiveLabel(f.member.objective);
    m["purpose"] = f.member.purpose;
    m["chosen"] = f.integer_mm ? "integer_mm_optimum" : "continuous_optimum";
    m["design"] = OptimumJson(f.Chosen());
    m["objective_value"] = ObjectiveDisplay(f.member.objective, f.Chosen().objective);
    m["continuous_optimum"] = OptimumJson(f.continuous);
    m["continuous_optimum"]["solver_log"] = f.continuous.solver_log;
    m["continuous_objective_value"] = ObjectiveDisplay(f.member.objective, f.continuous.objective);
    m["integer_mm_optimum"] = f.integer_mm ? OptimumJson(*f.integer_mm) : nlohmann::json(nullptr);
    m["rod_position"] = f.Chosen().metrics.plate_height;
    m["rod_offset_from_first"] = f.Chosen().metrics.plate_height - family.mirrors.front().Chosen().metrics.plate_height;
    if (f.optics) m["optics"] = OpticsJson(*f.optics);
    mirrors.push_back(m);
  }
  j["mirrors"] = mirrors;
  nlohmann::json coincident = nlohmann::json::array();
  for (const auto& [x, y] : family.coincident) coincident.push_back({x, y});
  j["coincident"] = coincident;
  j["seconds"] = family.seconds;
  return j;
}

std::string WriteFamilyReport(const DesignConfig& cfg, const MirrorFamily& family,
                              const std::filesystem::path& out_dir) {
  StagedDirectory stage(out_dir, "design", {cfg.source});
  const auto& dir = stage.staging();
  const auto versions = DesignVersions();
  WriteFileAtomic(dir / "config.yaml", cfg.text);

  nlohmann::json j = FamilyJson(cfg, family);
  j["versions"] = versions;
  WriteFileAtomic(dir / "family.json", j.dump(2) + "\n");

  std::vector<std::vector<std::string>> rows;
  for (const FamilyMirror& f : family.mirrors) rows.push_back(TableRow(f));
  {
    std::ostringstream csv;
    for (size_t i = 0; i < kTableHeader.size(); ++i) csv << (i ? "," : "") << kTableHeader[i];
    csv << "\n";
    for (const auto& r : rows) {
      for (size_t i = 0; i < r.size(); ++i) csv << (i ? "," : "") << r[i];
      csv << "\n";
    }
    WriteFileAtomic(dir / "family.csv", csv.str());
  }
  {
    std::ostringstream csv;
    csv << "mirror,elevation_deg,rho_px,px_per_deg\n";
    for (const FamilyMirror& f : family.mirrors)
      for (const auto& x : f.resolution)
        csv << f.member.name << ',' << FormatNumber("%.6f", x.elevation_deg) << ',' << FormatNumber("%.4f", x.rho_px)
            << ',' << FormatNumber("%.5f", x.px_per_deg) << '\n';
    WriteFileAtomic(dir / "radial_resolution.csv", csv.str());
  }

  WriteFamilyFigures(cfg, family, dir / "figures");
  {
    std::string csv = BlurCsvHeader(/*with_mirror=*/true);
    for (const FamilyMirror& f : family.mirrors)
      if (f.optics) csv += BlurCsvRows(*f.optics, f.member.name);
    WriteFileAtomic(dir / "blur.csv", csv);
  }

  std::ostringstream sum;
  sum << "hovs design: turret family " << cfg.name << " (" << family.mirrors.size() << " mirrors)\n";
  for (const FamilyMirror& f : family.mirrors) {
    const Metrics& m = f.Chosen().metrics;
    sum << "  " << f.member.name << std::string(f.member.name.size() < 14 ? 14 - f.member.name.size() : 0, ' ')
        << " a = " << Mm(m.p.a) << " mm, b = " << Mm(m.p.b) << " mm, 2c = " << Mm(m.system_length) << " mm, field "
        << FormatNumber("%.2f", m.lower_deg) << " .. " << FormatNumber("%.2f", m.upper_deg) << " deg, rod "
        << Mm(m.plate_height) << " mm; " << ObjectiveLabel(f.member.objective) << " "
        << FormatNumber("%.4g", ObjectiveDisplay(f.member.objective, f.Chosen().objective))
        << (f.Chosen().max_violation <= 0 ? "" : "  [INFEASIBLE]") << "\n";
  }
  for (const FamilyMirror& f : family.mirrors)
    if (f.optics) sum << OpticsSummary(*f.optics, f.problem);
  for (const auto& [x, y] : family.coincident)
    sum << "  note: mirrors " << x << " and " << y << " coincide; the turret offers fewer scales\n";
  sum << "  report in " << out_dir.string() << "\n";
  WriteFileAtomic(dir / "summary.txt", sum.str());

  results::HtmlPage page("hovs design: turret family " + cfg.name);
  page.Paragraph(
      "The variable-scale unit's mirrors (the article's section 3.1, item 2): one mirror per objective for the "
      "same camera and lens, all under the same constraints (rim inside the image, upper bound of the field, "
      "camera reflection inside the rim) and within the push rod's travel. The mirror each row lists is the "
      "integer-millimetre optimum of its objective when the search asks for one, else the continuous optimum.");
  page.Heading("Mirrors");
  page.Table(kTableHeader, rows);
  std::vector<std::vector<std::string>> purpose;
  for (const FamilyMirror& f : family.mirrors)
    purpose.push_back({f.member.name, ToString(f.member.objective), f.member.purpose,
                       FormatNumber("%.6g", ObjectiveDisplay(f.member.objective, f.continuous.objective)),
                       FormatNumber("%.6g", ObjectiveDisplay(f.member.objective, f.Chosen().objective)),
                       ObjectiveLabel(f.member.objective)});
  page.Table({"mirror", "objective", "purpose", "continuous optimum", "chosen design", "unit"}, purpose);
  page.Heading("Figures");
  page.Figure("figures/family_resolution.png", "Radial resolution of every mirror over its vertical field", 640);
  page.Figure("figures/rod_positions.png", "Plate heights the rod must reach, with its travel", 540);
  page.Heading("Constraints of the chosen designs (g <= 0 is satisfied)", 3);
  std::vector<std::vector<std::string>> crow;
  for (const FamilyMirror& f : family.mirrors)
    for (const auto& c : f.Chosen().constraints)
      crow.push_back({f.member.name, c.name, FormatNumber("%.6g", c.value) + " " + c.unit,
                      FormatNumber("%.6g", c.limit) + " " + c.unit, c.value <= 0 ? "yes" : "NO"});
  page.Table({"mirror", "constraint", "g", "limit", "satisfied"}, crow);
  for (const FamilyMirror& f : family.mirrors)
    if (f.optics)
      AppendOpticsSection(&page, *f.optics, f.problem,
                          WriteOpticsFigures(*f.optics, f.problem, dir, f.member.name + "_"));
  page.Heading("Files");
  page.Paragraph(
      "family.json (every design, constraint and solver log, the config and versions), family.csv (the "
      "table), radial_resolution.csv, blur.csv (each mirror's blur atlas, a mirror column first), config.yaml, "
      "summary.txt.");
  AppendConfigAndVersions(&page, cfg.text, versions);
  WriteFileAtomic(dir / "index.html", page.Render());
  stage.Commit();
  return sum.str();
}

}  // namespace hovs::design
