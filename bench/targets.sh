#!/usr/bin/env bash
# bench/targets.sh [REPEAT] — compile time of each target relative to shadertoy, for every bundled example.
#
# For each example and target, `iqc --repeat REPEAT` (default 7) compiles the scene that many times warm in
# one process and prints the median; the table gives each target's median in ms and its ratio to the
# shadertoy median of the same example (one run; medians). Uses ./build/iqc (IQC=... to override).
set -euo pipefail
cd "$(dirname "$0")/.."
IQC="${IQC:-./build/iqc}"
N="${1:-7}"
targets=(shadertoy webgl2 glsl330 html cpp spirv hlsl wgsl threejs)
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
printf '%-22s' "example"
for t in "${targets[@]}"; do printf ' %16s' "$t"; done
printf '\n'
declare -A sum
for ex in examples/*.md examples/*.iq; do
  [ "$(basename "$ex")" = README.md ] && continue
  printf '%-22s' "$(basename "$ex")"
  base=""
  for t in "${targets[@]}"; do
    ms=$("$IQC" "$ex" --target "$t" -o "$tmp/out" --repeat "$N" -q 2>&1 | sed -n 's/.*median \([0-9.]*\) ms.*/\1/p')
    [ -z "$base" ] && base="$ms"
    ratio=$(awk -v a="$ms" -v b="$base" 'BEGIN { printf "%.2f", a / b }')
    sum[$t]=$(awk -v s="${sum[$t]:-0}" -v r="$ratio" 'BEGIN { print s + log(r) }')
    printf ' %8.1f (%5s×)' "$ms" "$ratio"
  done
  printf '\n'
done
n=$(ls examples/*.md examples/*.iq | grep -vc README.md)
printf '%-22s' "geometric mean"
for t in "${targets[@]}"; do printf ' %16s' "$(awk -v s="${sum[$t]}" -v n="$n" 'BEGIN { printf "%.2f×", exp(s / n) }')"; done
printf '\n'
