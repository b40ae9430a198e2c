#!/usr/bin/env bash
# Writes a generated module of N statements (default 5000) to standard output: a chain of vector and
# scalar statements using names, subscripts, norms, products, min/max and trigonometry, for timing the
# front end:  bench/gen_module.sh 5000 > /tmp/big.iql && ./build/iqc eval /tmp/big.iql --time-passes
set -euo pipefail
n=${1:-5000}
awk -v n="$n" 'BEGIN {
  print "sin, cos from trigonometry"
  print "`v0` = p"
  for (i = 1; i < n - 1; i++) {
    a = i - 1; b = (i > 1) ? i - 2 : 0
    k = i % 4
    if (k == 0) printf "`v%d` = (cos(`v%d`_1), sin(`v%d`_2), `v%d`_3/2) + s`v%d`\n", i, a, a, b, b
    else if (k == 1) printf "`v%d` = ‖`v%d`‖(1, 0, 0) - max(`v%d`_1, 0.5)`v%d`\n", i, a, b, a
    else if (k == 2) printf "`v%d` = `v%d`∘(s, 2, 3)/(1 + ‖`v%d`‖²)\n", i, a, b
    else printf "`v%d` = (`v%d`⋅`v%d`)(0.1, 0.2, 0.3) + ½`v%d`\n", i, a, b, a
  }
  printf "D = ‖`v%d`‖ - s\n", n - 2
  print "where"
  print "p ∈ ℝ³: point"
  print "s ∈ [0,1] default = 0.5: a scale"
}'
