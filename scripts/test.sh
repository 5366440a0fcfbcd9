#!/usr/bin/env bash
# The test suite, from a fresh Debian 12 machine: install, build, run every CTest test, then build the core,
# design and unwrap unit tests (the remap kernels read memory by hand) with AddressSanitizer +
# UndefinedBehaviorSanitizer and run them.
# Environment: HOVS_TEST_LABELS (a CTest -L regex) to run a slice; HOVS_SKIP_SANITIZE=1 to skip the ASan pass.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
bash scripts/setup.sh
bash scripts/build.sh

label_args=()
if [ -n "${HOVS_TEST_LABELS:-}" ]; then label_args=(-L "$HOVS_TEST_LABELS"); fi
ctest --test-dir build --output-on-failure --parallel "$jobs" "${label_args[@]}"

if [ "${HOVS_SKIP_SANITIZE:-0}" != "1" ]; then
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHOVS_SANITIZE=ON -DHOVS_CORE_ONLY=ON \
        -DHOVS_BUILD_BENCHMARKS=OFF
  # Not the calibration tests: Debian's Ceres is a static library built without ASan, and Eigen switches to its
  # own aligned allocator under ASan (__SANITIZE_ADDRESS__), so Eigen code shared between Ceres and hovs would
  # free with one allocator what the other allocated (a false alarm of mixed builds, not a hovs defect).
  cmake --build build-asan --parallel "$jobs" --target hovs_core_tests hovs_design_tests hovs_unwrap_tests
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure --parallel "$jobs" -L unit
fi
