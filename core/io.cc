#include "core/io.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/json.h"
#include "core/version.h"

namespace hovs {
namespace fs = std::filesystem;

namespace {
std::string UniqueSuffix() {
  static std::atomic<int> counter{0};
  const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
  return std::to_string(::getpid()) + "-" + std::to_string(now) + "-" + std::to_string(counter++);
}

std::mutex g_inputs_mutex;
std::vector<fs::path>& Inputs() {
  static std::vector<fs::path> inputs;
  return inputs;
}
struct Expected {
  std::string checksum, record;
};
std::map<fs::path, Expected>& ExpectedChecksums() {  // by resolved path; under g_inputs_mutex
  static std::map<fs::path, Expected> expected;
  return expected;
}

// The absolute, normalised form of a path whose last parts may not exist (symbolic links resolved where they
// do), for comparing places.
fs::path Resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
  if (ec) r = fs::absolute(p).lexically_normal();
  return r;
}

// Whether `inner` is `outer` or lies below it (both resolved).
bool Within(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin(), o = outer.begin();
  for (; o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // a trailing separator
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}
}  // namespace

void NoteInput(const fs::path& path) {
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  Inputs().push_back(path);
}

void ClearNotedInputs() {
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  Inputs().clear();
  ExpectedChecksums().clear();
}

void ExpectChecksum(const fs::path& path, const std::string& checksum, const std::string& record) {
  const fs::path r = Resolved(path);
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  ExpectedChecksums()[r] = {checksum, record};
}

namespace {
std::optional<Expected> ExpectedFor(const fs::path& path) {
  const fs::path r = Resolved(path);
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  const auto it = ExpectedChecksums().find(r);
  if (it == ExpectedChecksums().end()) return std::nullopt;
  return it->second;
}
void RequireMatch(const fs::path& path, const Expected& e, const std::string& actual) {
  HOVS_REQUIRE(actual == e.checksum, path.string(), "does not match its checksum in ", e.record, " (", actual,
               ", recorded ", e.checksum, "): the file was changed or damaged after it was written");
}
}  // namespace

void VerifyExpectedChecksum(const fs::path& path) {
  if (const auto e = ExpectedFor(path)) RequireMatch(path, *e, FileChecksum(path));
}

void VerifyExpectedChecksum(const fs::path& path, const std::string& bytes) {
  if (const auto e = ExpectedFor(path)) RequireMatch(path, *e, TextChecksum(bytes));
}

std::vector<fs::path> NotedInputs() {
  std::lock_guard<std::mutex> lock(g_inputs_mutex);
  return Inputs();
}

void WriteFileAtomic(const fs::path& path, const std::string& content) {
  const fs::path parent = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  HOVS_REQUIRE(!ec, parent.string(), "cannot create folder: ", ec.message());
  HOVS_REQUIRE(!fs::is_directory(path, ec), path.string(), "is a folder; a file was to be written there");
  const fs::path tmp = parent / ("." + path.filename().string() + ".tmp-" + UniqueSuffix());
  RegisterForCleanup(tmp);
  const auto fail = [&](const std::string& what) {
    std::error_code ignore;
    fs::remove(tmp, ignore);
    UnregisterCleanup(tmp);
    throw Error(path.string(), what);
  };
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out.good()) fail("cannot open for writing (" + std::string(std::strerror(errno)) + ")");
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out.good()) fail("write failed (disk full?)");
  }
  fs::rename(tmp, path, ec);
  if (ec) fail("cannot rename into place: " + ec.message());
  UnregisterCleanup(tmp);
}

void RequireFile(const fs::path& path, const std::string& what) {
  std::error_code ec;
  const auto st = fs::status(path, ec);
  HOVS_REQUIRE(fs::exists(st), path.string(), what == "a file" ? std::string("file") : what, " not found");
  HOVS_REQUIRE(!fs::is_directory(st), path.string(), "is a folder, not ", what);
  HOVS_REQUIRE(fs::is_regular_file(st), path.string(), "is not a regular file");
}

