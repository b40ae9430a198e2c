#!/usr/bin/env bash
# Scene-compiler benchmark (issue 4): N instances of the torus (each with its own transform and
# material parameters). Reports iqc's compile time (median of 11, incl. glslang), the emitted size, and
# the shader's compile time on the renderer (Mesa's llvmpipe without a GPU; its shader cache off, and
# llvmpipe compiles lazily, so the first frame is reported too). Run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-10s %-22s %-14s %-12s %s\n' instances "compile (median, ms)" "size (bytes)" "bytes/inst" "llvmpipe compile (ms)"
for n in ${@:-10 25 50 100 200}; do
  f="$tmp/scene_$n.iq"
  {
    echo '[modules]'
    echo 'torus = """'
    printf 'shape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\nt ∈ [0,2]x[0,2] default = (0.3, 0.1)\n"""\n'
    echo 'lambert = """'
    printf 'material\nC = max(0, L̂⋅N̂)`k_d` + 0.05`k_d`\nL̂ = (`P_L` - p)/‖`P_L` - p‖\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³\n`P_L` ∈ ℝ³\n`k_d` ∈ [0,1]x[0,1]x[0,1] default = (0.8, 0.5, 0.2)\n"""\n'
    printf '[camera]\nposition = [0, 0, -12]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-5, 8, -6]\n'
    for i in $(seq 0 $((n - 1))); do
      x=$(( (i % 10) - 5 )); y=$(( (i / 10) % 10 - 5 )); z=$(( i / 100 ))
      printf '[[shapes]]\ntype = "torus"\nmaterial = "lambert"\ntransform = """T((%d, %d, %d))⋅`R_x`(r)\nwhere\nr ∈ [-3,3] default = %d.%d"""\n' "$x" "$y" "$z" $((i % 3)) $((i % 10))
    done
  } > "$f"
  ms=$(for i in $(seq 11); do ./build/iqc "$f" --time -o "$tmp/out.frag" 2>&1 | awk '/compiled in/ {print $(NF-1)}'; done | sort -n | sed -n 6p)
  size=$(wc -c < "$tmp/out.frag")
  gl=$(MESA_SHADER_CACHE_DISABLE=true ./build/iqc render "$f" -o "$tmp/out.png" --size 64x36 2>&1 | sed -n "s/.*shader compile \([0-9.]*\) ms, frame \([0-9.]*\) ms.*/\1 + first frame \2/p")
  printf '%-10s %-22s %-14s %-12s %s\n' "$n" "$ms" "$size" $((size / n)) "$gl"
done
