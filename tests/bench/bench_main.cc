// The benchmark programs' main: the process is set up as the hovs command sets itself up (freed frame-sized
// buffers kept for reuse, core/large_pages.h), then Google Benchmark runs as its own main would. With
// HOVS_DEFAULT_MALLOC set in the environment malloc keeps its defaults (to measure what the setting changes).
// The report's context (the JSON's "context") also names the CPU model, the malloc setting and the core's versions
// (hovs and its git description, compiler, Eigen, Ceres); a program may add its own
// libraries' with benchmark::AddCustomContext before main (render_bench.cc: Embree, OpenImageIO).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "core/large_pages.h"
#include "core/version.h"

namespace {

// The CPU as /proc/cpuinfo names it, with its family and model numbers (a VM's "AMD EPYC" alone does not tell Zen 4
// from Zen 5); Google Benchmark's context has the cores and caches, not the model.
std::string CpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string name, family, model;
  const auto value = [](const std::string& line) {
    const size_t colon = line.find(':'), start = line.find_first_not_of(" \t", colon + 1);
    return colon == std::string::npos || start == std::string::npos ? std::string() : line.substr(start);
  };
  for (std::string line; std::getline(in, line) && !line.empty();) {
    if (line.rfind("model name", 0) == 0)
      name = value(line);
    else if (line.rfind("cpu family", 0) == 0)
      family = value(line);
    else if (line.rfind("model", 0) == 0 && line.find_first_of(" \t") == 5)
      model = value(line);
  }
  if (name.empty()) return "unknown";
  return family.empty() ? name : name + " (family " + family + ", model " + model + ")";
}

}  // namespace

int main(int argc, char** argv) {
  const bool kept = std::getenv("HOVS_DEFAULT_MALLOC") == nullptr && hovs::KeepFreedMemoryForReuse();
  if (!kept) std::fprintf(stderr, "note: malloc keeps its default settings\n");
  benchmark::AddCustomContext("cpu_model", CpuModel());
#ifdef NDEBUG  // the context's "library_build_type" is Google Benchmark's own build (Debian: without NDEBUG)
  benchmark::AddCustomContext("hovs_build", "NDEBUG (Release)");
#else
  benchmark::AddCustomContext("hovs_build", "assertions on (not for timing)");
#endif
  benchmark::AddCustomContext("malloc", kept ? "freed memory kept for reuse" : "defaults");
  for (const auto& [name, version] : hovs::CoreVersions()) benchmark::AddCustomContext(name, version);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
