// The journal of a dataset run (staging/frames.jsonl), which makes an interrupted run resumable: a header line with
// the run's configuration, then one line per frame written whole, its manifest entry with the checksum of every
// file it names (core/io.h FileChecksum). A resumed run (hovs dataset --resume) keeps the frames whose files still
// match, removes every other file (what the killed frame left half-written) and renders the rest; the result is
// the set an uninterrupted run writes.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

namespace hovs::scenes {

// The "checksums" of a manifest frame entry: {relative path: FileChecksum} of every file its views name (image,
// ground-truth EXR and sidecar), under dir. Every hovs writer of a manifest records them (core/manifest.h: the
// readers verify them).
nlohmann::json FrameChecksums(const std::filesystem::path& dir, const nlohmann::json& entry);

class FrameJournal {
 public:
  // config: what must be equal for frames to be kept (the manifest's head and generator, the shard). resumed: the
  // staging folder holds an earlier run's files. Throws hovs::Error naming `where` when the earlier run had
  // another configuration.
  FrameJournal(const std::filesystem::path& staging, const nlohmann::json& config, bool resumed,
               const std::string& where);
  // The entry of frame `id` when the earlier run wrote it whole and its files still match.
  std::optional<nlohmann::json> Kept(int64_t id) const;
  // Adds the checksums of the entry's files ("checksums": {relative path: checksum}) and appends it.
  void Record(nlohmann::json* entry);
  size_t kept() const { return kept_.size(); }
  // Removes the journal (the manifest holds the checksums).
  void Finish();

 private:
  std::filesystem::path dir_, path_;
  std::map<int64_t, nlohmann::json> kept_;
  std::ofstream out_;
};

}  // namespace hovs::scenes
