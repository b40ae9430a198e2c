#!/usr/bin/env bash
# Hostile-input benchmarks (issue 16): reading must stay linear. Each case is a fresh process, median of
# 5 runs, wall time of the whole command (target: ≤ 2 s each). Run after scripts/build.sh.
#   instances   a scene of 10,000 [[shapes]] with transforms: `iqc SCENE` to the end of compilation,
#               and its "read scene" phase alone (the TOML reading that was quadratic)
#   letters     100,000 letters of names: one 100,000-letter run split into two declared 50,000-letter
#               names; 1,000 statements of 100-letter runs of one-letter names; and a 100,000-letter run
#               that almost matches known names everywhere (the cubic case: it ends in the nesting error)
set -euo pipefail
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 - "$tmp" <<'PY'
import sys
out = sys.argv[1]
with open(f"{out}/instances.iq", "w") as f:
    for i in range(10000):
        f.write(f'[[shapes]]\nname = "s{i}"\ntype = "sphere"\ntransform = "T(({i % 100}, {i // 100}, 0))"\n')
half = "ab" * 25000
with open(f"{out}/one_run.iql", "w") as f:
    f.write(f"y = {half}{half.upper()}\nwhere\n`{half}` ∈ ℝ default = 2\n`{half.upper()}` ∈ ℝ default = 3\n")
letters = "abcdefghij" * 10
with open(f"{out}/statements.iql", "w") as f:
    for k in range(1000):
        f.write(f"`y_{k}` = {letters}\n")
    f.write("where\n" + "".join(f"{c} ∈ ℝ default = 1\n" for c in "abcdefghij"))
with open(f"{out}/adversarial.iql", "w") as f:
    f.write("y = " + "ab" * 50000 + "\nwhere\na ∈ ℝ\nb ∈ ℝ\n`abab` ∈ ℝ\n`ababa` ∈ ℝ\n`bababab` ∈ ℝ\n")
PY
median() {  # median CMD...: seconds of 5 runs
  for i in 1 2 3 4 5; do
    s=$(date +%s.%N); "$@" >/dev/null 2>&1 || true; e=$(date +%s.%N)
    echo "$e - $s" | bc
  done | sort -n | sed -n 3p
}
phase() {  # the median of a --time-passes phase over 5 runs, ms
  for i in 1 2 3 4 5; do "${@:2}" --time-passes 2>&1 >/dev/null | awk -v p="$1" 'index($0, p) {print $(NF-1)}'; done |
    sort -n | sed -n 3p
}
printf 'instances: 10,000 shapes, whole compile            %6.2f s\n' "$(median ./build/iqc "$tmp/instances.iq" -o /dev/null)"
printf 'instances: 10,000 shapes, "read scene" phase       %6.1f ms\n' "$(phase 'read scene' ./build/iqc "$tmp/instances.iq" -o /dev/null)"
printf 'letters: one 100,000-letter run (two names)        %6.2f s\n' "$(median ./build/iqc eval "$tmp/one_run.iql")"
printf 'letters: 1,000 runs of 100 one-letter names        %6.2f s\n' "$(median ./build/iqc eval "$tmp/statements.iql")"
printf 'letters: adversarial 100,000-letter run            %6.2f s\n' "$(median ./build/iqc eval "$tmp/adversarial.iql")"
