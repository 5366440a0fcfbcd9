#!/usr/bin/env bash
# Builds and runs the Google Benchmark programs; writes results/benchmarks/{bench,render,unwrap,calib}.json.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
mkdir -p results/benchmarks
build/tests/bench/hovs_bench --benchmark_out=results/benchmarks/.bench.json.tmp --benchmark_out_format=json "$@"
mv results/benchmarks/.bench.json.tmp results/benchmarks/bench.json
build/tests/bench/hovs_render_bench --benchmark_out=results/benchmarks/.render.json.tmp --benchmark_out_format=json
mv results/benchmarks/.render.json.tmp results/benchmarks/render.json
build/tests/bench/hovs_unwrap_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true \
  --benchmark_out=results/benchmarks/.unwrap.json.tmp --benchmark_out_format=json
mv results/benchmarks/.unwrap.json.tmp results/benchmarks/unwrap.json
build/tests/bench/hovs_calib_bench --benchmark_out=results/benchmarks/.calib.json.tmp --benchmark_out_format=json
mv results/benchmarks/.calib.json.tmp results/benchmarks/calib.json
build/tests/bench/hovs_stream_bench --benchmark_out=results/benchmarks/.stream.json.tmp --benchmark_out_format=json
mv results/benchmarks/.stream.json.tmp results/benchmarks/stream.json
