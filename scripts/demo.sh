#!/usr/bin/env bash
# The main job, from a fresh Debian 12 machine: install the packages, build, and run the end-to-end demo on
# the reference design. Output: results/design-reference/ (open index.html).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/build.sh
xvfb-run -a build/apps/hovs design --config design/reference.yaml --out results/design-reference
echo "demo: report in results/design-reference/index.html"
