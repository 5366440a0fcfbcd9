// Shards of a design sweep and their merge (design/study.h).
#include <nlohmann/json.hpp>

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
  j["shard"] = {{"index", shard_index}, {"count", shard_count}, {"row_first", first}, {"row_end", end}};
  const size_t na = static_cast<size_t>(config.sweep.na);
  for (auto& [name, values] : Arrays(&s))
    j["rows"][name] = std::vector<double>(values->begin() + first * na, values->begin() + end * na);
  j["rows"]["violated"] = std::vector<uint32_t>(s.violated.begin() + first * na, s.violated.begin() + end * na);
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
  const std::vector<size_t> order = OrderShards(parts, inputs, {"rows"});
  const json& ref = parts[0];
  const int count = static_cast<int>(order.size());
  const DesignConfig config =
      ParseDesignConfig(ref["config"]["text"].get<std::string>(), ref["config"]["source"].get<std::string>());
  const size_t rows = Rows(config.sweep), na = static_cast<size_t>(config.sweep.na);
  SweepResult sweep = SweepRows(config.problem, config.sweep, 0, 0);  // the grid, no values yet
  size_t next = 0;
  for (int i = 0; i < count; ++i) {
    const size_t k = order[static_cast<size_t>(i)];
    const json& sh = parts[k]["shard"];
    const size_t first = sh["row_first"].get<size_t>(), end = sh["row_end"].get<size_t>();
    HOVS_REQUIRE(first == next && end >= first && end <= rows, inputs[k].string(), "holds rows ", first, "..", end,
                 " where rows from ", next, " were expected");
    const json& r = parts[k]["rows"];
    const size_t n = (end - first) * na;
    for (auto& [name, values] : Arrays(&sweep)) {
      const auto part = r.at(name).get<std::vector<double>>();
      HOVS_REQUIRE(part.size() == n, inputs[k].string(), "'", name, "' holds ", part.size(), " values, not ", n);
      std::copy(part.begin(), part.end(), values->begin() + first * na);
    }
    const auto violated = r.at("violated").get<std::vector<uint32_t>>();
    HOVS_REQUIRE(violated.size() == n, inputs[k].string(), "'violated' holds ", violated.size(), " values, not ", n);
    std::copy(violated.begin(), violated.end(), sweep.violated.begin() + first * na);
    next = end;
  }
  HOVS_REQUIRE(next == rows, "merge", "the shards hold ", next, " of the sweep's ", rows, " rows");
  CheckOutputFolder(out, "design", inputs);
  return WriteDesignReport(config, RunDesignStudy(config, std::move(sweep), 0.0), out);
}

}  // namespace hovs::design
