// The tolerance study's outputs: the analysis of the samples, tolerance.json, samples.csv, the report page, and the
// merge of shards.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "core/json.h"
#include "core/shard_set.h"
#include "design/study.h"
#include "results/html.h"
#include "results/plot.h"
#include "study/tolerance.h"

namespace hovs::study {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kFigures = 4;
constexpr double kDeg = M_PI / 180;
constexpr size_t kCheckSamples = 200;  // samples re-evaluated to check a uniform scaling of the tolerances

// p in [0, 1] of sorted values: the nearest rank.
double Percentile(const std::vector<double>& sorted, double p) {
  const size_t n = sorted.size();
  const size_t k = static_cast<size_t>(std::max(1.0, std::ceil(p * static_cast<double>(n)))) - 1;
  return sorted[std::min(k, n - 1)];
}

json Summary(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  double sum = 0;
  for (double x : v) sum += x;
  json j = {{"mean", sum / static_cast<double>(v.size())},
            {"p50", Percentile(v, 0.5)},
            {"p90", Percentile(v, 0.9)},
            {"p95", Percentile(v, 0.95)},
            {"p99", Percentile(v, 0.99)},
            {"max", v.back()}};
  constexpr int kBins = 30;
  const double top = v.back() > 0 ? v.back() : 1.0;
  std::vector<int64_t> counts(kBins, 0);
  for (double x : v) ++counts[std::min(kBins - 1, static_cast<int>(x / top * kBins))];
  std::vector<double> edges;
  for (int b = 0; b <= kBins; ++b) edges.push_back(top * b / kBins);
  j["histogram"] = {{"edges", edges}, {"counts", counts}};
  return j;
}

std::string DistributionName(const Tolerance& t) {
  return t.distribution == Distribution::kNormal ? "normal" : "uniform";
}

// Figure m of the erroneous left unit alone (the right unit nominal).
double Alone(const ToleranceEvaluator& ev, const std::string& parameter, double size, int m) {
  return ev.Evaluate(SingleError(parameter, size), UnitErrors{}).values[m];
}

}  // namespace

json AnalyseSamples(const ToleranceConfig& config, const std::vector<Sample>& samples) {
  HOVS_REQUIRE(!samples.empty(), "tolerance", "no samples to analyse");
  const ToleranceEvaluator ev(config);
  json report;
  report["samples"] = samples.size();
  std::vector<double> p95(kFigures);
  for (int m = 0; m < kFigures; ++m) {
    std::vector<double> v;
    for (const Sample& s : samples) v.push_back(s.figures.values[m]);
    report["figures"][Metrics()[m].name] = Summary(v);
    p95[m] = report["figures"][Metrics()[m].name]["p95"].get<double>();
  }
  // Each parameter alone at its tolerance: the figures it causes, and the ranking per figure.
  json sensitivity = json::array();
  std::vector<std::vector<std::pair<double, std::string>>> ranked(kFigures);
  for (const Parameter& p : Parameters()) {
    const auto it = config.tolerances.find(p.name);
    if (it == config.tolerances.end() || it->second.size == 0) continue;
    json entry = {{"parameter", p.name},
                  {"unit", p.unit},
                  {"distribution", DistributionName(it->second)},
                  {"size", it->second.size}};
    for (int m = 0; m < kFigures; ++m) {
      const double v = Alone(ev, p.name, it->second.size, m);
      entry["figures"][Metrics()[m].name] = {{"at_size", v}, {"per_unit", v / it->second.size}};
      ranked[m].push_back({v, p.name});
    }
    sensitivity.push_back(entry);
  }
  report["sensitivity"] = sensitivity;
  for (int m = 0; m < kFigures; ++m) {
    std::stable_sort(ranked[m].begin(), ranked[m].end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    json names = json::array();
    for (const auto& r : ranked[m]) names.push_back(r.second);
    report["ranking"][Metrics()[m].name] = names;
  }
  // The user's limits: whether the 95th percentile meets each; the factor on every tolerance that would bring it
  // there (checked on the first samples, scaled); each parameter's tolerance that alone reaches the limit
  // (linear estimate, checked).
  for (int m = 0; m < kFigures; ++m) {
    const auto lim = config.limits.find(Metrics()[m].name);
    if (lim == config.limits.end()) continue;
    const double limit = lim->second;
    json l = {{"limit", limit}, {"p95", p95[m]}, {"meets", p95[m] <= limit}};
    if (p95[m] > 0) {
      const double k = limit / p95[m];
      const size_t n = std::min(samples.size(), kCheckSamples);
      std::vector<double> check(n);
      tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const int64_t index = samples[i].index;
        check[i] =
            ev.Evaluate(DrawErrors(config, index, 0).Scaled(k), DrawErrors(config, index, 1).Scaled(k)).values[m];
      });
      std::sort(check.begin(), check.end());
      l["uniform_scale"] = k;
      l["uniform_scale_check_p95"] = Percentile(check, 0.95);
      l["uniform_scale_check_samples"] = n;
    }
    json alone = json::object();
    for (const json& s : sensitivity) {
      const double at = s["figures"][Metrics()[m].name]["at_size"].get<double>(), size = s["size"].get<double>();
      // (Below a billionth of the limit the figure is rounding noise: the parameter alone never reaches it.)
      if (!(at > 1e-9 * limit)) {
        alone[s["parameter"].get<std::string>()] = {{"needed", nullptr}, {"check", 0.0}};
        continue;
      }
      const double needed = size * limit / at;
      alone[s["parameter"].get<std::string>()] = {{"needed", needed}, {"check", Alone(ev, s["parameter"], needed, m)}};
    }
    l["alone"] = alone;
    report["limits"][Metrics()[m].name] = l;
  }
  return report;
}

