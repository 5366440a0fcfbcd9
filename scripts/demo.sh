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
# Panoramic expansion of a street scene: the article's six views and a cylindrical panorama of the left unit,
# each perspective view compared with a pinhole render of the same view at the unit's viewpoint (PSNR).
build/apps/hovs render --scene scenes/street.yaml --samples 4 --out results/street
build/apps/hovs unwrap --model scenes/street.yaml --unit left --layout article --input results/street/dataset.json \
  --save-map results/street/article.hmap --truth-scene scenes/street.yaml --out results/street-views
build/apps/hovs unwrap --model scenes/street.yaml --unit left --layout panorama --input results/street/dataset.json \
  --out results/street-panorama
# Dense binocular depth of the same street frame (both units), against the renderer's range channel.
build/apps/hovs depth --dataset results/street/dataset.json --out results/street-depth
# Binocular calibration: 12 ArUco board pairs of the two-unit rig (0.64 m, the right unit misaligned), markers
# found in unwrapped views, the relative pose solved jointly and compared with the true rig.
build/apps/hovs dataset --kind stereo_aruco --scene scenes/reference_stereo.yaml --count 12 --seed 1 --samples 2 \
  --out results/stereo-set
build/apps/hovs stereo-calibrate --dataset results/stereo-set/dataset.json --out results/stereo-calibration
echo "demo: reports in results/design-reference/index.html and results/calibration-set/index.html;"
echo "      street views in results/street-views/ (views.json: K, poses, PSNR against truth renders), panorama in results/street-panorama/,"
echo "      stereo calibration in results/stereo-calibration/ (stereo.json, stereo.yaml, summary.txt),"
echo "      depth in results/street-depth/ (depth.json: error per distance band; range.exr; points.ply / points.vtp)"
