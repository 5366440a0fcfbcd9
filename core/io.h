// Output that is never half-written and never replaces what hovs did not write: files are written to a temporary
// name and renamed; report folders are built in a staging folder and renamed into place only when complete, and
// only over a folder that an earlier run of the same command wrote (its marker file says so).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace hovs {

// Writes content to path atomically (temporary file in the same folder, then rename). Throws hovs::Error.
void WriteFileAtomic(const std::filesystem::path& path, const std::string& content);

// Throws hovs::Error naming `path` unless it is a regular file: "<what> not found", or "is a folder, not <what>"
// (a folder given where a file is expected), or "is not a regular file".
void RequireFile(const std::filesystem::path& path, const std::string& what = "a file");

// Reads a whole file, at most max_bytes (a larger file is an error naming it: inputs are parsed in memory). The
// path is noted as an input of this process (NoteInput). Throws hovs::Error naming the file.
std::string ReadFile(const std::filesystem::path& path, size_t max_bytes = size_t(1) << 30);

// Text as its parsers read it: a UTF-8 byte-order mark at the start removed, and every line end (LF, CR LF, or a
// lone CR as old Mac tools write) made LF, so that a table or model file from another system reads as written.
std::string NormalisedText(const std::string& text);

// The image files of a folder (png, jpg, jpeg, tif, tiff, exr, bmp, pgm; any case), sorted by name. Throws
// hovs::Error naming the folder when it is not a folder or holds no image.
std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& folder);

// A path inside `root` given by a file that hovs reads (a manifest's image, a sidecar's EXR): relative, without
// "..", resolved against root. Throws hovs::Error(where) otherwise: a shared dataset must not make hovs open
// /etc/passwd or a file beside it.
std::filesystem::path ContainedPath(const std::filesystem::path& root, const std::string& relative,
                                    const std::string& where);

// Inputs of this process: every file ReadFile and the image readers opened. An output folder may never be one
// that holds an input (CheckOutputFolder, StagedDirectory::Commit).
void NoteInput(const std::filesystem::path& path);
std::vector<std::filesystem::path> NotedInputs();
// Forgets the noted inputs: each command of a process (hovs validate runs several) starts with none.
void ClearNotedInputs();

// Files whose content a record vouches for (a dataset manifest's checksums): ReadFile checks the bytes it reads
// against the expected checksum, and VerifyExpectedChecksum the files read by other means (OpenEXR through
// OpenImageIO). A file that does not match is an error naming it, so a tampered or damaged image never passes for
// the one the record names. ClearNotedInputs forgets the expectations too.
void ExpectChecksum(const std::filesystem::path& path, const std::string& checksum, const std::string& record);
// Throws hovs::Error naming `path` when a checksum is expected for it and the file (or `bytes`, its content
// already read) does not match. Does nothing for other files.
void VerifyExpectedChecksum(const std::filesystem::path& path);
void VerifyExpectedChecksum(const std::filesystem::path& path, const std::string& bytes);

// The marker file in every hovs output folder: {"format": "hovs-output", "command": "<command>", "hovs": version}.
inline constexpr const char* kOutputMarker = ".hovs-output";
// Writes it into folder (for outputs that are not staged: a capture, written as it goes).
void WriteOutputMarker(const std::filesystem::path& folder, const std::string& command);

// Throws hovs::Error naming `target` unless it may become the output folder of `command`: it does not exist, or
// it is an empty folder, or a folder whose marker names the same command. Never a file or a symbolic link,
// never a folder that holds one of `inputs` (or of NotedInputs()), never one that holds the current directory.
void CheckOutputFolder(const std::filesystem::path& target, const std::string& command,
                       const std::vector<std::filesystem::path>& inputs = {});

// Throws hovs::Error naming `path` unless it may become an output file of the kind whose files begin with
// `signature` (a mapping file's magic, a layout's first line): it does not exist, or it is a regular file that
// begins so. Never a folder, a link or another file (a config given by mistake), never an input of this run.
void CheckOutputFile(const std::filesystem::path& path, const std::string& signature, const std::string& kind);

// A report folder under construction. The constructor checks the target (CheckOutputFolder) before any work
// is done and writes the marker into the staging folder; files go into staging(); Commit() checks again and
// replaces `target` with the staged folder in one rename (an earlier output is moved aside first and removed
// after). If Commit() is never called (an error was thrown), the destructor removes the staging folder and
// `target` is left untouched; an interrupt removes it too (core/interrupt.h). Staging folders that a killed run
// left behind for the same target are removed when this run commits, never before (with keep_interrupted they
// are renamed at once to a visible <name>.interrupted-<pid> beside it: a capture's frames are kept).
//
// Resumable runs: with `resume`, the newest staging folder that a killed run of the same command left for the
// same target becomes this run's staging folder, with what it holds (resumed() says so). An adopted folder is
// never removed by this run: if it does not commit (a configuration refused, an error, an interrupt), the folder
// stays for the next resume. KeepOnFailure() makes a new staging folder stay in the same way.
class StagedDirectory {
 public:
  StagedDirectory(std::filesystem::path target, std::string command, std::vector<std::filesystem::path> inputs = {},
                  bool keep_interrupted = false, bool resume = false);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& target() const { return target_; }
  bool resumed() const { return resumed_; }
  void KeepOnFailure();
  void Commit();

 private:
  std::filesystem::path target_;
  std::string command_;
  std::vector<std::filesystem::path> inputs_;
  std::filesystem::path staging_;
  bool committed_ = false, resumed_ = false, keep_ = false;
};

// A file's checksum as "fnv1a64:<16 hex digits>" (FNV-1a, 64 bits): enough to tell a complete file from a
// truncated or rewritten one. Throws hovs::Error naming the file when it cannot be read.
std::string FileChecksum(const std::filesystem::path& path);
// The same checksum of bytes in memory (a record's payload, a file already read).
std::string TextChecksum(const std::string& bytes);

}  // namespace hovs