namespace {

// samples.csv: the index, both units' errors in the parameters' units, the figures; %.17g (exact in doubles).
std::string SamplesCsv(const std::vector<Sample>& samples, bool header) {
  std::ostringstream out;
  const auto components = [](const UnitErrors& e) {
    return std::vector<double>{1e3 * e.a,
                               1e3 * e.b,
                               1e3 * e.rim,
                               e.tilt.x() / kDeg,
                               e.tilt.y() / kDeg,
                               1e3 * e.offset.x(),
                               1e3 * e.offset.y(),
                               1e3 * e.offset.z(),
                               100 * e.focal,
                               e.principal_point.x(),
                               e.principal_point.y()};
  };
  if (header) {
    out << "index";
    for (const char* unit : {"left", "right"})
      for (const Parameter& p : Parameters())
        for (int k = 0; k < p.components; ++k)
          out << "," << unit << "." << p.name << (p.components > 1 ? (k == 0 ? "_x" : "_y") : "") << "_"
              << (p.unit == "%" ? "percent" : p.unit);
    for (const Metric& m : Metrics()) out << "," << m.name;
    out << "\n";
  }
  for (const Sample& s : samples) {
    out << s.index;
    for (const UnitErrors* e : {&s.left, &s.right})
      for (double v : components(*e)) out << "," << FormatNumber("%.17g", v);
    for (int m = 0; m < kFigures; ++m) out << "," << FormatNumber("%.17g", s.figures.values[m]);
    out << "\n";
  }
  return out.str();
}

// A shard's samples back from its samples.csv: the index and the figures as written; the errors drawn again from
// the index (the draw is a function of the seed and the index alone).
std::vector<Sample> ReadSamplesCsv(const fs::path& path, const ToleranceConfig& config) {
  std::istringstream in(ReadFile(path));
  std::string line;
  HOVS_REQUIRE(std::getline(in, line) && line.rfind("index,", 0) == 0, path.string(), "not a tolerance samples file");
  std::vector<Sample> samples;
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    std::vector<std::string> cells;
    std::stringstream cs(line);
    std::string cell;
    while (std::getline(cs, cell, ',')) cells.push_back(cell);
    HOVS_REQUIRE(cells.size() > kFigures, path.string() + ":" + std::to_string(row), "too few columns");
    Sample s;
    char* end = nullptr;
    s.index = std::strtoll(cells[0].c_str(), &end, 10);
    HOVS_REQUIRE(*end == '\0' && s.index >= 0, path.string() + ":" + std::to_string(row), "bad index '", cells[0], "'");
    for (int m = 0; m < kFigures; ++m) {
      const std::string& c = cells[cells.size() - kFigures + m];
      s.figures.values[m] = std::strtod(c.c_str(), &end);
      HOVS_REQUIRE(*end == '\0' && std::isfinite(s.figures.values[m]), path.string() + ":" + std::to_string(row),
                   "bad value '", c, "'");
    }
    s.left = DrawErrors(config, s.index, 0);
    s.right = DrawErrors(config, s.index, 1);
    samples.push_back(s);
  }
  return samples;
}

