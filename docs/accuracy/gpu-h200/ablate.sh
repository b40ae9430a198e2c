#!/bin/bash
# Ablation on the GPU: frame medians (1600x900, 21 frames) of variants, 7 interleaved rounds.
cd "$(dirname "$0")/.."
median() { sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }
frame() { ./build/iqc render "$1" --size 1600x900 --frames "${2:-21}" -o /tmp/a.png 2>&1 | sed -n 's/.*later frames \([0-9.]*\) ms median.*/\1/p'; }
nvidia-smi --query-gpu=clocks.sm,clocks.max.sm,clocks.mem --format=csv
echo "clock check: few_shapes iqc 21 frames $(frame .gpu/abl/few_shapes_iqc.frag 21), 201 frames $(frame .gpu/abl/few_shapes_iqc.frag 201), 21 again $(frame .gpu/abl/few_shapes_iqc.frag 21)"
nvidia-smi --query-gpu=clocks.sm --format=csv,noheader
: > /tmp/abl.t
for s in few_shapes displaced_torus grazing_thin; do
  for r in 1 2 3 4 5 6 7; do
    for f in .gpu/abl/${s}_*.frag; do echo "$(basename "$f" .frag) $(frame "$f")" >> /tmp/abl.t; done
  done
  hand=$(awk -v n="${s}_hand" '$1 == n { print $2 }' /tmp/abl.t | median)
  for f in .gpu/abl/${s}_*.frag; do
    v=$(basename "$f" .frag); m=$(awk -v n="$v" '$1 == n { print $2 }' /tmp/abl.t | median)
    all=$(awk -v n="$v" '$1 == n { printf "%s ", $2 }' /tmp/abl.t)
    printf '%-26s %8s ms  %5.3fx  [%s]\n' "$v" "$m" "$(awk -v a="$m" -v b="$hand" 'BEGIN { print a / b }')" "$all"
  done
done
