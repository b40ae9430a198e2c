#!/usr/bin/env bash
# Regenerates docs/accuracy.md and docs/accuracy/*.{csv,svg}: `iqc bench` on every scene in bench/ at
# 160×90. Run after scripts/build.sh. Frame times vary from run to run; evaluations and errors do not.
set -euo pipefail
cd "$(dirname "$0")/.."
out=docs/accuracy
mkdir -p "$out"
size=${SIZE:-160x90}
# REPORT_ONLY=1 rebuilds the page and the plots from the existing results without measuring again.
if [ -z "${REPORT_ONLY:-}" ]; then
for f in bench/*.iq; do
  name=$(basename "$f" .iq)
  echo "bench $name ..." >&2
  ./build/iqc bench "$f" --size "$size" --csv "$out/$name.csv" --plot "$out/$name.svg" > "$out/$name.txt"
done
else  # the plots again from the measurements
for f in bench/*.iq; do
  name=$(basename "$f" .iq)
  ./build/iqc bench "$f" --replot "$out/$name.csv" --plot "$out/$name.svg"
done
fi
{
  cat docs/accuracy.intro.md
  for f in bench/*.iq; do
    name=$(basename "$f" .iq)
    title=$(sed -n 's/^title = "\(.*\)"/\1/p' "$f")
    echo
    echo "## $title (\`$f\`)"
    echo
    # The header: the run, the references, and each item's Lipschitz bound (derived by the compiler).
    sed -n '1,/^$/p' "$out/$name.txt" | grep . | sed 's/^/> /; s/$/  /'
    echo
    echo "![scene evaluations per pixel against depth error, log axes, the Pareto front named](accuracy/$name.svg)"
    echo
    echo "The five march methods at hit 1e-3, 256 steps, tetrahedron normals, I♥IQ's per-instance architecture, and the"
    echo "oracle (the fewest evaluations any march certified by overlapping unbounding spheres can take; not timed):"
    echo
    echo "| method | frame ms | evals/px (mean) | evals/px (p99) | miss % | depth err p99 | normal err p99 (°) | PSNR (dB) |"
    echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
    awk -F, 'NR > 1 && (($2 == "0.001" && $3 == "256" && $4 == "tetrahedron") || $1 == "per_instance") {
      printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, ($5 == "nan" ? "—" : $5), $6, $7, $8, $9, $10, $11 }' "$out/$name.csv"
    echo
    echo "Normal methods (sphere tracing, hit 1e-3, 256 steps):"
    echo
    echo "| normals | frame ms | evals/px (mean) | normal err p99 (°) |"
    echo "| --- | --- | --- | --- |"
    awk -F, 'NR > 1 && $1 == "sphere" && $2 == "0.001" && $3 == "256" { printf "| %s | %s | %s | %s |\n", $4, $5, $6, $10 }' "$out/$name.csv"
    echo
    echo "Full results: [$name.csv](accuracy/$name.csv)."
  done
} > docs/accuracy.md
echo "wrote docs/accuracy.md" >&2
