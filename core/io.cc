#include "core/io.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace hovs {
namespace fs = std::filesystem;

namespace {
std::string UniqueSuffix() {
  static std::atomic<int> counter{0};
  const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
  return std::to_string(::getpid()) + "-" + std::to_string(now) + "-" + std::to_string(counter++);
}
}  // namespace

void WriteFileAtomic(const fs::path& path, const std::string& content) {
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  HOVS_REQUIRE(!ec, parent.string(), "cannot create folder: ", ec.message());
  const fs::path tmp = parent / ("." + path.filename().string() + ".tmp-" + UniqueSuffix());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    HOVS_REQUIRE(out.good(), tmp.string(), "cannot open for writing");
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out.good()) {
      out.close();
      fs::remove(tmp, ec);
      throw Error(path.string(), "write failed (disk full?)");
    }
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ec2;
    fs::remove(tmp, ec2);
    throw Error(path.string(), "cannot rename into place: " + ec.message());
  }
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  HOVS_REQUIRE(in.good(), path.string(), "cannot open for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<fs::path> ListImageFiles(const fs::path& folder) {
  HOVS_REQUIRE(fs::is_directory(folder), folder.string(), "not a folder");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    for (const char* x : {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".bmp", ".pgm"})
      if (ext == x) files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  HOVS_REQUIRE(!files.empty() || !fs::is_regular_file(folder / "dataset.json"), folder.string(),
               "the folder holds no images but a dataset manifest: give ", (folder / "dataset.json").string());
  HOVS_REQUIRE(!files.empty(), folder.string(), "the folder holds no images (png, jpg, tif, exr, bmp, pgm)");
  return files;
}

namespace {

// The hidden siblings of an output folder <name>: its staging folder while a run writes it, and the previous
// output moved aside during Commit. Both end in -<pid>-<time>-<count> (UniqueSuffix).
constexpr const char* kStagingTag = ".partial-";
constexpr const char* kOldTag = ".old-";
fs::path HiddenSibling(const fs::path& parent, const std::string& name, const char* tag) {
  return parent / ("." + name + tag + UniqueSuffix());
}

// Removes what earlier runs for the same target left behind when they were killed before their destructor ran
// (Ctrl-C, a crash): hidden siblings .<name>.partial-<pid>-... and .<name>.old-<pid>-... whose process no longer
// exists. A folder of a live process (another run writing the same target now) is left alone.
void RemoveStaleStaging(const fs::path& parent, const std::string& name) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(parent, ec)) {
    const std::string f = e.path().filename().string();
    for (const char* tag : {kStagingTag, kOldTag}) {
      const std::string prefix = "." + name + tag;
      if (f.rfind(prefix, 0) != 0) continue;
      const size_t end = f.find('-', prefix.size());
      const std::string digits = f.substr(prefix.size(), end == std::string::npos ? std::string::npos : end - prefix.size());
      if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) continue;
      const pid_t pid = static_cast<pid_t>(std::stol(digits));
      if (pid > 0 && ::kill(pid, 0) != 0 && errno == ESRCH) {
        std::error_code ignore;
        fs::remove_all(e.path(), ignore);
      }
    }
  }
}

}  // namespace

StagedDirectory::StagedDirectory(fs::path target) : target_(std::move(target)) {
  HOVS_REQUIRE(!target_.empty(), "output folder", "empty path");
  if (target_.filename().empty()) target_ = target_.parent_path();
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  HOVS_REQUIRE(!ec, parent.string(), "cannot create folder: ", ec.message());
  RemoveStaleStaging(parent, target_.filename().string());
  staging_ = HiddenSibling(parent, target_.filename().string(), kStagingTag);
  fs::create_directory(staging_, ec);
  HOVS_REQUIRE(!ec, staging_.string(), "cannot create staging folder: ", ec.message());
}

StagedDirectory::~StagedDirectory() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
  }
}

void StagedDirectory::Commit() {
  std::error_code ec;
  fs::path old;
  if (fs::exists(target_)) {
    old = HiddenSibling(target_.parent_path(), target_.filename().string(), kOldTag);
    fs::rename(target_, old, ec);
    HOVS_REQUIRE(!ec, target_.string(), "cannot move the previous output aside: ", ec.message());
  }
  fs::rename(staging_, target_, ec);
  if (ec) {
    if (!old.empty()) {
      std::error_code ec2;
      fs::rename(old, target_, ec2);
    }
    throw Error(target_.string(), "cannot move the finished output into place: " + ec.message());
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

}  // namespace hovs
