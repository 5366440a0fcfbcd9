#!/usr/bin/env bash
# Builds the libFuzzer harnesses (clang, AddressSanitizer + UndefinedBehaviorSanitizer, tree build-fuzz) and runs
# each for HOVS_FUZZ_SECONDS (default 60) from its committed seed corpus (tests/fuzz/corpus/<name>), two at a
# time. New inputs go to build-fuzz/corpus/<name> (kept between runs); a finding (crash, sanitizer report, hang,
# out-of-memory) stops the script with the harness's report and the input under build-fuzz/findings/.
# Usage: scripts/fuzz.sh [name ...]      (names: mapping_file ocam omnidir camera_files model_file scene manifest corners
#                                          layout design image machine tolerance rig_folder shard_records; default all)
# Longer runs: HOVS_FUZZ_SECONDS=3600 bash scripts/fuzz.sh mapping_file
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
seconds=${HOVS_FUZZ_SECONDS:-60}
all=(mapping_file ocam omnidir camera_files model_file scene manifest corners layout design image machine tolerance
     rig_folder shard_records)
names=("$@")
if [ "${#names[@]}" -eq 0 ]; then names=("${all[@]}"); fi

if [ ! -f build-fuzz/build.ninja ]; then
  cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
        -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
        -DCMAKE_CXX_COMPILER=clang++ -DHOVS_FUZZ=ON -DHOVS_CORE_ONLY=ON -DHOVS_BUILD_BENCHMARKS=OFF
fi
cmake --build build-fuzz --parallel "$jobs" --target hovs_fuzzers

mkdir -p build-fuzz/findings
run_one() {
  local name=$1
  local work=build-fuzz/corpus/$name
  mkdir -p "$work"
  # -rss_limit_mb: an input that makes hovs take more than 2 GB is a finding (sizes must be checked first);
  # -timeout: one input taking more than 20 s is a hang.
  if ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     "build-fuzz/tests/fuzz/fuzz_$name" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=20 \
       -artifact_prefix="build-fuzz/findings/$name-" -print_final_stats=1 "$work" "tests/fuzz/corpus/$name" \
       > "build-fuzz/findings/$name.log" 2>&1; then
    echo "fuzz $name: $(grep -E '^stat::number_of_executed_units' "build-fuzz/findings/$name.log" | awk '{print $2}') inputs in ${seconds} s, no finding"
  else
    echo "fuzz $name: FINDING (build-fuzz/findings/$name.log):"
    grep -E "ERROR|SUMMARY|runtime error|terminate|==[0-9]+==" "build-fuzz/findings/$name.log" | head -20
    return 1
  fi
}
export -f run_one
export seconds
printf '%s\n' "${names[@]}" | xargs -P "$jobs" -I{} bash -c 'run_one {}'
