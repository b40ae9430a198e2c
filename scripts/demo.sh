#!/usr/bin/env bash
# The main job on a bundled example: build iqc, compile examples/two_tori.md to a Shadertoy shader and
# render it headlessly to a PNG.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh --main
./build/iqc examples/two_tori.md -o build/two_tori.frag
./build/iqc render examples/two_tori.md -o build/two_tori.png
echo
echo "Shadertoy shader: $(pwd)/build/two_tori.frag  (paste it into https://www.shadertoy.com/new)"
echo "Picture:          $(pwd)/build/two_tori.png"
