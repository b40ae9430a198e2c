#!/usr/bin/env bash
# Many instances with `bound`: a ground and N rings (bench/rings.sh, bench/instances.sh's scene), each ring with
# `bound = 0.4` — from 48 on, the group is a bounding-volume hierarchy (docs/scene.md, "Many instances") —
# and, for comparison, the same rings without `bound` (every member evaluated at every step).
#
# Prints per N: shape evaluations per scene evaluation (`iqc render --stats`), and the frame time on the
# headless renderer (llvmpipe without a GPU) at SIZE (default 160x90): the median over ROUNDS (default 7)
# interleaved rounds of the median of the FRAMES - 1 (default 3) frames after the first (which includes the
# driver's compile), and its ratio to the frame at the first N.
#
#   bench/hierarchy.sh                  # N = 10 100 1000 2000, Shadertoy target
#   TARGET=webgl2 ROUNDS=3 bench/hierarchy.sh 10 1000 10000
# (On Shadertoy a group of more than 2,048 members has no hierarchy: its tables would be code.)
#
# Run after scripts/build.sh. Timings vary with the machine's load: compare ratios within one run.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
target=${TARGET:-shadertoy}
rounds=${ROUNDS:-7}
size=${SIZE:-160x90}
frames=${FRAMES:-4}
sizes=(${@:-10 100 1000 2000})

median() { sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

frame() {  # frame FILE: the median of the frames after the first, ms
  MESA_SHADER_CACHE_DISABLE=true ./build/iqc render "$1" --target "$target" --size "$size" --frames "$frames" -o "$tmp/f.png" 2>&1 |
    sed -n 's/.*later frames \([0-9.]*\) ms median.*/\1/p'
}

for n in "${sizes[@]}"; do
  bash bench/rings.sh "$n" grid 0.4 > "$tmp/b_$n.iq"
  bash bench/rings.sh "$n" grid 0 > "$tmp/u_$n.iq"
done
declare -A times
for ((r = 0; r < rounds; ++r)); do
  for n in "${sizes[@]}"; do
    for v in b u; do
      # Without bound, thousands of rings take seconds a frame on llvmpipe: measured up to 1,000.
      [[ $v == u && $n -gt 1000 ]] && continue
      times[$v,$n]+="$(frame "$tmp/${v}_$n.iq") "
    done
  done
done

printf '%-9s %-28s %-22s %-22s\n' rings "shape evals / scene eval" "frame ms, bound (×)" "frame ms, no bound (×)"
base_b="" base_u=""
for n in "${sizes[@]}"; do
  per=$(MESA_SHADER_CACHE_DISABLE=true ./build/iqc render "$tmp/b_$n.iq" --target "$target" --size 160x90 --stats -o "$tmp/s.png" 2>/dev/null |
        awk '/shape_evals_per_eval/ { print $2 }')
  fb=$(tr ' ' '\n' <<< "${times[b,$n]}" | grep . | median)
  [ -z "$base_b" ] && base_b=$fb
  fu="-" ru=""
  if [ -n "${times[u,$n]:-}" ]; then
    fu=$(tr ' ' '\n' <<< "${times[u,$n]}" | grep . | median)
    [ -z "$base_u" ] && base_u=$fu
    ru=$(awk -v a="$fu" -v b="$base_u" 'BEGIN { printf "(%.2f×)", a / b }')
  fi
  rb=$(awk -v a="$fb" -v b="$base_b" 'BEGIN { printf "(%.2f×)", a / b }')
  printf '%-9s %-28s %-22s %-22s\n' "$n" "$per" "$fb $rb" "$fu $ru"
done
