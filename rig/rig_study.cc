#include "rig/rig_study.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "calib/checkerboard_detector.h"
#include "calib/model_io.h"
#include "core/any_model.h"
#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "core/json.h"
#include "core/statistics.h"
#include "results/html.h"
#include "results/plot.h"
#include "unwrap/remap_table.h"

namespace hovs::rig {
namespace {

constexpr double kDeg = M_PI / 180.0;

nlohmann::json PoseJson(const MirrorPose& p) {
  return {{"offset_mm", {p.offset.x() * 1e3, p.offset.y() * 1e3, p.offset.z() * 1e3}},
          {"rotation_deg", {p.rotation.x() / kDeg, p.rotation.y() / kDeg, p.rotation.z() / kDeg}},
          {"lateral_mm", p.LateralM() * 1e3},
          {"tilt_deg", p.TiltRad() / kDeg},
          {"height_mm", p.offset.z() * 1e3}};
}

nlohmann::json AxesJson(const std::array<double, kAxisCount>& a) {
  nlohmann::json j;
  for (int i = 0; i < kAxisCount; ++i) j[AxisName(AxisAt(i))] = a[i];
  return j;
}

double Max(const std::vector<double>& v) { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }

std::array<double, 3> Colour(int i) {
  static const std::array<double, 3> kColours[] = {
      {0.10, 0.10, 0.10}, {0.85, 0.15, 0.10}, {0.10, 0.45, 0.85}, {0.15, 0.65, 0.20}, {0.80, 0.50, 0.00}};
  return kColours[i % 5];
}

}  // namespace

std::map<std::string, std::string> RigVersions() {
  auto v = raytrace::RaytraceVersions();
  for (const auto& m : {results::ResultsVersions(), calib::CalibVersions()}) v.insert(m.begin(), m.end());
  return v;
}

FaultSpec ParseFault(const std::string& text, const std::string& where) {
  FaultSpec f;
  const size_t colon = text.find(':');
  HOVS_REQUIRE(colon != std::string::npos, where, "expected AXIS:stuck, AXIS:lost=F or label:covered (got '", text,
               "')");
  f.axis = text.substr(0, colon);
  const std::string what = text.substr(colon + 1);
  if (f.axis == "label") {
    HOVS_REQUIRE(what == "covered", where, "the label's fault is 'label:covered' (got '", text, "')");
    f.label_covered = true;
    return f;
  }
  bool known = false;
  for (int i = 0; i < kAxisCount; ++i) known = known || f.axis == AxisName(AxisAt(i));
  HOVS_REQUIRE(known, where, "unknown axis '", f.axis, "' (turret, rod, x, y, tilt_x, tilt_y, focus, or label)");
  if (what == "stuck") {
    f.fault.stuck = true;
  } else if (what.rfind("lost=", 0) == 0) {
    char* end = nullptr;
    f.fault.lost_steps = std::strtod(what.c_str() + 5, &end);
    HOVS_REQUIRE(end && *end == 0 && f.fault.lost_steps > 0 && f.fault.lost_steps < 1, where,
                 "lost=F needs a fraction in (0, 1) (got '", text, "')");
  } else {
    throw Error(where, "unknown fault '" + what + "' (stuck or lost=F)");
  }
  return f;
}

void StartSpec::Check(const std::string& where) const {
  HOVS_REQUIRE(std::isfinite(lateral) && lateral >= 0 && lateral <= 0.004, where,
               "the start's lateral offset must be 0..4 mm");
  HOVS_REQUIRE(std::isfinite(tilt) && tilt >= 0 && tilt <= 2.5 * kDeg, where, "the start's tilt must be 0..2.5 deg");
  HOVS_REQUIRE(std::isfinite(height) && height >= 0 && height <= 0.01, where,
               "the start's height error must be 0..10 mm");
}

void AlignStudyOptions::Check(const std::string& where, const TurretSpec& spec) const {
  HOVS_REQUIRE(!mirrors.empty(), where, "no mirror to align");
  for (int k : mirrors) HOVS_REQUIRE(k >= 0 && k < static_cast<int>(spec.mirrors.size()), where, "no mirror ", k);
  HOVS_REQUIRE(starts >= 1 && starts <= 1000, where, "starts must be 1..1000");
  start.Check(where);
  align.Check(where);
  focus_options.Check(where);
}

std::vector<AlignRun> RunAlignStudy(const TurretSpec& spec, const AlignStudyOptions& o) {
  o.Check("align study", spec);
  for (int k : o.mirrors) RequireLabelPrecision(spec, k, o.align, spec.source);
  std::vector<AlignRun> runs;
  for (int k : o.mirrors)
    for (int i = 0; i < o.starts; ++i) {
      AlignRun run;
      run.mirror = k;
      run.seed = o.seed + static_cast<uint64_t>(i);
      const auto seats = DrawSeats(spec, run.seed * 31u + 17u);
      const double focus = spec.mirrors[k].PlateHeight();  // the label in focus while aligning
      const auto start =
          DisturbedStart(spec, k, seats[k], focus, o.start.lateral, o.start.tilt, o.start.height, run.seed);
      SimulatedUnit unit(spec, k, start, seats, run.seed);
      if (o.fault) {
        if (o.fault->label_covered) unit.CoverLabel(true);
        for (int a = 0; a < kAxisCount; ++a)
          if (o.fault->axis == AxisName(AxisAt(a))) unit.sim().sim(AxisAt(a)).SetFault(o.fault->fault);
      }
      run.start = *unit.Truth();
      run.result = Align(unit, spec, o.align);
      if (o.focus && run.result.converged) run.focus = FocusLens(unit, spec, o.focus_options);
      run.render_seconds = unit.render_seconds();
      run.machine_seconds = unit.machine().Now();
      runs.push_back(std::move(run));
    }
  return runs;
}

std::vector<AlignSummary> SummariseAlignStudy(const TurretSpec& spec, const std::vector<AlignRun>& runs) {
  std::vector<AlignSummary> out;
  for (size_t k = 0; k < spec.mirrors.size(); ++k) {
    std::vector<double> lat, tilt, height, its, focus;
    AlignSummary s;
    s.mirror = spec.mirrors[k].id;
    for (const auto& r : runs) {
      if (r.mirror != static_cast<int>(k)) continue;
      ++s.runs;
      s.converged += r.result.converged;
      const MirrorPose& t = *r.result.final_truth;
      lat.push_back(t.LateralM());
      tilt.push_back(t.TiltRad());
      height.push_back(std::abs(t.offset.z()));
      its.push_back(static_cast<double>(r.result.steps.size()));
      if (r.focus) {
        double best = 0;
        for (const auto& [f, sh] : r.focus->samples) best = std::max(best, sh);
        focus.push_back(r.focus->sharpness / best);
      }
    }
    if (s.runs == 0) continue;
    s.median_lateral = Median(lat), s.worst_lateral = Max(lat);
    s.median_tilt = Median(tilt), s.worst_tilt = Max(tilt);
    s.median_height = Median(height), s.worst_height = Max(height);
    s.median_iterations = Median(its), s.worst_iterations = Max(its);
    s.median_focus_ratio = Median(focus);
    out.push_back(s);
  }
  return out;
}

nlohmann::json AlignRunJson(const TurretSpec& spec, const AlignRun& run) {
  nlohmann::json j;
  j["mirror"] = spec.mirrors.at(run.mirror).id;
  j["seed"] = run.seed;
  j["start"] = PoseJson(run.start);
  j["converged"] = run.result.converged;
  j["failure"] = run.result.failure;
  j["failing"] = run.result.failing;
  j["final_truth"] = run.result.final_truth ? PoseJson(*run.result.final_truth) : nlohmann::json(nullptr);
  j["final_measured"] = run.result.final_measured ? PoseJson(*run.result.final_measured) : nlohmann::json(nullptr);
  nlohmann::json steps = nlohmann::json::array();
  for (const LoopStep& s : run.result.steps) {
    nlohmann::json x;
    x["iteration"] = s.iteration;
    x["time_s"] = s.time;
    x["truth"] = s.truth ? PoseJson(*s.truth) : nlohmann::json(nullptr);
    x["measured"] = s.measured ? PoseJson(*s.measured) : nlohmann::json(nullptr);
    x["markers"] = s.markers;
    x["label_rms_px"] = s.label_rms_px;
    x["label_sigma"] = {{"x_mm", 1e3 * s.label_sigma[0]},
                        {"y_mm", 1e3 * s.label_sigma[1]},
                        {"height_mm", 1e3 * s.label_sigma[2]},
                        {"tilt_x_deg", s.label_sigma[3] * 180 / M_PI},
                        {"tilt_y_deg", s.label_sigma[4] * 180 / M_PI}};
    x["reported"] = AxesJson(s.reported);
    x["command"] = AxesJson(s.command);
    if (!s.note.empty()) x["note"] = s.note;
    steps.push_back(x);
  }
  j["steps"] = steps;
  if (run.focus) {
    nlohmann::json f;
    f["focus_m"] = run.focus->focus;
    f["sharpness"] = run.focus->sharpness;
    f["images"] = run.focus->images;
    nlohmann::json samples = nlohmann::json::array();
    for (const auto& [x, y] : run.focus->samples) samples.push_back({x, y});
    f["samples"] = samples;
    // The loop against the optics' prediction for the mirror (rig/focus.h): inside the depth of focus, the focus
    // it found costs at most the tolerance of blur over the field.
    if (const auto p = PredictFocus(spec, run.mirror))
      f["predicted"] = {
          {"best_focus_m", p->best},
          {"depth_of_focus_m", {p->near, std::isinf(p->far) ? nlohmann::json("infinity") : nlohmann::json(p->far)}},
          {"tolerance_px", p->tolerance_px},
          {"worst_rms_px_at_best", p->worst_rms_px},
          {"within", p->Contains(run.focus->focus)}};
    j["focus"] = f;
  }
  j["render_seconds"] = run.render_seconds;
  j["machine_seconds"] = run.machine_seconds;
  return j;
}

std::string WriteAlignReport(const TurretSpec& spec, const AlignStudyOptions& o, const std::vector<AlignRun>& runs,
                             const std::filesystem::path& out_dir) {
  StagedDirectory stage(out_dir, "rig align", {spec.source});
  const auto& dir = stage.staging();
  const auto summary = SummariseAlignStudy(spec, runs);
  nlohmann::json j;
  j["tool"] = "hovs rig align";
  j["machine"] = spec.source;
  j["machine_text"] = spec.text;
  j["options"] = {
      {"starts", o.starts},
      {"seed", o.seed},
      {"start_lateral_mm", o.start.lateral * 1e3},
      {"start_tilt_deg", o.start.tilt / kDeg},
      {"start_height_mm", o.start.height * 1e3},
      {"max_iterations", o.align.max_iterations},
      {"tolerances", {o.align.lateral_tolerance * 1e3, o.align.tilt_tolerance / kDeg, o.align.height_tolerance * 1e3}},
      {"gains", {{"kp", o.align.lateral.kp}, {"ki", o.align.lateral.ki}, {"kd", o.align.lateral.kd}}},
      {"focus", o.focus},
      {"fault", o.fault ? o.fault->axis : ""},
      {"downscale", spec.downscale},
      {"samples", spec.samples}};
  nlohmann::json rs = nlohmann::json::array();
  for (const auto& r : runs) rs.push_back(AlignRunJson(spec, r));
  j["runs"] = rs;
  nlohmann::json sj = nlohmann::json::array();
  for (const auto& s : summary)
    sj.push_back({{"mirror", s.mirror},
                  {"runs", s.runs},
                  {"converged", s.converged},
                  {"lateral_mm", {{"median", s.median_lateral * 1e3}, {"worst", s.worst_lateral * 1e3}}},
                  {"tilt_deg", {{"median", s.median_tilt / kDeg}, {"worst", s.worst_tilt / kDeg}}},
                  {"height_mm", {{"median", s.median_height * 1e3}, {"worst", s.worst_height * 1e3}}},
                  {"iterations", {{"median", s.median_iterations}, {"worst", s.worst_iterations}}},
                  {"focus_ratio_median", s.median_focus_ratio}});
  j["summary"] = sj;
  j["versions"] = RigVersions();
  WriteFileAtomic(dir / "align.json", j.dump(1) + "\n");

  // Convergence of the true deviations, every run, coloured by mirror (figures need a display: under xvfb-run).
  const bool figures = results::CanRender();
  if (figures) std::filesystem::create_directories(dir / "figures");
  const struct {
    const char* file;
    const char* label;
    double limit;
    double (*value)(const MirrorPose&);
  } kinds[] = {
      {"convergence_lateral.png", "log10 lateral offset (mm)", 0.05,
       [](const MirrorPose& p) { return p.LateralM() * 1e3; }},
      {"convergence_tilt.png", "log10 tilt (deg)", 0.02, [](const MirrorPose& p) { return p.TiltRad() / kDeg; }},
      {"convergence_height.png", "log10 height error (mm)", 0.05,
       [](const MirrorPose& p) { return std::abs(p.offset.z()) * 1e3; }},
  };
  for (const auto& kind : kinds) {
    if (!figures) break;
    results::LineFigure f;
    f.title = std::string("Visual positioning: ") + kind.label + " against the renderer's truth";
    f.x_label = "iteration";
    f.y_label = kind.label;
    std::vector<bool> named(spec.mirrors.size(), false);
    int longest = 1;
    for (const auto& r : runs) {
      results::Series s;
      for (const auto& step : r.result.steps)
        if (step.truth) {
          s.x.push_back(step.iteration);
          s.y.push_back(std::log10(std::max(1e-6, kind.value(*step.truth))));
        }
      s.x.push_back(static_cast<double>(r.result.steps.size()));
      s.y.push_back(std::log10(std::max(1e-6, kind.value(*r.result.final_truth))));
      longest = std::max(longest, static_cast<int>(r.result.steps.size()));
      s.name = spec.mirrors[r.mirror].id;
      s.rgb = Colour(r.mirror);
      s.line_width = 1.0;
      s.in_legend = !named[r.mirror];
      named[r.mirror] = true;
      if (s.x.size() >= 2) f.series.push_back(s);
    }
    results::Series limit;
    limit.name = "acceptance";
    limit.rgb = {0.6, 0.6, 0.6};
    limit.x = {0, static_cast<double>(longest)};
    limit.y = {std::log10(kind.limit), std::log10(kind.limit)};
    f.series.push_back(limit);
    results::WritePng(f, dir / "figures" / kind.file);
  }

  std::ostringstream sum;
  sum << "hovs rig align: " << spec.name << ", " << runs.size() << " runs from "
      << FormatNumber("%.2f", o.start.lateral * 1e3) << " mm lateral, " << FormatNumber("%.2f", o.start.tilt / kDeg)
      << " deg tilt, " << FormatNumber("%.2f", o.start.height * 1e3)
      << " mm height (truth after the loop: median / worst)\n";
  std::vector<std::vector<std::string>> rows;
  for (const auto& s : summary) {
    const std::vector<std::string> row = {
        s.mirror,
        std::to_string(s.converged) + " / " + std::to_string(s.runs),
        FormatNumber("%.4f", s.median_lateral * 1e3) + " / " + FormatNumber("%.4f", s.worst_lateral * 1e3),
        FormatNumber("%.4f", s.median_tilt / kDeg) + " / " + FormatNumber("%.4f", s.worst_tilt / kDeg),
        FormatNumber("%.4f", s.median_height * 1e3) + " / " + FormatNumber("%.4f", s.worst_height * 1e3),
        FormatNumber("%.0f", s.median_iterations) + " / " + FormatNumber("%.0f", s.worst_iterations),
        o.focus ? FormatNumber("%.4f", s.median_focus_ratio) : "-"};
    rows.push_back(row);
    sum << "  " << s.mirror << ": converged " << row[1] << ", lateral " << row[2] << " mm, tilt " << row[3]
        << " deg, height " << row[4] << " mm, iterations " << row[5] << "\n";
  }
  for (const auto& r : runs)
    if (!r.result.failure.empty())
      sum << "  " << spec.mirrors[r.mirror].id << " seed " << r.seed << ": " << r.result.failure << "\n";
  WriteFileAtomic(dir / "summary.txt", sum.str());

  results::HtmlPage page("hovs rig align: " + spec.name);
  page.Paragraph(
      "The visual positioning loop of the variable-scale unit in simulation: each run starts from a seeded disturbed "
      "pose, the renderer images the unit in its true state, the label's pose is measured and the PID loop acts "
      "on the simulated axes (lag, steps, backlash, noise). Final deviations are the renderer's truth.");
  page.Table({"mirror", "converged", "lateral (mm)", "tilt (deg)", "height (mm)", "iterations", "focus / best seen"},
             rows);
  if (figures) {
    page.Figure("figures/convergence_lateral.png", "Lateral offset per iteration (truth)", 640);
    page.Figure("figures/convergence_tilt.png", "Tilt per iteration (truth)", 640);
    page.Figure("figures/convergence_height.png", "Height error per iteration (truth)", 640);
  } else {
    page.Paragraph("No figures: there was no X display (run under xvfb-run -a for them).");
  }
  page.Heading("Machine");
  page.Preformatted(spec.text);
  WriteFileAtomic(dir / "index.html", page.Render());
  stage.Commit();
  return sum.str();
}

namespace {

// The median difference (deg) between the elevations that `model` and the machine's nominal model of mirror k
// give the pixels of k's image annulus (the image camera at 1/downscale of the camera).
double FieldDifferenceDeg(const TurretSpec& spec, int k, int downscale, const AnyModel& model) {
  TurretSpec at = spec;
  at.downscale = downscale;
  CatadioptricCamera<double> nominal = RigAt(at, k, {});
  nominal.camera = at.ImageCamera();
  const HyperboloidMirror<double>& m = spec.mirrors.at(k).mirror;
  const double rim = nominal.camera.fx * m.RimRadius() / spec.mirrors[k].PlateHeight();
  std::vector<double> diffs;
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 16; ++j) {
      const double r = rim * (0.45 + 0.5 * i / 7.0), phi = 2 * M_PI * j / 16;
      const Vec2d uv(nominal.camera.cx + r * std::cos(phi), nominal.camera.cy + r * std::sin(phi));
      Vec3d a, b;
      if (!nominal.CamFromImg(uv, &a) || !model.MirrorFromImg(uv, &b)) continue;
      const auto elevation = [](const Vec3d& v) { return std::atan2(v.z(), v.head<2>().norm()) * 180 / M_PI; };
      diffs.push_back(std::abs(elevation(a) - elevation(b)));
    }
  return diffs.size() < 32 ? std::numeric_limits<double>::infinity() : Median(diffs);
}

}  // namespace

