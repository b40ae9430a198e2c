#!/usr/bin/env bash
# bench/rings.sh N [LAYOUT [BOUND]] > scene.iq
#
# The many-instances benchmark scene (bench/instances.sh, bench/hierarchy.sh): a ground and N rings on a
# grid of 10-ring layers, one shape and one material, each ring with its own constant transform. LAYOUT
# `grid` (default) places them on a lattice; `irregular` jitters and tilts them (their tables stay tables);
# `moving` tilts each on the grid by an angle that changes with time (instances of their own, each
# inverted once per pixel: no group).
# BOUND > 0 gives every ring `bound = BOUND` (from 16 rings on, a bounding-volume hierarchy).
set -euo pipefail
awk -v n="$1" -v layout="${2:-grid}" -v bound="${3:-0}" 'BEGIN {
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
    if (layout == "moving")
      t = sprintf("T((%g, %g, %g))⋅`R_x`(0.5 time + %.3f)", x, y, z, 0.4 * (i % 7))
    else if (layout == "irregular")
      t = sprintf("T((%.4f, %.4f, %.4f))⋅`R_x`(%.3f)", x + 0.3 * (rand() - 0.5), y, z + 0.3 * (rand() - 0.5), 0.4 * (i % 7))
    else
      t = sprintf("T((%g, %g, %g))", x, y, z)
    print "[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"" t "\""
    if (bound > 0) print "bound = " bound
  }
}'
