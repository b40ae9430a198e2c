#!/usr/bin/env bash
# bench/gpu.sh OUT [PART...] — issue 17's figures on a GPU, in parts sized for a lease (15 minutes of device
# time, 10 a command): the hand-written comparison (bench/handwritten.sh), an ablation of the emitted runtime
# (bench/ablate.sh), many instances with `bound` (bench/hierarchy.sh), the scene compiler's
# sizes and the driver's compile (bench/instances.sh), and `iqc bench` on the bench scenes. Each part writes
# OUT/NAME.txt and has its own time limit, so that a slow part leaves the others their time; the first
# line of each file says how long it ran and its exit status.
#
# Sizes are larger than llvmpipe's (a GPU draws 640x360 in well under a millisecond, the timer's noise):
# frames at 1600x900 (under `iqc render`'s threshold of 2 megapixels for drawing in bands), `iqc bench` at
# 320x180 (its reference is the double-precision evaluator on the CPU, which grows with the pixels).
# NVIDIA's shader disk cache is off (__GL_SHADER_DISK_CACHE=0), as Mesa's is for llvmpipe, so that every
# compile is measured. The renderer is the first EGL display that works (compiler/render/Render.cpp; IQC_EGL_PLATFORM=surfaceless,
# device or default picks one).
#
# The parts, in this order (each its time limit): handwritten (400 s: 8 scenes took 46 s each on an H200),
# ablate (150 s), hierarchy (70 s), instances (50 s), bench (110 s). All of them outrun one 10-minute command:
# run `handwritten ablate` in one, the rest in another.
#
#   bench/gpu.sh /tmp/gpu                      # after scripts/build.sh, on the machine with the GPU: every part
#   bench/gpu.sh /tmp/gpu handwritten ablate   # those two (about 9 minutes)
set -uo pipefail
out=$(realpath -m "${1:?usage: bench/gpu.sh OUT [PART...]}")  # before the cd: a relative OUT is the caller's
shift
parts=" ${*:-handwritten ablate hierarchy instances bench} "
cd "$(dirname "$0")/.."
mkdir -p "$out"
export __GL_SHADER_DISK_CACHE=0 MESA_SHADER_CACHE_DISABLE=true

part() {  # part NAME SECONDS COMMAND... (only the parts asked for)
  local name=$1 limit=$2 t0=$SECONDS rc
  shift 2
  [[ "$parts" == *" $name "* ]] || return 0
  timeout "$limit" "$@" > "$out/$name.body" 2>&1
  rc=$?
  { echo "# $name: $((SECONDS - t0)) s, exit $rc$([ $rc = 124 ] && echo " (stopped at its ${limit} s limit)")"; cat "$out/$name.body"; } > "$out/$name.txt"
  rm -f "$out/$name.body"
  echo "$name: $((SECONDS - t0)) s, exit $rc"
}

if ! ./build/iqc render bench/few_shapes.iq --size 64x36 -o "$out/smoke.png" 2> "$out/smoke.txt"; then
  cat "$out/smoke.txt"
  echo "gpu.sh: no renderer; nothing measured" >&2
  exit 1
fi
cat "$out/smoke.txt"
part handwritten 400 env SIZE=1600x900 FRAMES=21 ROUNDS=7 bench/handwritten.sh
part ablate 150 bench/ablate.sh
part hierarchy 70 env SIZE=1600x900 FRAMES=11 ROUNDS=5 bench/hierarchy.sh 10 100 1000
part instances 50 env LLVMPIPE_SIZES="10 100 1000" bench/instances.sh 10 100 1000
# `iqc bench` per scene into a folder beside OUT, packed into OUT/bench.tar.gz at the end, whether or not
# the part ran to its end (a lease returns a few files only).
[[ "$parts" == *" bench "* ]] && mkdir -p "$out.bench"
part bench 110 bash -c 'for s in "$@"; do
    ./build/iqc bench "bench/$s.iq" --size 320x180 --csv "$0/$s.csv" > "$0/$s.txt" 2>&1 || echo "bench $s: exit $?"
  done' "$out.bench" few_shapes displaced_torus twisted_bar fractal instances_100 grazing_thin sine_terrain twisted
if [[ "$parts" == *" bench "* ]]; then tar -C "$out.bench" -czf "$out/bench.tar.gz" .; fi
