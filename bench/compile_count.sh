#!/usr/bin/env bash
# bench/compile_count.sh [SCENE...] — llvmpipe's compile of iqc's shader against the hand-written reference's,
# counted in instructions: a deterministic companion to bench/handwritten.sh's compile times.
#
# bench/handwritten.sh times the driver's compile (medians of interleaved rounds); on a shared machine one
# scene's ratio moved between 0.91 and 1.35 across four runs of 9 rounds each (stop 41, 100 instances). Here
# each shader is drawn once at 8x8 (`iqc render X.frag --size 8x8 --frames 1`: the compile, 64 pixels' drawing
# and the harness) under valgrind's cachegrind without cache simulation, which counts the instructions the
# process executes; a trivial shader's count is subtracted, leaving the compile and a few pixels. The count is
# the same from run to run (to ~0.1%), so a change of 1-2% in the emitted code shows. It is a proxy: the
# instructions are not all of equal cost, and on a GPU the driver is another compiler.
#
#   bench/compile_count.sh                        # every scene with a reference (about 30 s per shader)
#   bench/compile_count.sh grazing_thin few_shapes
#
# Needs valgrind (apt install valgrind); run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
IQC=${IQC:-./build/iqc}
command -v valgrind > /dev/null || { echo "compile_count.sh: needs valgrind (apt install valgrind)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export MESA_SHADER_CACHE_DISABLE=true LP_NUM_THREADS=1

scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  for f in bench/reference/*.frag; do scenes+=("$(basename "$f" .frag)"); done
fi

# count FILE.frag -> instructions executed
count() {
  valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
    "$IQC" render "$1" --size 8x8 --frames 1 -q -o "$tmp/x.png" 2>&1 | sed -n 's/.*I *refs: *\([0-9,]*\).*/\1/p' | tr -d , | tail -1
}

printf 'void mainImage(out vec4 c, in vec2 p) { c = vec4(p.x / iResolution.x, 0.0, 0.0, 1.0); }\n' > "$tmp/trivial.frag"
base=$(count "$tmp/trivial.frag")
printf '%-16s %-14s %-14s %s\n' scene "iqc (M instr)" "hand (M instr)" ratio
worst=0
for s in "${scenes[@]}"; do
  scene=bench/$s.iq; hand=bench/reference/$s.frag
  [ -f "$scene" ] && [ -f "$hand" ] || { echo "compile_count.sh: no $scene or $hand" >&2; exit 2; }
  "$IQC" "$scene" -o "$tmp/iqc.frag" 2>/dev/null
  i=$(count "$tmp/iqc.frag"); h=$(count "$hand")
  r=$(awk -v i="$i" -v h="$h" -v b="$base" 'BEGIN { printf "%.3f", (i - b) / (h - b) }')
  worst=$(awk -v a="$worst" -v b="$r" 'BEGIN { print (b > a ? b : a) }')
  awk -v s="$s" -v i="$i" -v h="$h" -v b="$base" -v r="$r" 'BEGIN { printf "%-16s %-14.1f %-14.1f %sx\n", s, (i - b) / 1e6, (h - b) / 1e6, r }'
done
echo "worst: ${worst}x (iqc/hand, instructions of llvmpipe's compile and an 8x8 draw)"