RigFolder LoadRigFolder(const std::filesystem::path& rig_json, const TurretSpec& spec) {
  namespace fs = std::filesystem;
  const nlohmann::json j = ReadJsonFile(rig_json);
  const std::string where = rig_json.string();
  HOVS_REQUIRE(j.is_object() && JsonText(j, "format") == "hovs-rig", where,
               "not a hovs rig folder record (hovs rig calibrate writes rig.json)");
  HOVS_REQUIRE(j.contains("version") && j["version"] == kRigFolderVersion, where + " (version)",
               "this hovs reads rig folders of version ", kRigFolderVersion,
               " (the files' checks need it): run hovs rig calibrate again");
  HOVS_REQUIRE(j.contains("mirrors") && j["mirrors"].is_object(), where,
               "expected {\"mirrors\": {\"<id>\": {\"calibration\": ..., \"map\": ...}}}");
  HOVS_REQUIRE(j.contains("machine") && j["machine"].is_object(), where + " (machine)", "missing");
  HOVS_REQUIRE(JsonString(j["machine"], "geometry_checksum", where + " (machine)") ==
                   TextChecksum(MachineGeometryJson(spec).dump()),
               where, "was made on machine '", JsonText(j["machine"], "name"), "' (", JsonText(j["machine"], "source"),
               "), whose camera, mirrors or label differ from ", spec.source,
               "'s: its calibrations are not for this machine");
  RigFolder r;
  r.root = rig_json.parent_path();
  r.downscale = static_cast<int>(JsonInteger(j, "downscale", 1, 16, where));
  HOVS_REQUIRE(spec.camera.width % r.downscale == 0 && spec.camera.height % r.downscale == 0, where + " (downscale)",
               r.downscale, " does not divide the camera's image");
  if (j.contains("seed")) {
    HOVS_REQUIRE(j["seed"].is_number_unsigned(), where + " (seed)", "must be a non-negative integer");
    r.seed = j["seed"].get<uint64_t>();
  }
  const int width = spec.camera.width / r.downscale, height = spec.camera.height / r.downscale;
  for (const auto& [id, e] : j["mirrors"].items()) {
    const std::string w = where + " (mirrors." + id + ")";
    const int k = spec.MirrorIndex(id);
    HOVS_REQUIRE(e.is_object(), w, "expected an object");
    const HyperboloidMirror<double>& m = spec.mirrors[k].mirror;
    HOVS_REQUIRE(e.contains("mirror") && JsonNumber(e["mirror"], "a", w) == m.a &&
                     JsonNumber(e["mirror"], "b", w) == m.b &&
                     JsonNumber(e["mirror"], "rim_diameter", w) == m.rim_diameter,
                 w, "was calibrated for another mirror than the machine's '", id, "'");
    RigFolder::Entry entry;
    entry.calibration = ContainedPath(r.root, JsonString(e, "calibration", w), w + ".calibration");
    entry.map = ContainedPath(r.root, JsonString(e, "map", w), w + ".map");
    for (const auto& [path, key] :
         {std::pair{entry.calibration, "calibration_checksum"}, std::pair{entry.map, "map_checksum"}}) {
      RequireFile(path);
      HOVS_REQUIRE(FileChecksum(path) == JsonString(e, key, w), path.string(), "does not match its checksum in ", where,
                   ": the file was replaced or changed after hovs rig calibrate wrote it");
    }
    entry.model = calib::LoadPolynomialModelFile(entry.calibration);
    HOVS_REQUIRE(entry.model.width == width && entry.model.height == height, entry.calibration.string(), "is for ",
                 entry.model.width, " x ", entry.model.height, " images; the folder's (1/", r.downscale,
                 " of the camera) are ", width, " x ", height);
    const AnyModel model = AnyModel::Polynomial(entry.model, entry.calibration.string());
    const double off = FieldDifferenceDeg(spec, k, r.downscale, model);
    if (!(off <= 0.5)) {
      std::string best;
      double best_off = std::numeric_limits<double>::infinity();
      for (size_t o = 0; o < spec.mirrors.size(); ++o) {
        const double d = FieldDifferenceDeg(spec, static_cast<int>(o), r.downscale, model);
        if (d < best_off) best_off = d, best = spec.mirrors[o].id;
      }
      throw Error(entry.calibration.string(),
                  "does not image mirror '" + id + "''s field (its elevations differ from the machine's model by " +
                      FormatNumber("%.3g", off) + " deg; mirror '" + best + "' fits it within " +
                      FormatNumber("%.3g", best_off) + " deg): it is not this mirror's calibration");
    }
    const unwrap::RemapTable table = unwrap::LoadRemapTable(entry.map);
    HOVS_REQUIRE(table.source_width == width && table.source_height == height, entry.map.string(), "maps ",
                 table.source_width, " x ", table.source_height, " images; the folder's are ", width, " x ", height);
    const nlohmann::json header = ParseJson(table.header, entry.map.string() + " (header)");
    bool same = header.contains("model") && header["model"].contains("parameters");
    for (const auto& [name, value] : model.Parameters()) {
      if (!same) break;
      const auto& p = header["model"]["parameters"];
      same = p.contains(name) && p[name].is_number() &&
             std::abs(p[name].get<double>() - value) <= 1e-9 * std::max(1.0, std::abs(value));
    }
    HOVS_REQUIRE(same, entry.map.string(), "was not built from ", entry.calibration.string(),
                 " (its model's parameters differ): rebuild the folder with hovs rig calibrate");
    r.mirrors[id] = std::move(entry);
  }
  return r;
}

