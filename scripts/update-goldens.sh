#!/usr/bin/env bash
# Regenerates every golden file (golden/**/*.expected) from the current compiler. Review each diff
# (`git diff golden/`) as if it were code before committing: a golden is an expectation.
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --build build -j "$(nproc)" >/dev/null
IQC_UPDATE_GOLDEN=1 ./build/tests/iqc_tests "[golden]"
# docs/lipschitz.md: the derived Lipschitz bounds of the standard library (tests/lipschitz_table_test.cpp)
IQC_UPDATE_GOLDEN=1 ./build/tests/iqc_tests "[lipschitz-table]"
# (the image goldens are tagged [golden] too: golden/images/*.png)
git --no-pager diff --stat -- golden/ docs/lipschitz.md || true
