#!/usr/bin/env bash
# Render benchmark (issue 5): every example at 640×360 on the headless renderer (llvmpipe without a GPU;
# Mesa's shader cache off). Per example, the median of 5 runs of: the shader's compile and link, the first
# frame (llvmpipe also compiles lazily, at the first draw) and the median of 4 later frames; the share of
# "compile + first frame" that is not drawing. Run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-24s %-13s %-14s %-15s %s\n' example "compile (ms)" "frame 1 (ms)" "later (ms)" "compilation share"
for f in examples/*.md examples/*.iq; do
  [ "$(basename "$f")" = README.md ] && continue
  for i in 1 2 3 4 5; do
    MESA_SHADER_CACHE_DISABLE=true ./build/iqc render "$f" -o "$tmp/out.png" --size 640x360 --frames 5 2>&1 |
      sed -n 's/.*shader compile \([0-9.]*\) ms, frame \([0-9.]*\) ms, later frames \([0-9.]*\) ms median.*/\1 \2 \3/p'
  done > "$tmp/runs"
  med() { awk -v k="$1" '{print $k}' "$tmp/runs" | sort -n | sed -n 3p; }
  c=$(med 1); f1=$(med 2); later=$(med 3)
  # Compilation = the compile call plus what the first frame takes beyond a later frame.
  share=$(awk -v c="$c" -v a="$f1" -v l="$later" 'BEGIN { x = c + a - l; if (x < c) x = c; printf "%.0f%%", 100 * x / (c + a) }')
  printf '%-24s %-13s %-14s %-15s %s\n' "$(basename "$f")" "$c" "$f1" "$later" "$share"
done
