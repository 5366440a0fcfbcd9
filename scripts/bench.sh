#!/usr/bin/env bash
# Builds and runs the Google Benchmark programs; writes results/benchmarks/bench.json and prints the table.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
mkdir -p results/benchmarks
build/tests/bench/hovs_bench --benchmark_out=results/benchmarks/.bench.json.tmp --benchmark_out_format=json "$@"
mv results/benchmarks/.bench.json.tmp results/benchmarks/bench.json
