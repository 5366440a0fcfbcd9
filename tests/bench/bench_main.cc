// The benchmark programs' main: the process is set up as the hovs command sets itself up (freed frame-sized
// buffers kept for reuse, core/large_pages.h), then Google Benchmark runs as its own main would. With
// HOVS_DEFAULT_MALLOC set in the environment malloc keeps its defaults (to measure what the setting changes).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>

#include "core/large_pages.h"

int main(int argc, char** argv) {
  if (std::getenv("HOVS_DEFAULT_MALLOC") != nullptr || !hovs::KeepFreedMemoryForReuse())
    std::fprintf(stderr, "note: malloc keeps its default settings\n");
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
