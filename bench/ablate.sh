#!/usr/bin/env bash
# bench/ablate.sh [SCENE.iq...] — what each part of the emitted runtime costs on this machine's renderer: for
# each scene, iqc's Shadertoy shader, the edited copies bench/ablate/variants.py makes of it (each changes one
# thing and draws the same picture), and the hand-written reference where bench/reference has one, drawn in
# interleaved rounds; prints per shader the median over ROUNDS (default 7) of the median of the FRAMES - 1
# (default 20) frames after the first at SIZE (default 1600x900: sized for a GPU; on llvmpipe use 640x360),
# and its ratio to iqc's. The PSNR against iqc's picture says each copy draws the same one (`inf`; the
# normal's taps of the whole scene may differ where another instance lies within a tap's reach).
#
#   bench/ablate.sh                                   # the default scenes (below)
#   SIZE=640x360 ROUNDS=5 bench/ablate.sh bench/few_shapes.iq
#
# Written for the GPU leases (bench/gpu.sh's part `ablate`): stop 35 found the GPU ranks the code differently
# from llvmpipe (docs/accuracy.md, "On a GPU"). Run after scripts/build.sh.
set -uo pipefail
cd "$(dirname "$0")/.."
IQC=${IQC:-./build/iqc}
size=${SIZE:-1600x900}
frames=${FRAMES:-21}
rounds=${ROUNDS:-7}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export MESA_SHADER_CACHE_DISABLE=true __GL_SHADER_DISK_CACHE=0
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(bench/few_shapes.iq bench/grazing_thin.iq bench/displaced_torus.iq bench/instances_100.iq
                                   golden/effects/shadows_soft.iq golden/effects/shadows_hard.iq)

median() { sort -n | awk '{ v[NR] = $1 } END { if (NR == 0) print "nan"; else print v[int((NR + 1) / 2)] }'; }
frame() {
  "$IQC" render "$1" --size "$size" --frames "$frames" -o "$tmp/f.png" 2>&1 |
    sed -n 's/.*later frames \([0-9.]*\) ms median.*/\1/p'
}

for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .iq)
  dir=$tmp/$name
  mkdir -p "$dir"
  "$IQC" "$scene" -o "$dir/iqc.frag" 2>/dev/null || { echo "ablate.sh: $scene does not compile" >&2; continue; }
  python3 bench/ablate/variants.py "$dir/iqc.frag" "$dir/iqc"
  [ -f "bench/reference/$name.frag" ] && cp "bench/reference/$name.frag" "$dir/hand.frag"
  "$IQC" render "$dir/iqc.frag" --size 320x180 -o "$tmp/ref.png" -q
  : > "$dir/times"
  for ((r = 0; r < rounds; r++)); do
    for f in "$dir"/*.frag; do echo "$(basename "$f" .frag) $(frame "$f")" >> "$dir/times"; done
  done
  base=$(awk '$1 == "iqc" { print $2 }' "$dir/times" | median)
  echo "$scene at $size ($rounds rounds of $frames frames)"
  for f in "$dir"/*.frag; do
    v=$(basename "$f" .frag)
    "$IQC" render "$f" --size 320x180 -o "$tmp/v.png" -q
    m=$(awk -v n="$v" '$1 == n { print $2 }' "$dir/times" | median)
    printf '  %-14s %9s ms  %6sx  PSNR %s\n' "$v" "$m" "$(awk -v a="$m" -v b="$base" 'BEGIN { printf "%.3f", a / b }')" \
      "$(bash bench/psnr.sh "$tmp/ref.png" "$tmp/v.png")"
  done
done