SwitchResult SimulateSwitch(const TurretSpec& spec, int from, int to, uint64_t seed, const AlignOptions& align,
                            const FocusOptions& focus) {
  HOVS_REQUIRE(from >= 0 && from < static_cast<int>(spec.mirrors.size()) && to >= 0 &&
                   to < static_cast<int>(spec.mirrors.size()),
               "rig switch", "no such mirror");
  RequireLabelPrecision(spec, to, align, spec.source);
  const auto seats = DrawSeats(spec, seed * 31u + 17u);
  SimulatedUnit unit(spec, from, spec.NominalAxes(from, 1.15 * spec.mirrors[from].PlateHeight()), seats, seed);
  SwitchResult s;
  s.from = from, s.to = to;
  // The move: the turret to the new slot, the rod to its plate height, the other axes home, the focus on the
  // new mirror's label (the plate) for the alignment; the focus loop then finds the mirror image's focus.
  const auto target = spec.NominalAxes(to, spec.mirrors[to].PlateHeight());
  for (int a = 0; a < kAxisCount; ++a) unit.machine().axis(AxisAt(a)).MoveTo(target[a]);
  unit.machine().WaitIdle(120.0);
  unit.SetMirror(to);
  s.move_seconds = unit.machine().Now();
  s.after_move = *unit.Truth();
  s.align = Align(unit, spec, align);
  if (s.align.converged) s.focus = FocusLens(unit, spec, focus);
  s.machine_seconds = unit.machine().Now();
  s.render_seconds = unit.render_seconds();
  s.images = unit.images();
  return s;
}

nlohmann::json SwitchJson(const TurretSpec& spec, const SwitchResult& s) {
  AlignRun run;
  run.mirror = s.to;
  run.start = s.after_move;
  run.result = s.align;
  run.focus = s.focus;
  run.render_seconds = s.render_seconds;
  run.machine_seconds = s.machine_seconds;
  nlohmann::json j = AlignRunJson(spec, run);
  j["from"] = spec.mirrors.at(s.from).id;
  j["to"] = spec.mirrors.at(s.to).id;
  j["move_seconds"] = s.move_seconds;
  j["images"] = s.images;
  return j;
}

}  // namespace hovs::rig
