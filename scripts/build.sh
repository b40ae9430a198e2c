#!/usr/bin/env bash
# scripts/build.sh [--main]
# Installs what is missing, then configures and builds iqc and its tests in ./build (Release). With --main,
# only iqc: installs only what it needs (scripts/install-deps.sh --main) and builds no tests (the README's
# main job); a later build without --main adds the tests to the same ./build.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${1:-}" = "--main" ]; then
  bash scripts/install-deps.sh --main
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DIQC_BUILD_TESTS=OFF >/dev/null
  cmake --build build -j "$(nproc)" --target iqc
else
  bash scripts/install-deps.sh
  cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DIQC_BUILD_TESTS=ON >/dev/null
  cmake --build build -j "$(nproc)"
fi
