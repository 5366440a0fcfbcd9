// libFuzzer harnesses for the parsers hovs owns (scripts/fuzz.sh runs them; tests/fuzz/README.md). Each feeds the
// fuzzer's bytes to one parser: hovs::Error is the expected answer to bad input; anything else (another
// exception, a sanitizer report, a crash, a hang) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"

#define HOVS_FUZZ_TARGET(body)                                                        \
  extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {           \
    const std::string input(reinterpret_cast<const char*>(data), size);              \
    try {                                                                             \
      body(input);                                                                    \
    } catch (const hovs::Error&) {                                                    \
    }                                                                                 \
    return 0;                                                                         \
  }
