#!/usr/bin/env bash
# Scene-compiler benchmark: a ground and N rings (one shape, one material, each with its own constant
# transform), for every target. Reports iqc's compile time (median of 7 whole-process runs, incl. glslang),
# the emitted size, and — for the sizes in LLVMPIPE_SIZES — the driver's compile time and the first
# frame at 64x36 on the headless renderer (Mesa's llvmpipe without a GPU; its shader cache off).
#
#   bench/instances.sh                 # 1 10 100 1000 10000, grid layout
#   LAYOUT=irregular bench/instances.sh 10 100 1000   # jittered, tilted rings (their tables stay tables)
#   LAYOUT=moving LLVMPIPE_SIZES="10 100" bench/instances.sh 10 100 1000 10000   # rings tilting with time
#
# Run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
layout=${LAYOUT:-grid}
llvmpipe_sizes=" ${LLVMPIPE_SIZES:-10 100 1000} "

scene() { bash bench/rings.sh "$1" "$2"; }  # scene N LAYOUT > file

median() { sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

printf '%-9s %-10s %-20s %-13s %s\n' instances target "iqc compile (ms)" "size (bytes)" "llvmpipe: driver compile + first frame 64x36 (ms)"
for n in ${@:-1 10 100 1000 10000}; do
  f="$tmp/rings_$n.iq"
  scene "$n" "$layout" > "$f"
  for target in shadertoy webgl2 glsl330; do
    ms=$(for i in 1 2 3 4 5 6 7; do ./build/iqc "$f" --target "$target" --time -o "$tmp/out.frag" 2>&1 | awk '/compiled in/ { print $(NF-1) }'; done | median)
    size=$(wc -c < "$tmp/out.frag")
    gl="-"
    if [[ "$llvmpipe_sizes" == *" $n "* && "$target" != glsl330 ]]; then
      gl=$(MESA_SHADER_CACHE_DISABLE=true ./build/iqc render "$f" --target "$target" -o "$tmp/out.png" --size 64x36 2>&1 |
           sed -n 's/.*shader compile \([0-9.]*\) ms, frame \([0-9.]*\) ms.*/\1 + \2/p')
    fi
    printf '%-9s %-10s %-20s %-13s %s\n' "$n" "$target" "$ms" "$size" "$gl"
  done
done
