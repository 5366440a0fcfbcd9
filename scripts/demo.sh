#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install the packages, build, and run `hovs validate` on the
# reference design: the whole chain (design study, renders, detection, calibration of both units, stereo
# calibration, six views and panorama, dense and sparse depth, the real VMR images) against ground truth.
# Output: results/validate-full/ (open report.html; metrics.json holds every figure). About 12-15 minutes on 2
# cores (the variable-scale stage about 9 of them).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
xvfb-run -a build/apps/hovs validate
