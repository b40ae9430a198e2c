#!/usr/bin/env bash
# The whole test suite: build iqc and its tests, then run them under ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
cd build
ctest -j "$(nproc)" --output-on-failure
