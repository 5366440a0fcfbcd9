// Running the hovs executable from tests: exit code and combined output; scratch folders.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

namespace hovs::test {

struct CliRun {
  int exit_code = -1;
  std::string output;
};

// Any shell command line: exit code and combined output.
inline CliRun Run(const std::string& command) {
  const std::string cmd = command + " 2>&1";
  CliRun r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

inline CliRun Hovs(const std::string& args) { return Run(std::string(HOVS_BINARY) + " " + args); }

// A fresh folder path under the system temp folder (removed first), unique per process.
inline std::filesystem::path Scratch(const std::string& suite, const std::string& name) {
  const auto p = std::filesystem::temp_directory_path() / ("hovs-" + suite + "-" + std::to_string(getpid())) / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p.parent_path());
  return p;
}

}  // namespace hovs::test
