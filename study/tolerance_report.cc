// The tolerance study's outputs: the analysis of the samples, tolerance.json, samples.csv, the report page, and the
// merge of shards.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/error.h"
#include "core/format.h"
#include "core/io.h"
#include "core/json.h"
#include "core/shard_set.h"
#include "core/statistics.h"
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

// JSON of a figure's value: null where it failed (NaN) or is unbounded (a percentile landing on failed samples).
json Value(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// The percentiles and histogram of one figure over the samples. Failed samples (NaN) are counted apart; the
// statistics are of the evaluated ones, and "all_p95" ranks the failed above every value (null when it lands on
// one), so that failures can never make a limit pass.
json Summary(const std::vector<double>& values) {
  std::vector<double> v;
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  std::sort(v.begin(), v.end());
  const size_t failed = values.size() - v.size();
  json j = {{"evaluated", v.size()}, {"failed", failed}};
  std::vector<double> all = v;
  all.resize(values.size(), std::numeric_limits<double>::infinity());
  j["all_p95"] = Value(Percentile(all, 0.95));
  if (v.empty()) {
    for (const char* k : {"mean", "p50", "p90", "p95", "p99", "max"}) j[k] = nullptr;
    return j;
  }
  double sum = 0;
  for (double x : v) sum += x;
  j["mean"] = sum / static_cast<double>(v.size());
  j["p50"] = Percentile(v, 0.5), j["p90"] = Percentile(v, 0.9), j["p95"] = Percentile(v, 0.95);
  j["p99"] = Percentile(v, 0.99), j["max"] = v.back();
  constexpr int kBins = 30;
  const double top = v.back() > 0 ? v.back() : 1.0;
  std::vector<int64_t> counts(kBins, 0);
  for (double x : v) ++counts[std::min(kBins - 1, static_cast<int>(x / top * kBins))];
  std::vector<double> edges;
  for (int b = 0; b <= kBins; ++b) edges.push_back(top * b / kBins);
  j["histogram"] = {{"edges", edges}, {"counts", counts}};
  return j;
}

// A figure for the page: its value, or "failed" where it is null (failed or unbounded).
std::string Shown(const json& j) { return j.is_number() ? FormatNumber("%.4g", j.get<double>()) : "failed"; }

// A JSON number or null as a double (null: NaN).
double Number(const json& j) { return j.is_number() ? j.get<double>() : std::numeric_limits<double>::quiet_NaN(); }

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
  json warnings = json::array();
  for (int m = 0; m < kFigures; ++m) {
    std::vector<double> v;
    for (const Sample& s : samples) v.push_back(s.figures.values[m]);
    const json summary = Summary(v);
    report["figures"][Metrics()[m].name] = summary;
    p95[m] = Number(summary["all_p95"]);
    const auto failed = summary["failed"].get<size_t>();
    if (failed > 0 && 100 * failed >= samples.size())  // 1 % or more
      warnings.push_back(std::to_string(failed) + " of " + std::to_string(samples.size()) + " samples (" +
                         FormatNumber("%.1f", 100.0 * static_cast<double>(failed) / samples.size()) +
                         " %) could not evaluate " + Metrics()[m].name +
                         ": their units no longer image the field the nominal model covers (tolerances too large)");
  }
  report["warnings"] = warnings;
  // Each parameter alone at its tolerance: the figures it causes, and the ranking per figure (a figure that fails
  // ranks first).
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
      entry["figures"][Metrics()[m].name] = {{"at_size", Value(v)}, {"per_unit", Value(v / it->second.size)}};
      ranked[m].push_back({std::isfinite(v) ? v : std::numeric_limits<double>::infinity(), p.name});
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
  // The user's limits: whether the 95th percentile over every sample (failed ones above every value) meets each;
  // the factor on every tolerance that would bring it there (checked on the first samples, scaled); each
  // parameter's tolerance that alone reaches the limit (linear estimate, checked).
  for (int m = 0; m < kFigures; ++m) {
    const auto lim = config.limits.find(Metrics()[m].name);
    if (lim == config.limits.end()) continue;
    const double limit = lim->second;
    const json& summary = report["figures"][Metrics()[m].name];
    json l = {{"limit", limit},
              {"p95", Value(p95[m])},
              {"failed", summary["failed"]},
              {"meets", std::isfinite(p95[m]) && p95[m] <= limit}};
    if (std::isfinite(p95[m]) && p95[m] > 0) {
      const double k = limit / p95[m];
      const size_t n = std::min(samples.size(), kCheckSamples);
      std::vector<double> check(n);
      tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const int64_t index = samples[i].index;
        const double v =
            ev.Evaluate(DrawErrors(config, index, 0).Scaled(k), DrawErrors(config, index, 1).Scaled(k)).values[m];
        check[i] = std::isfinite(v) ? v : std::numeric_limits<double>::infinity();
      });
      std::sort(check.begin(), check.end());
      l["uniform_scale"] = k;
      l["uniform_scale_check_p95"] = Value(Percentile(check, 0.95));
      l["uniform_scale_check_samples"] = n;
    }
    json alone = json::object();
    for (const json& s : sensitivity) {
      const double at = Number(s["figures"][Metrics()[m].name]["at_size"]), size = s["size"].get<double>();
      const std::string name = s["parameter"].get<std::string>();
      if (!std::isfinite(at)) {  // the figure fails at this tolerance: no linear estimate
        alone[name] = {{"needed", nullptr}, {"check", nullptr}, {"fails_at_size", true}};
        continue;
      }
      // (Below a billionth of the limit the figure is rounding noise: the parameter alone never reaches it.)
      if (!(at > 1e-9 * limit)) {
        alone[name] = {{"needed", nullptr}, {"check", 0.0}};
        continue;
      }
      const double needed = size * limit / at;
      alone[name] = {{"needed", needed}, {"check", Value(Alone(ev, name, needed, m))}};
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
std::vector<Sample> ReadSamplesCsv(const fs::path& path, const std::string& text, const ToleranceConfig& config) {
  std::istringstream in(text);
  std::string line;
  std::string header = SamplesCsv({}, true);
  header.pop_back();  // its newline
  HOVS_REQUIRE(std::getline(in, line) && line == header, path.string(),
               "not a tolerance samples file of this hovs (its header differs)");
  const size_t columns = static_cast<size_t>(std::count(line.begin(), line.end(), ',')) + 1;
  std::vector<Sample> samples;
  int row = 1;
  while (std::getline(in, line)) {
    ++row;
    std::vector<std::string> cells;
    std::stringstream cs(line);
    std::string cell;
    while (std::getline(cs, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    HOVS_REQUIRE(cells.size() == columns, path.string() + ":" + std::to_string(row), "has ", cells.size(),
                 " columns, the header ", columns);
    Sample s;
    char* end = nullptr;
    s.index = std::strtoll(cells[0].c_str(), &end, 10);
    HOVS_REQUIRE(!cells[0].empty() && *end == '\0' && s.index >= 0, path.string() + ":" + std::to_string(row),
                 "bad index '", cells[0], "'");
    for (int m = 0; m < kFigures; ++m) {
      const std::string& c = cells[cells.size() - kFigures + m];
      s.figures.values[m] = std::strtod(c.c_str(), &end);
      // "nan" is a failed figure (SampleFigures); anything else must be a finite number >= 0.
      HOVS_REQUIRE(*end == '\0' && !c.empty() &&
                       (c == "nan" || (std::isfinite(s.figures.values[m]) && s.figures.values[m] >= 0)),
                   path.string() + ":" + std::to_string(row), "bad value '", c, "'");
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
    for (const char* k : {"mean", "p50", "p90", "p95", "p99", "max"}) row.push_back(Shown(f[k]));
    row.push_back(std::to_string(f["failed"].get<int64_t>()));
    rows.push_back(row);
  }
  for (const auto& w : r["warnings"]) page.Paragraph("Warning: " + w.get<std::string>() + ".");
  page.Heading("Figures over the samples");
  page.Paragraph(
      "Statistics of the samples that evaluated the figure; 'failed' counts those that could not (less "
      "than 90 % of the figure's grid imaged): they count against every limit.");
  page.Table({"figure", "what", "mean", "p50", "p90", "p95", "p99", "max", "failed"}, rows);
  page.Heading("Sensitivity: each tolerance alone");
  rows.clear();
  for (const json& s : r["sensitivity"]) {
    std::vector<std::string> row = {s["parameter"], FormatNumber("%g", s["size"].get<double>()) + " " +
                                                        s["unit"].get<std::string>() + " (" +
                                                        s["distribution"].get<std::string>() + ")"};
    for (const Metric& m : Metrics()) row.push_back(Shown(s["figures"][m.name]["at_size"]));
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
                 (a.value("fails_at_size", false) ? std::string("fails at its tolerance")
                  : a["needed"].is_null()         ? std::string("any")
                                                  : FormatNumber("%.3g", a["needed"].get<double>()));
      rows.push_back({name, FormatNumber("%g", l["limit"].get<double>()), Shown(l["p95"]),
                      l["meets"].get<bool>() ? "yes" : "no",
                      l.contains("uniform_scale") ? FormatNumber("%.3g", l["uniform_scale"].get<double>()) + " (p95 " +
                                                        Shown(l["uniform_scale_check_p95"]) + ")"
                                                  : "-",
                      alone});
    }
    page.Table({"figure", "limit", "p95", "met", "every tolerance times (check)", "each alone at most"}, rows);
  }
  if (results::CanRender()) {
    fs::create_directories(dir / "figures");
    for (const Metric& m : Metrics()) {
      if (!r["figures"][m.name].contains("histogram")) continue;  // no sample evaluated the figure
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

std::vector<std::string> Warnings(const json& report) {
  std::vector<std::string> w;
  for (const auto& s : report["warnings"]) w.push_back(s.get<std::string>());
  return w;
}

// Samples of a shard re-evaluated at the merge (the first, the last and two between): a figure edited in a
// samples file, even one given a matching checksum again, does not merge. Figures agree to 1e-9 relative (the same
// binary on another CPU may round libm's last bits otherwise), a failed figure only with a failed one.
void CheckSamplesAgain(const ToleranceEvaluator& ev, const ToleranceConfig& config, const std::vector<Sample>& part,
                       const fs::path& file) {
  if (part.empty()) return;
  const size_t n = part.size();
  for (size_t i : {size_t(0), n / 3, 2 * n / 3, n - 1}) {
    const Sample& s = part[i];
    const SampleFigures again = ev.Evaluate(DrawErrors(config, s.index, 0), DrawErrors(config, s.index, 1));
    for (int m = 0; m < kFigures; ++m) {
      const double a = s.figures.values[m], b = again.values[m];
      const bool same =
          (s.figures.Failed(m) && again.Failed(m)) ||
          (!s.figures.Failed(m) && !again.Failed(m) && std::abs(a - b) <= 1e-9 * std::max(1.0, std::abs(b)));
      HOVS_REQUIRE(same, file.string(), "sample ", s.index, "'s ", Metrics()[m].name, " is ", FormatNumber("%.17g", a),
                   " but evaluates to ", FormatNumber("%.17g", b), ": the shard was edited or made by another hovs");
    }
  }
}

// The head of a tolerance study or shard (StudyHead), its fields checked: a malformed file is an error naming it
// and the key, not a JSON exception.
void CheckStudyHead(const json& j, const std::string& file) {
  HOVS_REQUIRE(j.is_object() && JsonText(j, "format") == "hovs-tolerance", file, "not a tolerance study");
  JsonInteger(j, "version", 1, 1, file);
  HOVS_REQUIRE(j.contains("config") && j["config"].is_object(), file + " (config)", "missing or not an object");
  for (const char* key : {"source", "text", "design_source", "design_text"})
    JsonString(j["config"], key, file + " (config)");
  HOVS_REQUIRE(j.contains("seed") && j["seed"].is_number_unsigned() && j["seed"].get<uint64_t>() <= (uint64_t(1) << 53),
               file + " (seed)", "must be an integer in [0, 2^53]");
  JsonInteger(j, "samples", 1, 10000000, file);
  HOVS_REQUIRE(j.contains("versions") && j["versions"].is_object(), file + " (versions)", "missing or not an object");
  for (const auto& [k, v] : j["versions"].items())
    HOVS_REQUIRE(v.is_string(), file + " (versions." + k + ")", "must be a string");
}

}  // namespace

std::vector<std::string> WriteToleranceStudy(const ToleranceConfig& config, int64_t count, int shard_index,
                                             int shard_count, const fs::path& out,
                                             const std::map<std::string, std::string>& versions, bool progress) {
  const std::vector<fs::path> inputs = {config.source, config.design.source};
  CheckOutputFolder(out, "tolerance", inputs);
  const std::vector<Sample> samples = RunSamples(config, count, shard_index, shard_count, progress);
  StagedDirectory stage(out, "tolerance", inputs);
  json study = StudyHead(config, count, versions);
  std::vector<std::string> warnings;
  if (shard_count > 1) {
    const std::string csv = SamplesCsv(samples, true);
    study["shard"] = {{"index", shard_index},
                      {"count", shard_count},
                      {"first", samples.front().index},
                      {"end", samples.back().index + 1},
                      {"samples_checksum", TextChecksum(csv)}};
    WriteFileAtomic(stage.staging() / "samples.csv", csv);
    WriteFileAtomic(stage.staging() / "tolerance.json", study.dump(1) + "\n");
    size_t failed = 0;
    for (const Sample& s : samples)
      for (int m = 0; m < kFigures; ++m) failed += s.figures.Failed(m) ? 1 : 0;
    if (failed > 0)
      warnings.push_back(std::to_string(failed) + " figures of this shard's " + std::to_string(samples.size()) +
                         " samples failed (tolerance.h SampleFigures); the merged report counts them");
  } else {
    WriteWhole(config, samples, study, stage.staging());
    warnings = Warnings(ReadJsonFile(stage.staging() / "tolerance.json")["report"]);
  }
  stage.Commit();
  return warnings;
}

bool IsToleranceFolder(const fs::path& dir) { return fs::is_regular_file(dir / "tolerance.json"); }

std::vector<std::string> MergeToleranceShards(const std::vector<fs::path>& shards, const fs::path& out) {
  HOVS_REQUIRE(!shards.empty(), "merge", "no shards given");
  std::vector<json> heads;
  std::vector<fs::path> inputs;
  for (const fs::path& dir : shards) {
    const fs::path file = dir / "tolerance.json";
    HOVS_REQUIRE(fs::is_regular_file(file), dir.string(), "not a tolerance study folder (no tolerance.json)");
    json j = ReadJsonFile(file);
    CheckStudyHead(j, file.string());
    HOVS_REQUIRE(j.contains("shard"), file.string(), "is not a shard (written without --shard)");
    heads.push_back(j), inputs.push_back(file);
  }
  const std::vector<size_t> order = OrderShards(heads, inputs);
  json ref = heads[0];
  ref.erase("shard");
  const int64_t total = ref["samples"].get<int64_t>();
  const int count = static_cast<int>(order.size());
  HOVS_REQUIRE(count <= total, "merge", count, " shards of a study of ", total, " samples");
  // The config as the study recorded it (the files may have moved or changed since), with the seed the study ran
  // with (hovs tolerance --seed overrides the config's).
  const json& c = ref["config"];
  const design::DesignConfig design =
      design::ParseDesignConfig(c["design_text"].get<std::string>(), c["design_source"].get<std::string>());
  ToleranceConfig config =
      ParseToleranceConfig(c["text"].get<std::string>(), c["source"].get<std::string>(), ".", &design);
  config.seed = ref["seed"].get<uint64_t>();
  const ToleranceEvaluator ev(config);
  std::vector<Sample> samples;
  for (int i = 0; i < count; ++i) {
    const size_t k = order[static_cast<size_t>(i)];
    const fs::path dir = shards[k], csv = dir / "samples.csv";
    const json& sh = heads[k]["shard"];
    const int64_t first = total * i / count, end = total * (i + 1) / count;
    HOVS_REQUIRE(sh.contains("first") && sh["first"] == first && sh.contains("end") && sh["end"] == end,
                 inputs[k].string() + " (shard)", "shard ", i, " of ", count, " holds samples ", first, "..", end,
                 ", not what the record says");
    const std::string text = ReadFile(csv);
    HOVS_REQUIRE(sh.contains("samples_checksum") && sh["samples_checksum"].is_string(), inputs[k].string() + " (shard)",
                 "has no samples_checksum: its samples cannot be verified");
    HOVS_REQUIRE(TextChecksum(text) == sh["samples_checksum"].get<std::string>(), csv.string(),
                 "does not match its checksum in ", inputs[k].string(), ": the file was changed or damaged");
    const auto part = ReadSamplesCsv(csv, text, config);
    HOVS_REQUIRE(static_cast<int64_t>(part.size()) == end - first, csv.string(), "holds ", part.size(),
                 " samples, not ", end - first);
    for (const Sample& s : part) {
      HOVS_REQUIRE(s.index == static_cast<int64_t>(samples.size()), csv.string(), "sample ", s.index,
                   " is out of order (expected ", samples.size(), ")");
      samples.push_back(s);
    }
    CheckSamplesAgain(ev, config, part, csv);
  }
  HOVS_REQUIRE(static_cast<int64_t>(samples.size()) == total, "merge", "the shards hold ", samples.size(),
               " samples but the study has ", total);
  CheckOutputFolder(out, "tolerance", inputs);
  StagedDirectory stage(out, "tolerance", inputs);
  WriteWhole(config, samples, ref, stage.staging());
  const auto warnings = Warnings(ReadJsonFile(stage.staging() / "tolerance.json")["report"]);
  stage.Commit();
  return warnings;
}

}  // namespace hovs::study
