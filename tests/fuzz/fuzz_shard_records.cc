// Shard records (the "shard" objects of dataset, design and tolerance shards) and the I/N text of --shard: a
// record is ordered with itself and with a copy given the other index, as a merge does (core/shard_set.h).
#include "core/json.h"
#include "core/shard_set.h"
#include "tests/fuzz/fuzz_common.h"

namespace {

void Run(const std::string& input) {
  int index = 0, count = 0;
  try {
    hovs::ParseShardSpec(input.substr(0, input.find('\n')), "--shard", &index, &count);
  } catch (const hovs::Error&) {}
  const nlohmann::json doc = hovs::ParseJson(input, "shard.json");
  try {
    hovs::OrderShards({doc}, {"shard.json"}, {"frames", "rows"});
  } catch (const hovs::Error&) {}
  nlohmann::json other = doc;
  if (other.is_object() && other.contains("shard") && other["shard"].is_object()) other["shard"]["index"] = 1;
  hovs::OrderShards({doc, other}, {"a.json", "b.json"}, {"frames", "rows"});
}

}  // namespace

HOVS_FUZZ_TARGET(Run)