json StudyHead(const ToleranceConfig& config, int64_t count, const std::map<std::string, std::string>& versions) {
  json j;
  j["format"] = "hovs-tolerance";
  j["version"] = 1;
  j["name"] = config.name;
  j["config"] = {{"source", config.source},
                 {"text", config.text},
                 {"design_source", config.design.source},
                 {"design_text", config.design.text}};
  j["seed"] = config.seed;
  j["samples"] = count;
  j["nominal"] = {{"a", config.nominal.a}, {"b", config.nominal.b}, {"rim_diameter", config.nominal.d}};
  j["versions"] = versions;
  return j;
}

void WritePage(const fs::path& dir, const ToleranceConfig& config, const json& study) {
  const json& r = study["report"];
  results::HtmlPage page("hovs tolerance: " + config.name);
  page.Paragraph(
      std::to_string(r["samples"].get<int64_t>()) + " Monte-Carlo samples (seed " + std::to_string(config.seed) +
      ") of the design a = " + FormatNumber("%.1f", 1e3 * config.nominal.a) + " mm, b = " +
      FormatNumber("%.1f", 1e3 * config.nominal.b) + " mm, rim " + FormatNumber("%.1f", 1e3 * config.nominal.d) +
      " mm, each unit with its own errors, evaluated against the nominal model (study/tolerance.h says how).");
  std::vector<std::vector<std::string>> rows;
  for (const Metric& m : Metrics()) {
    const json& f = r["figures"][m.name];
    std::vector<std::string> row = {m.name, m.meaning};
    for (const char* k : {"mean", "p50", "p90", "p95", "p99", "max"})
      row.push_back(FormatNumber("%.4g", f[k].get<double>()));
    rows.push_back(row);
  }
  page.Heading("Figures over the samples");
  page.Table({"figure", "what", "mean", "p50", "p90", "p95", "p99", "max"}, rows);
  page.Heading("Sensitivity: each tolerance alone");
  rows.clear();
  for (const json& s : r["sensitivity"]) {
    std::vector<std::string> row = {s["parameter"], FormatNumber("%g", s["size"].get<double>()) + " " +
                                                        s["unit"].get<std::string>() + " (" +
                                                        s["distribution"].get<std::string>() + ")"};
    for (const Metric& m : Metrics())
      row.push_back(FormatNumber("%.4g", s["figures"][m.name]["at_size"].get<double>()));
    rows.push_back(row);
  }
  std::vector<std::string> header = {"parameter", "tolerance"};
  for (const Metric& m : Metrics()) header.push_back(m.name);
  page.Table(header, rows);
  rows.clear();
  for (const Metric& m : Metrics()) {
    std::string order;
    for (const auto& n : r["ranking"][m.name]) order += (order.empty() ? "" : " > ") + n.get<std::string>();
    rows.push_back({m.name, order});
  }
  page.Table({"figure", "what matters most, in order"}, rows);
  if (r.contains("limits")) {
    page.Heading("Tolerances for the limits");
    rows.clear();
    for (const auto& [name, l] : r["limits"].items()) {
      std::string alone;
      for (const auto& [p, a] : l["alone"].items())
        alone += (alone.empty() ? "" : "; ") + p + " " +
                 (a["needed"].is_null() ? std::string("any") : FormatNumber("%.3g", a["needed"].get<double>()));
      rows.push_back({name, FormatNumber("%g", l["limit"].get<double>()), FormatNumber("%.4g", l["p95"].get<double>()),
                      l["meets"].get<bool>() ? "yes" : "no",
                      l.contains("uniform_scale")
                          ? FormatNumber("%.3g", l["uniform_scale"].get<double>()) + " (p95 " +
                                FormatNumber("%.4g", l["uniform_scale_check_p95"].get<double>()) + ")"
                          : "-",
                      alone});
    }
    page.Table({"figure", "limit", "p95", "met", "every tolerance times (check)", "each alone at most"}, rows);
  }
  if (results::CanRender()) {
    fs::create_directories(dir / "figures");
    for (const Metric& m : Metrics()) {
      const json& h = r["figures"][m.name]["histogram"];
      results::Series s;
      s.name = "samples";
      for (size_t b = 0; b + 1 < h["edges"].size(); ++b)
        for (double x : {h["edges"][b].get<double>(), h["edges"][b + 1].get<double>()})
          s.x.push_back(x), s.y.push_back(static_cast<double>(h["counts"][b].get<int64_t>()));
      results::LineFigure fig;
      fig.title = m.meaning;
      fig.x_label = m.name;
      fig.y_label = "samples";
      fig.series = {s};
      results::WritePng(fig, dir / "figures" / (m.name + ".png"));
      page.Figure("figures/" + m.name + ".png", m.name + ": histogram over the samples", 640);
    }
  } else {
    page.Paragraph("No figures: VTK cannot render here (run under xvfb-run -a).");
  }
  design::AppendConfigAndVersions(&page, config.text, study["versions"].get<std::map<std::string, std::string>>());
  WriteFileAtomic(dir / "index.html", page.Render());
}

