#!/usr/bin/env bash
# docs/overview.jpg, the README's picture, from a finished `hovs validate` run (default results/validate-full):
# the left unit's rendered street image beside four of its six unwrapped views (calibrated model).
set -euo pipefail
cd "$(dirname "$0")/.."
run=${1:-results/validate-full}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
oiiotool "$run/data/street/images/left.png" --cut 2200x2200+275+0 --resize 300x300 -o "$tmp/unit.png"
for v in view0 view60 view120 view240; do oiiotool "$run/views/frame0/$v.png" --resize 0x150 -o "$tmp/$v.png"; done
oiiotool "$tmp/view0.png" "$tmp/view60.png" --mosaic:pad=0 2x1 -o "$tmp/top.png"
oiiotool "$tmp/view120.png" "$tmp/view240.png" --mosaic:pad=0 2x1 -o "$tmp/bottom.png"
oiiotool "$tmp/top.png" "$tmp/bottom.png" --mosaic:pad=0 1x2 -o "$tmp/views.png"
oiiotool --nosoftwareattrib "$tmp/unit.png" "$tmp/views.png" --mosaic:pad=0:fit=514x300 2x1 -o docs/overview.jpg