std::string ReadFile(const fs::path& path, size_t max_bytes) {
  RequireFile(path);
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  HOVS_REQUIRE(!ec, path.string(), "cannot read: ", ec.message());
  HOVS_REQUIRE(size <= max_bytes, path.string(), "is ", size, " bytes; at most ", max_bytes, " are read");
  std::ifstream in(path, std::ios::binary);
  HOVS_REQUIRE(in.good(), path.string(), "cannot open for reading");
  NoteInput(path);
  std::string data(size, '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  HOVS_REQUIRE(static_cast<size_t>(in.gcount()) == size, path.string(), "read failed");
  VerifyExpectedChecksum(path, data);
  return data;
}

std::string NormalisedText(const std::string& text) {
  const size_t start = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  std::string out;
  out.reserve(text.size() - start);
  for (size_t i = start; i < text.size(); ++i) {
    if (text[i] != '\r') {
      out += text[i];
    } else {
      out += '\n';
      if (i + 1 < text.size() && text[i + 1] == '\n') ++i;
    }
  }
  return out;
}

std::vector<fs::path> ListImageFiles(const fs::path& folder) {
  HOVS_REQUIRE(fs::is_directory(folder), folder.string(), "not a folder");
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    for (const char* x : {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".bmp", ".pgm"})
      if (ext == x) files.push_back(e.path());
  }
  HOVS_REQUIRE(!ec, folder.string(), "cannot list the folder: ", ec.message());
  std::sort(files.begin(), files.end());
  HOVS_REQUIRE(!files.empty() || !fs::is_regular_file(folder / "dataset.json"), folder.string(),
               "the folder holds no images but a dataset manifest: give ", (folder / "dataset.json").string());
  HOVS_REQUIRE(!files.empty(), folder.string(), "the folder holds no images (png, jpg, tif, exr, bmp, pgm)");
  return files;
}

fs::path ContainedPath(const fs::path& root, const std::string& relative, const std::string& where) {
  HOVS_REQUIRE(!relative.empty(), where, "empty path");
  HOVS_REQUIRE(relative.find('\0') == std::string::npos, where, "the path holds a NUL character");
  const fs::path rel(relative);
  HOVS_REQUIRE(rel.is_relative() && !rel.has_root_name() && !rel.has_root_directory(), where, "the path '", relative,
               "' is absolute; paths in the file are relative to its folder");
  for (const auto& part : rel)
    HOVS_REQUIRE(part != "..", where, "the path '", relative, "' leaves the file's folder ('..')");
  return root / rel;
}

namespace {

// The hidden siblings of an output folder <name>: its staging folder while a run writes it, and the previous
// output moved aside during Commit. Both end in -<pid>-<time>-<count> (UniqueSuffix).
constexpr const char* kStagingTag = ".partial-";
constexpr const char* kOldTag = ".old-";
fs::path HiddenSibling(const fs::path& parent, const std::string& name, const char* tag) {
  return parent / ("." + name + tag + UniqueSuffix());
}

// What earlier runs for the same target left behind when they were killed before their destructor ran (a
// crash, SIGKILL): hidden siblings .<name>.partial-<pid>-... and .<name>.old-<pid>-... whose process no longer
// exists. A folder of a live process (another run writing the same target now) is left alone. Staging folders
// are removed, or with `keep` renamed to <name>.interrupted-<pid>; old outputs are removed (their replacement
// was committed).
// The pid in a hidden sibling's name (.<name><tag><pid>-...), when the sibling is one and its process is gone.
std::optional<pid_t> DeadSiblingPid(const std::string& f, const std::string& name, const char* tag) {
  const std::string prefix = "." + name + tag;
  if (f.rfind(prefix, 0) != 0) return std::nullopt;
  const size_t end = f.find('-', prefix.size());
  const std::string digits =
      f.substr(prefix.size(), end == std::string::npos ? std::string::npos : end - prefix.size());
  if (digits.empty() || digits.size() > 9 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return std::nullopt;
  const pid_t pid = static_cast<pid_t>(std::stol(digits));
  if (pid <= 0 || ::kill(pid, 0) == 0 || errno != ESRCH) return std::nullopt;
  return pid;
}

void CleanStaleStaging(const fs::path& parent, const std::string& name, bool keep) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(parent, ec)) {
    const std::string f = e.path().filename().string();
    for (const char* tag : {kStagingTag, kOldTag}) {
      const auto pid = DeadSiblingPid(f, name, tag);
      if (!pid) continue;
      std::error_code ignore;
      if (keep && tag == kStagingTag) {
        fs::rename(e.path(), parent / (name + ".interrupted-" + std::to_string(*pid)), ignore);
        if (!ignore) continue;
      }
      fs::remove_all(e.path(), ignore);
    }
  }
}

