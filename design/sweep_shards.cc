// Shards of a design sweep and their merge (design/study.h).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/io.h"
#include "core/json.h"
#include "core/shard_set.h"
#include "design/study.h"

namespace hovs::design {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* const kShardFile = "design-shard.json";

// The sweep's arrays by name, in one order (the shard file's keys).
std::vector<std::pair<const char*, std::vector<double>*>> Arrays(SweepResult* s) {
  return {{"upper_deg", &s->upper_deg}, {"lower_deg", &s->lower_deg},         {"field_deg", &s->field_deg},
          {"rim_px", &s->rim_px},       {"system_length", &s->system_length}, {"objective", &s->objective}};
}

size_t Rows(const SweepSpec& spec) { return static_cast<size_t>(spec.nb) * spec.nd; }

// Values [begin, begin + n) of a merged sweep against the same row evaluated again: equal to 1e-9 relative (the
// same binary on another CPU may round libm's last bits otherwise), NaN only where NaN, the same constraints.
void CheckRowAgain(SweepResult* merged, SweepResult* again, size_t begin, size_t n, const std::string& file) {
  const auto ours = Arrays(merged), theirs = Arrays(again);
  for (size_t a = 0; a < ours.size(); ++a)
    for (size_t i = begin; i < begin + n; ++i) {
      const double x = (*ours[a].second)[i], y = (*theirs[a].second)[i];
      const bool same = (std::isnan(x) && std::isnan(y)) || std::abs(x - y) <= 1e-9 * std::max(1.0, std::abs(y));
      HOVS_REQUIRE(same, file, "'rows.", ours[a].first, "' holds ", x, " where the design evaluates to ", y,
                   ": the shard was edited or made by another hovs");
    }
  for (size_t i = begin; i < begin + n; ++i)
    HOVS_REQUIRE(merged->violated[i] == again->violated[i], file,
                 "'rows.violated' differs from the design's evaluation: the shard was edited or made by another hovs");
}

}  // namespace

void WriteDesignShard(const DesignConfig& config, int shard_index, int shard_count, const fs::path& out,
                      const std::map<std::string, std::string>& versions) {
  HOVS_REQUIRE(config.family.empty(), config.source, "a turret family study cannot be sharded (shard the config of ",
               "one design)");
  const size_t rows = Rows(config.sweep);
  HOVS_REQUIRE(
      shard_count >= 1 && static_cast<size_t>(shard_count) <= rows && shard_index >= 0 && shard_index < shard_count,
      "--shard", "needs 0 <= index < shards <= the sweep's ", rows, " rows (got ", shard_index, " of ", shard_count,
      ")");
  const size_t first = rows * shard_index / shard_count, end = rows * (shard_index + 1) / shard_count;
  CheckOutputFolder(out, "design", {config.source});
  SweepResult s = SweepRows(config.problem, config.sweep, first, end);
  StagedDirectory stage(out, "design", {config.source});
  json j;
  j["format"] = "hovs-design-shard";
  j["version"] = 1;
  j["config"] = {{"source", config.source}, {"text", config.text}};
  j["versions"] = versions;
  const size_t na = static_cast<size_t>(config.sweep.na);
  for (auto& [name, values] : Arrays(&s))
    j["rows"][name] = std::vector<double>(values->begin() + first * na, values->begin() + end * na);
  j["rows"]["violated"] = std::vector<uint32_t>(s.violated.begin() + first * na, s.violated.begin() + end * na);
  j["shard"] = {{"index", shard_index},
                {"count", shard_count},
                {"row_first", first},
                {"row_end", end},
                {"rows_checksum", TextChecksum(j["rows"].dump())}};
  WriteFileAtomic(stage.staging() / kShardFile, j.dump() + "\n");
  stage.Commit();
}

bool IsDesignShard(const fs::path& dir) { return fs::is_regular_file(dir / kShardFile); }

