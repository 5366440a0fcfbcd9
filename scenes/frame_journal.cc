#include "scenes/frame_journal.h"

#include <set>
#include <sstream>

#include "core/error.h"
#include "core/io.h"

namespace hovs::scenes {
namespace fs = std::filesystem;

namespace {

constexpr const char* kJournal = "frames.jsonl";

// The files a frame entry names: every view's image and ground truth.
std::vector<std::string> EntryFiles(const nlohmann::json& entry) {
  std::vector<std::string> files;
  for (const auto& v : entry.at("views")) {
    files.push_back(v.at("image").get<std::string>());
    if (v.contains("ground_truth"))
      for (const char* k : {"exr", "sidecar"})
        if (v["ground_truth"].contains(k)) files.push_back(v["ground_truth"][k].get<std::string>());
  }
  return files;
}

bool FilesMatch(const fs::path& dir, const nlohmann::json& entry) {
  if (!entry.contains("checksums") || !entry["checksums"].is_object()) return false;
  for (const auto& rel : EntryFiles(entry)) {
    std::error_code ec;
    if (!entry["checksums"].contains(rel) || !fs::is_regular_file(dir / rel, ec)) return false;
    if (FileChecksum(dir / rel) != entry["checksums"][rel]) return false;
  }
  return true;
}

}  // namespace

FrameJournal::FrameJournal(const fs::path& staging, const nlohmann::json& config, bool resumed,
                           const std::string& where)
    : dir_(staging), path_(staging / kJournal) {
  std::set<fs::path> keep = {dir_ / kOutputMarker};
  if (resumed && fs::is_regular_file(path_)) {
    std::istringstream in(ReadFile(path_));
    std::string line;
    bool header = true;
    while (std::getline(in, line)) {
      const auto j = nlohmann::json::parse(line, nullptr, false);
      if (j.is_discarded()) break;  // the line a kill cut short: its frame is redone
      if (header) {
        HOVS_REQUIRE(j == config, where,
                     "the interrupted run it would resume was made with another configuration (run without --resume "
                     "to start over)");
        header = false;
        continue;
      }
      try {
        if (FilesMatch(dir_, j)) {
          kept_[j.at("id").get<int64_t>()] = j;
          for (const auto& rel : EntryFiles(j)) keep.insert(dir_ / rel);
        }
      } catch (const nlohmann::json::exception&) {
        // a malformed entry: its frame is redone
      } catch (const Error&) {}
    }
  }
  // Everything else the earlier run left (the frame it was writing when it was killed) goes.
  if (resumed) {
    std::vector<fs::path> stale;
    for (const auto& e : fs::recursive_directory_iterator(dir_))
      if (e.is_regular_file() && !keep.count(e.path())) stale.push_back(e.path());
    for (const auto& p : stale) fs::remove(p);
  }
  out_.open(path_, std::ios::trunc);
  HOVS_REQUIRE(out_.good(), path_.string(), "cannot write the journal");
  out_ << config.dump() << "\n";
  for (const auto& [id, e] : kept_) out_ << e.dump() << "\n";
  out_.flush();
}

std::optional<nlohmann::json> FrameJournal::Kept(int64_t id) const {
  const auto it = kept_.find(id);
  if (it == kept_.end()) return std::nullopt;
  return it->second;
}

nlohmann::json FrameChecksums(const fs::path& dir, const nlohmann::json& entry) {
  nlohmann::json sums = nlohmann::json::object();
  for (const auto& rel : EntryFiles(entry)) sums[rel] = FileChecksum(dir / rel);
  return sums;
}

void FrameJournal::Record(nlohmann::json* entry) {
  (*entry)["checksums"] = FrameChecksums(dir_, *entry);
  out_ << entry->dump() << "\n";
  out_.flush();
  HOVS_REQUIRE(out_.good(), path_.string(), "cannot write the journal");
}

void FrameJournal::Finish() {
  out_.close();
  fs::remove(path_);
}

}  // namespace hovs::scenes