std::string MarkerCommand(const fs::path& folder);

// The newest staging folder a killed run of `command` left for parent/name, or nothing.
std::optional<fs::path> NewestDeadStaging(const fs::path& parent, const std::string& name, const std::string& command) {
  std::error_code ec;
  std::optional<fs::path> best;
  fs::file_time_type best_time;
  for (const auto& e : fs::directory_iterator(parent, ec)) {
    if (!DeadSiblingPid(e.path().filename().string(), name, kStagingTag) || MarkerCommand(e.path()) != command)
      continue;
    const auto t = fs::last_write_time(e.path(), ec);
    if (ec) continue;
    if (!best || t > best_time) best = e.path(), best_time = t;
  }
  return best;
}

std::string MarkerText(const std::string& command) {
  return nlohmann::json{{"format", "hovs-output"}, {"command", command}, {"hovs", HovsVersion()}}.dump(1) + "\n";
}

// The command named by a folder's marker, or "" when it has none (or an unreadable one).
std::string MarkerCommand(const fs::path& folder) {
  std::error_code ec;
  const fs::path m = folder / kOutputMarker;
  if (!fs::is_regular_file(m, ec) || fs::file_size(m, ec) > 4096) return "";
  std::ifstream in(m, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  const auto j = nlohmann::json::parse(ss.str(), nullptr, false);
  if (j.is_discarded() || !j.is_object() || JsonText(j, "format") != "hovs-output") return "";
  const auto c = j.find("command");
  return c != j.end() && c->is_string() ? c->get<std::string>() : "";
}

}  // namespace

void WriteOutputMarker(const fs::path& folder, const std::string& command) {
  WriteFileAtomic(folder / kOutputMarker, MarkerText(command));
}

void CheckOutputFolder(const fs::path& target, const std::string& command, const std::vector<fs::path>& inputs) {
  const std::string where = target.string();
  HOVS_REQUIRE(!target.empty(), "output folder", "empty path");
  const fs::path resolved = Resolved(target);
  std::error_code ec;
  const fs::path cwd = fs::current_path(ec);
  HOVS_REQUIRE(ec || !Within(Resolved(cwd), resolved), where,
               "the output folder holds the current directory; hovs replaces its output folder, so give a folder "
               "below it (for example --out ",
               (target / "out").string(), ")");
  std::vector<fs::path> all = inputs;
  for (const auto& p : NotedInputs()) all.push_back(p);
  for (const auto& in : all) {
    if (in.empty()) continue;
    const fs::path r = Resolved(in);
    HOVS_REQUIRE(r != resolved, where, "is an input of this run; hovs never writes its output over an input");
    HOVS_REQUIRE(!Within(r, resolved), where, "the output folder holds the input ", in.string(),
                 "; a run would delete it: choose another --out");
  }
  const auto st = fs::symlink_status(target, ec);
  if (!fs::exists(st)) return;
  HOVS_REQUIRE(!fs::is_symlink(st), where,
               "is a symbolic link; hovs replaces output folders and never follows a link "
               "to do so: give the folder itself");
  HOVS_REQUIRE(fs::is_directory(st), where, "exists and is not a folder; hovs never replaces a file with its output");
  if (fs::is_empty(target, ec) && !ec) return;
  const std::string marker = MarkerCommand(target);
  HOVS_REQUIRE(!marker.empty(), where, "holds files hovs did not write (no ", kOutputMarker,
               " marker): hovs only replaces its own earlier output; choose another --out or remove the folder "
               "yourself");
  HOVS_REQUIRE(marker == command, where, "holds the output of 'hovs ", marker, "', not of 'hovs ", command,
               "'; choose another --out");
}

void CheckOutputFile(const fs::path& path, const std::string& signature, const std::string& kind) {
  const std::string where = path.string();
  HOVS_REQUIRE(!path.empty() && !path.filename().empty(), where, "name the output file itself");
  const fs::path resolved = Resolved(path);
  for (const auto& in : NotedInputs())
    HOVS_REQUIRE(Resolved(in) != resolved, where,
                 "is an input of this run; hovs never writes its output over an input");
  std::error_code ec;
  const auto st = fs::symlink_status(path, ec);
  if (!fs::exists(st)) return;
  HOVS_REQUIRE(!fs::is_symlink(st), where, "is a symbolic link; give the file itself");
  HOVS_REQUIRE(fs::is_regular_file(st), where, "exists and is not a file");
  std::string head(signature.size(), '\0');
  {
    std::ifstream in(path, std::ios::binary);
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<size_t>(std::max<std::streamsize>(0, in.gcount())));
  }
  HOVS_REQUIRE(head == signature, where, "exists and is not ", kind,
               ": hovs only replaces its own earlier file; choose another name or remove it yourself");
}

