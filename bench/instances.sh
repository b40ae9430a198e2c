#!/usr/bin/env bash
# Scene-compiler benchmark: a ground and N rings (one shape, one material, each with its own constant
# transform), for every target. Reports iqc's compile time (median of 7 whole-process runs, incl. glslang),
# the emitted size, and — for the sizes in LLVMPIPE_SIZES — the driver's compile time and the first
# frame at 64x36 on the headless renderer (Mesa's llvmpipe without a GPU; its shader cache off).
#
#   bench/instances.sh                 # 1 10 100 1000 10000, grid layout
#   LAYOUT=irregular bench/instances.sh 10 100 1000   # jittered, tilted rings (their tables stay tables)
#
# Run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
layout=${LAYOUT:-grid}
llvmpipe_sizes=" ${LLVMPIPE_SIZES:-10 100 1000} "

scene() {  # scene N LAYOUT > file
  awk -v n="$1" -v layout="$2" 'BEGIN {
    print "title = \"" n " rings\"\n[modules]\nring = \"\"\"\nshape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³"
    print "t ∈ [0,2]x[0,2] default = (0.3, 0.08)\n\"\"\"\nground = \"\"\"\nshape\nD = p_2 + h\nwhere\np ∈ ℝ³\nh ∈ [0,5] default = 1\n\"\"\""
    print "lambert = \"\"\"\nmaterial\nC = max(0, L̂⋅N̂)`k_d` + 0.05`k_d`\nL̂ = (`P_L` - p)/‖`P_L` - p‖\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³"
    print "`P_L` ∈ ℝ³\n`k_d` ∈ [0,1]x[0,1]x[0,1] default = (0.8, 0.5, 0.2)\n\"\"\""
    print "[camera]\nposition = [0, 7, -13]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-5, 8, -6]"
    print "[[shapes]]\ntype = \"ground\"\nmaterial = \"lambert\"\nmaterial_params = { k_d = [0.5, 0.5, 0.5] }"
    side = 1; while (side * side * 10 < n) side++
    srand(12345)
    for (i = 0; i < n; i++) {
      x = (i % side) - side / 2; z = int(i / side) % side - side / 2; y = int(i / (side * side)) * 0.5 - 0.7
      if (layout == "irregular")
        t = sprintf("T((%.4f, %.4f, %.4f))⋅`R_x`(%.3f)", x + 0.3 * (rand() - 0.5), y, z + 0.3 * (rand() - 0.5), 0.4 * (i % 7))
      else
        t = sprintf("T((%g, %g, %g))", x, y, z)
      print "[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"" t "\""
    }
  }'
}

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
