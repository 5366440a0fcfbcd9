#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install the packages, build, and run the end-to-end demo on
# the reference design. Output: results/design-reference/ (open index.html).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
xvfb-run -a build/apps/hovs design --config design/reference.yaml --out results/design-reference
# A small monocular calibration set of the reference unit, rendered with exact ground truth.
build/apps/hovs dataset --scene scenes/reference_calibration.yaml --count 9 --seed 1 --samples 4 \
  --out results/calibration-set
echo "demo: reports in results/design-reference/index.html and results/calibration-set/index.html"