void WriteWhole(const ToleranceConfig& config, const std::vector<Sample>& samples, json study, const fs::path& dir) {
  study["report"] = AnalyseSamples(config, samples);
  WriteFileAtomic(dir / "samples.csv", SamplesCsv(samples, true));
  WriteFileAtomic(dir / "tolerance.json", study.dump(1) + "\n");
  WritePage(dir, config, study);
}

}  // namespace

void WriteToleranceStudy(const ToleranceConfig& config, int64_t count, int shard_index, int shard_count,
                         const fs::path& out, const std::map<std::string, std::string>& versions, bool progress) {
  const std::vector<fs::path> inputs = {config.source, config.design.source};
  CheckOutputFolder(out, "tolerance", inputs);
  const std::vector<Sample> samples = RunSamples(config, count, shard_index, shard_count, progress);
  StagedDirectory stage(out, "tolerance", inputs);
  json study = StudyHead(config, count, versions);
  if (shard_count > 1) {
    study["shard"] = {{"index", shard_index},
                      {"count", shard_count},
                      {"first", samples.front().index},
                      {"end", samples.back().index + 1}};
    WriteFileAtomic(stage.staging() / "samples.csv", SamplesCsv(samples, true));
    WriteFileAtomic(stage.staging() / "tolerance.json", study.dump(1) + "\n");
  } else {
    WriteWhole(config, samples, study, stage.staging());
  }
  stage.Commit();
}

bool IsToleranceFolder(const fs::path& dir) { return fs::is_regular_file(dir / "tolerance.json"); }

void MergeToleranceShards(const std::vector<fs::path>& shards, const fs::path& out) {
  HOVS_REQUIRE(!shards.empty(), "merge", "no shards given");
  std::vector<json> heads;
  std::vector<fs::path> inputs;
  for (const fs::path& dir : shards) {
    const fs::path file = dir / "tolerance.json";
    HOVS_REQUIRE(fs::is_regular_file(file), dir.string(), "not a tolerance study folder (no tolerance.json)");
    json j = ReadJsonFile(file);
    HOVS_REQUIRE(j.is_object() && j.value("format", "") == "hovs-tolerance", file.string(), "not a tolerance study");
    HOVS_REQUIRE(j.contains("shard"), file.string(), "is not a shard (written without --shard)");
    heads.push_back(j), inputs.push_back(file);
  }
  const std::vector<size_t> order = OrderShards(heads, inputs);
  json ref = heads[0];
  ref.erase("shard");
  const int count = static_cast<int>(order.size());
  // The config as the study recorded it (the files may have moved or changed since).
  const json& c = ref["config"];
  const design::DesignConfig design =
      design::ParseDesignConfig(c["design_text"].get<std::string>(), c["design_source"].get<std::string>());
  const ToleranceConfig config =
      ParseToleranceConfig(c["text"].get<std::string>(), c["source"].get<std::string>(), ".", &design);
  std::vector<Sample> samples;
  for (int i = 0; i < count; ++i) {
    const fs::path dir = shards[order[static_cast<size_t>(i)]];
    const auto part = ReadSamplesCsv(dir / "samples.csv", config);
    for (const Sample& s : part) {
      HOVS_REQUIRE(s.index == static_cast<int64_t>(samples.size()), (dir / "samples.csv").string(), "sample ", s.index,
                   " is out of order (expected ", samples.size(), ")");
      samples.push_back(s);
    }
  }
  HOVS_REQUIRE(static_cast<int64_t>(samples.size()) == ref["samples"].get<int64_t>(), "merge", "the shards hold ",
               samples.size(), " samples but the study has ", ref["samples"].get<int64_t>());
  CheckOutputFolder(out, "tolerance", inputs);
  StagedDirectory stage(out, "tolerance", inputs);
  WriteWhole(config, samples, ref, stage.staging());
  stage.Commit();
}

}  // namespace hovs::study
