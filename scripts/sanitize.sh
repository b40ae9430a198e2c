#!/usr/bin/env bash
# The sanitizer suite: iqc, its tests and the libFuzzer harnesses built with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer in ./build-asan (-DIQC_SANITIZE=ON), then the whole test suite run there.
# Any sanitizer report fails the run (scripts/sanitizer-env.sh). CI runs it after scripts/test.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
if [ ! -f build-asan/CMakeCache.txt ]; then
  CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIQC_SANITIZE=ON >/dev/null
fi
cmake --build build-asan -j "$(nproc)"
source scripts/sanitizer-env.sh
cd build-asan
ctest -j "$(nproc)" --output-on-failure --timeout 900
