#!/usr/bin/env bash
# Formats hovs' C++ sources with clang-format 14 and .clang-format; --check lists the files that differ and exits 1
# (scripts/test.sh runs the check).
set -euo pipefail
cd "$(dirname "$0")/.."
mapfile -t files < <(git ls-files '*.cc' '*.h' | grep -v '^tests/fuzz/corpus/')
if [ "${1:-}" = "--check" ]; then
  bad=0
  for f in "${files[@]}"; do
    if ! clang-format-14 --dry-run --Werror "$f" >/dev/null 2>&1; then echo "not formatted: $f"; bad=1; fi
  done
  [ "$bad" = 0 ] || { echo "run scripts/format.sh"; exit 1; }
else
  clang-format-14 -i "${files[@]}"
fi
