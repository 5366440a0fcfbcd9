// libFuzzer harnesses for the parsers hovs owns (scripts/fuzz.sh runs them; tests/fuzz/README.md). Each feeds the
// fuzzer's bytes to one parser: hovs::Error is the expected answer to bad input; anything else (another
// exception, a sanitizer report, a crash, a hang) is a finding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/any_model.h"
#include "core/error.h"

namespace hovs::fuzz {

// A model that loaded is used: n pixels along the image diagonal back-projected and projected again.
inline void UseModel(const AnyModel& m, int n = 16) {
  Vec3d bearing;
  Vec2d uv;
  for (int k = 0; k < n; ++k)
    if (m.MirrorFromImg(Vec2d(k * m.width() / double(n), k * m.height() / double(n)), &bearing))
      m.ImgFromMirror(bearing, &uv);
}

}  // namespace hovs::fuzz

#define HOVS_FUZZ_TARGET(body)                                              \
  extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) { \
    const std::string input(reinterpret_cast<const char*>(data), size);     \
    try {                                                                   \
      body(input);                                                          \
    } catch (const hovs::Error&) {}                                         \
    return 0;                                                               \
  }
