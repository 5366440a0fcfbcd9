// Output that is never half-written: files are written to a temporary name and renamed; report folders are
// built in a staging folder and renamed into place only when complete.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace hovs {

// Writes content to path atomically (temporary file in the same folder, then rename). Throws hovs::Error.
void WriteFileAtomic(const std::filesystem::path& path, const std::string& content);

// Reads a whole file. Throws hovs::Error naming the file.
std::string ReadFile(const std::filesystem::path& path);

// The image files of a folder (png, jpg, jpeg, tif, tiff, exr, bmp, pgm; any case), sorted by name. Throws
// hovs::Error naming the folder when it is not a folder or holds no image.
std::vector<std::filesystem::path> ListImageFiles(const std::filesystem::path& folder);

// A report folder under construction. Files go into staging(); Commit() replaces `target` with the staged
// folder in one rename (an existing target is moved aside first and removed after). If Commit() is never
// called (an error was thrown), the destructor removes the staging folder and `target` is left untouched.
class StagedDirectory {
 public:
  explicit StagedDirectory(std::filesystem::path target);
  ~StagedDirectory();
  StagedDirectory(const StagedDirectory&) = delete;
  StagedDirectory& operator=(const StagedDirectory&) = delete;

  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& target() const { return target_; }
  void Commit();

 private:
  std::filesystem::path target_;
  std::filesystem::path staging_;
  bool committed_ = false;
};

}  // namespace hovs