std::string MergeDesignShards(const std::vector<fs::path>& shards, const fs::path& out) {
  HOVS_REQUIRE(!shards.empty(), "merge", "no shards given");
  std::vector<json> parts;
  std::vector<fs::path> inputs;
  for (const fs::path& dir : shards) {
    const fs::path file = dir / kShardFile;
    HOVS_REQUIRE(fs::is_regular_file(file), dir.string(), "not a design sweep shard (no ", kShardFile, ")");
    parts.push_back(ReadJsonFile(file)), inputs.push_back(file);
    HOVS_REQUIRE(parts.back().value("format", "") == "hovs-design-shard", file.string(), "not a design sweep shard");
  }
  for (size_t k = 0; k < parts.size(); ++k) {
    const std::string file = inputs[k].string();
    HOVS_REQUIRE(parts[k].contains("config") && parts[k]["config"].is_object(), file + " (config)",
                 "missing or not an object");
    JsonString(parts[k]["config"], "text", file + " (config)");
    JsonString(parts[k]["config"], "source", file + " (config)");
    HOVS_REQUIRE(parts[k].contains("rows") && parts[k]["rows"].is_object(), file + " (rows)",
                 "missing or not an object");
  }
  const std::vector<size_t> order = OrderShards(parts, inputs, {"rows"});
  const json& ref = parts[0];
  const int count = static_cast<int>(order.size());
  const DesignConfig config =
      ParseDesignConfig(ref["config"]["text"].get<std::string>(), ref["config"]["source"].get<std::string>());
  const size_t rows = Rows(config.sweep), na = static_cast<size_t>(config.sweep.na);
  HOVS_REQUIRE(static_cast<size_t>(count) <= rows, "merge", count, " shards of a sweep of ", rows, " rows");
  SweepResult sweep = SweepRows(config.problem, config.sweep, 0, 0);  // the grid, no values yet
  size_t next = 0;
  for (int i = 0; i < count; ++i) {
    const size_t k = order[static_cast<size_t>(i)];
    const std::string file = inputs[k].string();
    const json& sh = parts[k]["shard"];
    // The rows this shard must hold (WriteDesignShard's split), and its record's checksum of them.
    const size_t first = rows * i / count, end = rows * (i + 1) / count;
    HOVS_REQUIRE(sh.contains("row_first") && sh["row_first"] == first && sh.contains("row_end") && sh["row_end"] == end,
                 file + " (shard)", "shard ", i, " of ", count, " holds rows ", first, "..", end,
                 ", not what the record says");
    const json& r = parts[k]["rows"];
    HOVS_REQUIRE(sh.contains("rows_checksum") && sh["rows_checksum"].is_string() &&
                     sh["rows_checksum"].get<std::string>() == TextChecksum(r.dump()),
                 file, "its rows do not match the shard's rows_checksum: the file was changed or damaged");
    const size_t n = (end - first) * na;
    for (auto& [name, values] : Arrays(&sweep)) {
      const auto part = JsonNumbers(r, name, n, n, file + " (rows)");
      std::copy(part.begin(), part.end(), values->begin() + first * na);
    }
    HOVS_REQUIRE(r.contains("violated") && r["violated"].is_array() && r["violated"].size() == n, file,
                 "'rows.violated' must hold ", n, " values");
    for (size_t v = 0; v < n; ++v) {
      HOVS_REQUIRE(r["violated"][v].is_number_unsigned() && r["violated"][v].get<uint64_t>() <= UINT32_MAX, file,
                   "'rows.violated' holds a value that is not a constraint mask");
      sweep.violated[first * na + v] = r["violated"][v].get<uint32_t>();
    }
    // The shard's first row evaluated again: an edited value does not merge even with its checksum made again.
    if (end > first) {
      SweepResult again = SweepRows(config.problem, config.sweep, first, first + 1);
      CheckRowAgain(&sweep, &again, first * na, na, file);
    }
    next = end;
  }
  HOVS_REQUIRE(next == rows, "merge", "the shards hold ", next, " of the sweep's ", rows, " rows");
  CheckOutputFolder(out, "design", inputs);
  return WriteDesignReport(config, RunDesignStudy(config, std::move(sweep), 0.0), out);
}

}  // namespace hovs::design
