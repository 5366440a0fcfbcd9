#!/usr/bin/env bash
# The test suite, from a fresh Debian 12 machine: install, build, run every CTest test; then, in a second tree
# built with clang, AddressSanitizer + UndefinedBehaviorSanitizer and libFuzzer's coverage (build-fuzz), the core,
# design, optics and unwrap unit tests (the remap kernels read memory by hand) and a short run of every parser's
# fuzzer (scripts/fuzz.sh, HOVS_FUZZ_SECONDS each, two at a time).
# Environment: HOVS_TEST_LABELS (a CTest -L regex) to run a slice; HOVS_SKIP_SANITIZE=1 to skip the sanitizer
# tree; HOVS_FUZZ_SECONDS (default 30) per fuzzer, 0 to build the fuzzers without running them.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
bash scripts/setup.sh
bash scripts/build.sh

# The README's headline table matches the committed results; no new over-long file or function; every source
# formatted (.clang-format).
python3 scripts/headline.py --check
python3 scripts/check_sizes.py
bash scripts/format.sh --check

label_args=()
if [ -n "${HOVS_TEST_LABELS:-}" ]; then label_args=(-L "$HOVS_TEST_LABELS"); fi
ctest --test-dir build --output-on-failure --parallel "$jobs" "${label_args[@]}"

if [ "${HOVS_SKIP_SANITIZE:-0}" != "1" ]; then
  # -O1 with line tables: enough for the sanitizers' stack traces, and the tree compiles in about 60 % of the time
  # -O2 -g takes (polynomial_calibration.cc: 43 s against 75 s).
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
        -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
        -DCMAKE_CXX_COMPILER=clang++ -DHOVS_FUZZ=ON -DHOVS_CORE_ONLY=ON -DHOVS_BUILD_BENCHMARKS=OFF
  # Not the calibration tests: Debian's Ceres is a static library built without ASan, and Eigen switches to its
  # own aligned allocator under ASan, so Eigen code shared between Ceres and hovs would free with one allocator
  # what the other allocated (a false alarm of mixed builds, not a hovs defect).
  cmake --build build-fuzz --parallel "$jobs" \
    --target hovs_core_tests hovs_design_tests hovs_optics_tests hovs_unwrap_tests hovs_fuzzers
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-fuzz --output-on-failure --parallel "$jobs" -L unit
  if [ "${HOVS_FUZZ_SECONDS:-30}" != "0" ]; then
    HOVS_FUZZ_SECONDS=${HOVS_FUZZ_SECONDS:-30} bash scripts/fuzz.sh
  fi
fi
