#!/usr/bin/env bash
# Front-end benchmark (issue 3): lex + parse + check of a generated N-line module (default 5000),
# median of 11 runs, each a fresh process as a user runs it. Run after scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-5000}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
bench/gen_module.sh "$n" > "$tmp/module.iql"
for i in $(seq 11); do
  ./build/iqc eval "$tmp/module.iql" --time-passes 2>&1 >/dev/null | awk '/lex \+ parse \+ check/ {print $(NF-1)}'
done | sort -n | awk -v n="$n" '{a[NR]=$1} END {printf "front end (lex + parse + check), %d lines: median %.1f ms (min %.1f, max %.1f, 11 runs)\n", n, a[6], a[1], a[11]}'