StagedDirectory::StagedDirectory(fs::path target, std::string command, std::vector<fs::path> inputs,
                                 bool keep_interrupted, bool resume)
    : target_(std::move(target)), command_(std::move(command)), inputs_(std::move(inputs)) {
  HOVS_REQUIRE(!target_.empty(), "output folder", "empty path");
  if (target_.filename().empty()) target_ = target_.parent_path();
  HOVS_REQUIRE(target_.filename() != "." && target_.filename() != "..", target_.string(),
               "name the output folder itself (not '.' or '..')");
  CheckOutputFolder(target_, command_, inputs_);
  const fs::path parent = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  HOVS_REQUIRE(!ec, target_.string(), "cannot create the folder that holds it (", parent.string(), "): ", ec.message());
  staging_ = HiddenSibling(parent, target_.filename().string(), kStagingTag);
  if (resume) {
    if (const auto earlier = NewestDeadStaging(parent, target_.filename().string(), command_)) {
      fs::rename(*earlier, staging_, ec);
      HOVS_REQUIRE(!ec, earlier->string(), "cannot take over the interrupted run's folder: ", ec.message());
      // What a killed run kept is never removed by a run that fails: a resume refused for its configuration (or
      // failing for any other reason) leaves the folder, now under this process's name, for the next --resume.
      resumed_ = keep_ = true;
    }
  }
  // Other runs' leftovers are only renamed here (a capture's frames); they are removed when this run commits, so
  // that a run refused or failing never deletes what an interrupted run kept.
  if (keep_interrupted) CleanStaleStaging(parent, target_.filename().string(), true);
  if (!resumed_) {
    fs::create_directory(staging_, ec);
    HOVS_REQUIRE(!ec, target_.string(), "cannot write there (its staging folder beside it: ", ec.message(), ")");
  }
  if (!keep_) RegisterForCleanup(staging_);  // an interrupt removes a new staging folder, never an adopted one
  WriteOutputMarker(staging_, command_);
}

void StagedDirectory::KeepOnFailure() { keep_ = true; }

StagedDirectory::~StagedDirectory() {
  if (!committed_ && !keep_) {
    std::error_code ec;
    fs::remove_all(staging_, ec);
  }
  UnregisterCleanup(staging_);
}

namespace {
constexpr uint64_t kFnvBasis = 14695981039346656037ull;
uint64_t Fnv1a(uint64_t h, const char* data, size_t n) {
  for (size_t i = 0; i < n; ++i) h = (h ^ static_cast<uint8_t>(data[i])) * 1099511628211ull;
  return h;
}
std::string ChecksumText(uint64_t h) {
  char text[40];
  std::snprintf(text, sizeof text, "fnv1a64:%016llx", static_cast<unsigned long long>(h));
  return text;
}
}  // namespace

std::string FileChecksum(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  HOVS_REQUIRE(in.good(), path.string(), "cannot read the file for its checksum");
  uint64_t h = kFnvBasis;
  std::vector<char> buf(1 << 16);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    h = Fnv1a(h, buf.data(), static_cast<size_t>(in.gcount()));
  }
  HOVS_REQUIRE(in.eof(), path.string(), "read error while taking its checksum");
  return ChecksumText(h);
}

std::string TextChecksum(const std::string& bytes) {
  return ChecksumText(Fnv1a(kFnvBasis, bytes.data(), bytes.size()));
}

void StagedDirectory::Commit() {
  CheckOutputFolder(target_, command_, inputs_);
  std::error_code ec;
  fs::path old;
  if (fs::exists(fs::symlink_status(target_, ec))) {
    old = HiddenSibling(target_.parent_path().empty() ? fs::path(".") : target_.parent_path(),
                        target_.filename().string(), kOldTag);
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
  UnregisterCleanup(staging_);
  if (!old.empty()) fs::remove_all(old, ec);
  // The target is complete: what killed runs left for it is obsolete.
  CleanStaleStaging(target_.has_parent_path() ? target_.parent_path() : fs::path("."), target_.filename().string(),
                    false);
}

}  // namespace hovs
