// Sharded runs: the I/N text of --shard, and the shards of one run as their JSON records (each with "shard":
// {"index", "count", ...}), checked to belong together and put in shard order. Used by every command that takes
// --shard and by every merge (datasets, design sweeps, tolerance studies).
#pragma once

#include <charconv>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace hovs {

// The most shards a run is cut into (Slurm's array indices stay far below this).
inline constexpr int kMaxShards = 100000;

// "I/N" with 0 <= I < N <= kMaxShards, digits only (no sign, no space, no wrap-around of large numbers). Throws
// hovs::Error(where) otherwise.
inline void ParseShardSpec(const std::string& text, const std::string& where, int* index, int* count) {
  const size_t slash = text.find('/');
  const auto number = [&](const std::string& part, int* out) {
    const bool digits = !part.empty() && part.size() <= 9 && part.find_first_not_of("0123456789") == std::string::npos;
    HOVS_REQUIRE(digits, where, "expected I/N (shard I from 0 of N, each 0..", kMaxShards, "), got '", text, "'");
    std::from_chars(part.data(), part.data() + part.size(), *out);
  };
  HOVS_REQUIRE(slash != std::string::npos, where, "expected I/N (shard I from 0 of N), got '", text, "'");
  number(text.substr(0, slash), index);
  number(text.substr(slash + 1), count);
  HOVS_REQUIRE(*count >= 1 && *count <= kMaxShards && *index < *count, where, "needs 0 <= I < N <= ", kMaxShards,
               " (got ", text, ")");
}

// A shard record's "index" and "count", checked (integers, 0 <= index < count <= kMaxShards); `file` names it.
inline void ReadShardRecord(const nlohmann::json& doc, const std::string& file, int* index, int* count) {
  HOVS_REQUIRE(doc.is_object() && doc.contains("shard") && doc["shard"].is_object(), file,
               "is not a shard (no \"shard\" record; written without --shard?)");
  const nlohmann::json& s = doc["shard"];
  const auto integer = [&](const char* key) {
    HOVS_REQUIRE(s.contains(key) && s[key].is_number_integer() && s[key].get<int64_t>() >= 0 &&
                     s[key].get<int64_t>() <= kMaxShards,
                 file + " (shard." + key + ")", "must be an integer in 0..", kMaxShards);
    return static_cast<int>(s[key].get<int64_t>());
  };
  *index = integer("index"), *count = integer("count");
  HOVS_REQUIRE(*count >= 1 && *index < *count, file + " (shard)", "needs 0 <= index < count (got ", *index, " of ",
               *count, ")");
}

// docs[k] read from files[k]. Every key but "shard" and those in `own` (a shard's own data) must equal the first
// record's; the indices must be those of one count, each once. Returns, for shard i = 0 .. count - 1, its position
// in docs. Throws hovs::Error naming the file that does not belong (and the keys that differ), a malformed shard
// record, a shard given twice, or the shard that is missing.
inline std::vector<size_t> OrderShards(const std::vector<nlohmann::json>& docs,
                                       const std::vector<std::filesystem::path>& files,
                                       const std::vector<std::string>& own = {}) {
  HOVS_REQUIRE(!docs.empty() && docs.size() == files.size(), "merge", "no shards given");
  const auto head = [&](nlohmann::json j) {
    j.erase("shard");
    for (const auto& k : own) j.erase(k);
    return j;
  };
  int first_index = 0, count = 0;
  ReadShardRecord(docs[0], files[0].string(), &first_index, &count);  // before head(): docs[0] is an object
  const nlohmann::json ref = head(docs[0]);
  std::vector<int> index_of(docs.size());
  std::set<int> seen;
  for (size_t k = 0; k < docs.size(); ++k) {
    int index = 0, n = 0;
    ReadShardRecord(docs[k], files[k].string(), &index, &n);
    const nlohmann::json h = head(docs[k]);
    if (h != ref) {
      std::string differ;
      int differing = 0;
      for (const auto& [key, value] : ref.items())
        if (!h.contains(key) || h[key] != value) differ += (differing++ ? ", " : "") + key;
      for (const auto& [key, value] : h.items())
        if (!ref.contains(key)) differ += (differing++ ? ", " : "") + key;
      throw Error(files[k].string(), "does not belong with " + files[0].string() + ": its " + differ +
                                         (differing == 1 ? " differs" : " differ"));
    }
    HOVS_REQUIRE(n == count, files[k].string(), "is shard ", index, " of ", n, ", the first of ", count);
    if (!seen.insert(index).second) {
      size_t other = 0;
      while (index_of[other] != index) ++other;
      throw Error(files[k].string(),
                  "is shard " + std::to_string(index) + ", given twice (also " + files[other].string() + ")");
    }
    index_of[k] = index;
  }
  for (int i = 0; i < count; ++i) HOVS_REQUIRE(seen.count(i), "merge", "shard ", i, " of ", count, " is missing");
  std::vector<size_t> order(static_cast<size_t>(count));
  for (size_t k = 0; k < docs.size(); ++k) order[static_cast<size_t>(index_of[k])] = k;
  return order;
}

}  // namespace hovs
