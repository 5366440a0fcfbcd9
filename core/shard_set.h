// The shards of one sharded run, as their JSON records (each with "shard": {"index", "count"}): checked to belong
// together and put in shard order. Used by every merge (datasets, design sweeps, tolerance studies).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/error.h"

namespace hovs {

// docs[k] read from files[k]. Every key but "shard" and those in `own` (a shard's own data) must equal the first
// record's; the indices must be those of one count, each once. Returns, for shard i = 0 .. count - 1, its position
// in docs. Throws hovs::Error naming the file that does not belong (and the keys that differ), a shard given twice,
// or the shard that is missing.
inline std::vector<size_t> OrderShards(const std::vector<nlohmann::json>& docs,
                                       const std::vector<std::filesystem::path>& files,
                                       const std::vector<std::string>& own = {}) {
  HOVS_REQUIRE(!docs.empty() && docs.size() == files.size(), "merge", "no shards given");
  const auto head = [&](nlohmann::json j) {
    j.erase("shard");
    for (const auto& k : own) j.erase(k);
    return j;
  };
  const nlohmann::json ref = head(docs[0]);
  const int count = docs[0]["shard"]["count"].get<int>();
  std::vector<int> seen(static_cast<size_t>(std::max(count, 0)), -1);
  for (size_t k = 0; k < docs.size(); ++k) {
    const nlohmann::json h = head(docs[k]);
    if (h != ref) {
      std::string differ;
      for (const auto& [key, value] : ref.items())
        if (!h.contains(key) || h[key] != value) differ += (differ.empty() ? "" : ", ") + key;
      throw Error(files[k].string(), "does not belong with " + files[0].string() + ": its " + differ + " differ");
    }
    const int index = docs[k]["shard"]["index"].get<int>(), n = docs[k]["shard"]["count"].get<int>();
    HOVS_REQUIRE(n == count && index >= 0 && index < count, files[k].string(), "is shard ", index, " of ", n,
                 ", the first of ", count);
    HOVS_REQUIRE(seen[static_cast<size_t>(index)] < 0, files[k].string(), "is shard ", index, ", given twice (also ",
                 files[static_cast<size_t>(seen[static_cast<size_t>(index)])].string(), ")");
    seen[static_cast<size_t>(index)] = static_cast<int>(k);
  }
  std::vector<size_t> order;
  for (int i = 0; i < count; ++i) {
    HOVS_REQUIRE(seen[static_cast<size_t>(i)] >= 0, "merge", "shard ", i, " of ", count, " is missing");
    order.push_back(static_cast<size_t>(seen[static_cast<size_t>(i)]));
  }
  return order;
}

}  // namespace hovs
