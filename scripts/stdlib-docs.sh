#!/usr/bin/env bash
# Regenerates docs/stdlib.md (a reference of every stdlib/*.iql module) and the thumbnails
# docs/stdlib/<module>.png (shapes, and materials shown on a sphere), rendered with `iqc render`.
#
#   scripts/stdlib-docs.sh            # uses ./build/iqc
#   IQC=path/to/iqc JOBS=8 SIZE=128 scripts/stdlib-docs.sh
#
# Needs only bash, coreutils, mawk/gawk and xargs (what scripts/install-deps.sh gives a fresh machine).
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
IQC="${IQC:-$ROOT/build/iqc}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 4)}"
SIZE="${SIZE:-128}"
OUT_MD="docs/stdlib.md"
OUT_IMG="docs/stdlib"
export LC_ALL=C

if [ ! -x "$IQC" ]; then
  echo "stdlib-docs: $IQC not found (build first: cmake --build build -j8, or set IQC=)" >&2
  exit 2
fi

TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
# Work on a private copy, so a rebuild of the tree's iqc during the run does not break the renders.
cp "$IQC" "$TMP/iqc" && IQC="$TMP/iqc"
mkdir -p "$OUT_IMG"

# kind of a module: first non-blank line `shape` / `material`; a header-less file is a library
# (functions to import), and the operators module is listed as `operator`.
kind_of() {
  local f="$1" first
  first="$(awk 'NF { print $1; exit }' "$f")"
  case "$first" in
    shape|material) echo "$first" ;;
    *) case "$(basename "$f" .iql)" in *operator*) echo operator ;; *) echo library ;; esac ;;
  esac
}

# ---- 1. classify --------------------------------------------------------------------------------
: > "$TMP/modules.tsv"
for f in stdlib/*.iql; do
  m="$(basename "$f" .iql)"
  k="$(kind_of "$f")"
  case "$k" in shape) o=1 ;; material) o=2 ;; operator) o=3 ;; *) o=4 ;; esac
  printf '%s\t%s\t%s\n' "$o" "$k" "$m" >> "$TMP/modules.tsv"
done
sort -t$'\t' -k1,1n -k3,3 "$TMP/modules.tsv" -o "$TMP/modules.tsv"

# ---- 2. thumbnails (parallel) -------------------------------------------------------------------
mkdir -p "$TMP/scenes" "$TMP/logs"
scene_common() {
  cat <<'EOF'
[camera]
position = [2.4, 2.1, -3.9]
target = [0, 0, 0]
fov = 45

[render]
max_steps = 160
max_dist = 40
background = [0.92, 0.93, 0.95]
output = "linear"      # the thesis's look: the stdlib's default colours were chosen for it

[[lights]]
position = [-4, 6, -5]
color = [1, 1, 1]

EOF
}
while IFS=$'\t' read -r _ k m; do
  case "$k" in
    shape)
      { scene_common
        printf '[[shapes]]\ntype = "%s"\nmaterial = "lambert"\nmaterial_params = { k_d = [0.85, 0.55, 0.3] }\n' "$m"
      } > "$TMP/scenes/$m.iq" ;;
    material)
      { scene_common
        printf '[effects]\nreflections = 2\nrefraction = true\n\n'
        printf '[[shapes]]\nname = "ball"\ntype = "sphere"\nmaterial = "%s"\n\n' "$m"
        printf '[[shapes]]\nname = "floor"\ntype = "plane"\nmaterial = "checker"\nmaterial_params = { s = 0.75 }\n'
      } > "$TMP/scenes/$m.iq" ;;
  esac
done < "$TMP/modules.tsv"

export IQC TMP SIZE OUT_IMG
render_one() {
  local m="$1"
  if "$IQC" render "$TMP/scenes/$m.iq" -o "$OUT_IMG/$m.png" --size "${SIZE}x${SIZE}" > "$TMP/logs/$m.log" 2>&1; then
    :
  else
    echo "$m" >> "$TMP/failed.$m"
    rm -f "$OUT_IMG/$m.png"
  fi
}
export -f render_one
rm -f "$OUT_IMG"/*.png
( cd "$TMP/scenes" && ls *.iq 2>/dev/null | sed 's/\.iq$//' ) \
  | xargs -P "$JOBS" -I{} bash -c 'render_one "$@"' _ {}

# ---- 3. markdown --------------------------------------------------------------------------------
# One awk program per module turns the .iql into its section.
section_awk='
function esc(s) { gsub(/\|/, "\\|", s); return s }
function trim(s) { sub(/^[ \t]+/, "", s); sub(/[ \t]+$/, "", s); return s }
function code(s) { s = trim(s); gsub(/`/, "", s); return "`" s "`" }
# type and bounds from the text after "∈"
function typeof_(spec,   n) {
  if (spec ~ /^ℝ/) return spec
  n = split(spec, parts, /\]x\[/)
  return (n == 1) ? "ℝ" : (n == 2 ? "ℝ²" : (n == 3 ? "ℝ³" : "ℝ^" n))
}
{ lines[NR] = $0 }
END {
  # header / pragmas / leading description
  i = 1
  while (i <= NR && lines[i] ~ /^[ \t]*$/) i++
  if (kind == "shape" || kind == "material") i++
  desc = ""; exact = ""; lip = ""
  for (; i <= NR && lines[i] ~ /^[ \t]*#/; i++) {
    c = lines[i]; sub(/^[ \t]*#[ \t]?/, "", c)
    if (c ~ /^exact/) { exact = "exact"; continue }
    if (c ~ /^bound/) { exact = "bound"; continue }
    if (c ~ /^lipschitz/) { lip = c; sub(/^lipschitz[: \t]*/, "", lip); continue }
    if (c ~ /^[ \t]*$/) { if (desc != "") desc = desc "\n\n"; continue }
    desc = desc ((desc == "" || desc ~ /\n$/) ? "" : " ") c
  }
  body = i
  print "## " name
  print ""
  tag = "**Kind:** " kind
  if (kind == "shape") {
    if (exact == "") exact = "unmarked (treated as a bound)"
    tag = tag " · **distance:** " exact
    if (lip != "") tag = tag " · **Lipschitz factor:** " lip
  }
  tag = tag " · source: [`stdlib/" name ".iql`](../stdlib/" name ".iql)"
  print tag
  print ""
  if (desc != "") { print desc; print "" }
  if (img != "") { print "![" name "](stdlib/" name ".png)"; print "" }
  else if (kind == "shape" || kind == "material") { print "_(no thumbnail: " fail ")_"; print "" }

  if (kind == "shape" || kind == "material") {
    w = 0
    for (j = body; j <= NR; j++) if (lines[j] ~ /^where[ \t]*$/) { w = j; break }
    if (w == 0) w = NR + 1
    print "| Parameter | Type | Bounds | Default | Description |"
    print "|---|---|---|---|---|"
    for (j = w + 1; j <= NR; j++) {
      l = lines[j]
      if (l ~ /^[ \t]*$/ || l ~ /^[ \t]*#/) continue
      p = index(l, "∈"); if (p == 0) continue
      pname = substr(l, 1, p - 1); rest = trim(substr(l, p + length("∈")))
      d = ""; q = index(rest, ": ")
      if (q > 0) { d = trim(substr(rest, q + 2)); rest = trim(substr(rest, 1, q - 1)) }
      else if (rest ~ /:$/) { rest = substr(rest, 1, length(rest) - 1) }
      def = ""; q = index(rest, " default")
      if (q > 0) { def = trim(substr(rest, q + 8)); sub(/^=[ \t]*/, "", def); rest = trim(substr(rest, 1, q - 1)) }
      t = typeof_(rest); b = (rest ~ /^ℝ/) ? "" : rest
      print "| " code(pname) " | " t " | " (b == "" ? "—" : code(b)) " | " (def == "" ? "—" : code(def)) " | " esc(d == "" ? "—" : d) " |"
    }
    print ""
    print "```"
    for (j = body; j < w; j++) if (lines[j] !~ /^[ \t]*#/) print lines[j]
    print "```"
  } else {
    # library / operator: the functions it defines, with the comment lines just above each
    print "| Function | Description |"
    print "|---|---|"
    cm = ""
    for (j = body; j <= NR; j++) {
      l = lines[j]
      if (l ~ /^[ \t]*#/) { c = l; sub(/^[ \t]*#[ \t]?/, "", c); cm = cm (cm == "" ? "" : " ") c; continue }
      if (l ~ /^[ \t]*$/) { cm = ""; continue }
      if (match(l, /^`?[^ (=`]+`?\(/)) {
        sig = l; q = index(sig, ") ="); if (q > 0) sig = substr(sig, 1, q)
        print "| " code(sig) " | " esc(cm == "" ? "—" : cm) " |"
        cm = ""
      }
    }
    print ""
    print "<details><summary>source</summary>"
    print ""
    print "```"
    for (j = body; j <= NR; j++) print lines[j]
    print "```"
    print ""
    print "</details>"
  }
  print ""
}'

{
  echo "<!-- Generated by scripts/stdlib-docs.sh from stdlib/*.iql; do not edit by hand, re-run the script. -->"
  echo
  echo "# The standard library"
  echo
  n=$(wc -l < "$TMP/modules.tsv")
  echo "Every module in \`stdlib/\` ($n modules): shapes (signed distances, with their exact/bound tag), materials"
  echo "(shown on a sphere over a checkered floor), operators and libraries (functions to import). Each"
  echo "shape thumbnail is the module alone at its default parameters, lit by one light, seen from a fixed camera."
  echo
  echo "## Contents"
  echo
  prev=""
  while IFS=$'\t' read -r _ k m; do
    if [ "$k" != "$prev" ]; then
      [ -n "$prev" ] && echo
      case "$k" in shape) t="Shapes" ;; material) t="Materials" ;; operator) t="Operators" ;; *) t="Libraries" ;; esac
      printf -- '- **%s:** ' "$t"; sep=""; prev="$k"
    fi
    printf '%s[%s](#%s)' "$sep" "$m" "$(echo "$m" | tr -d '`')"; sep=", "
  done < "$TMP/modules.tsv"
  echo
  echo
  while IFS=$'\t' read -r _ k m; do
    img=""; fail=""
    if [ -f "$OUT_IMG/$m.png" ]; then img="$m.png"
    else fail="render failed: $(grep -m1 -i 'error' "$TMP/logs/$m.log" 2>/dev/null | tr '|' '/' | cut -c1-160 || true)"; fi
    awk -v name="$m" -v kind="$k" -v img="$img" -v fail="$fail" "$section_awk" "stdlib/$m.iql"
  done < "$TMP/modules.tsv"
} > "$OUT_MD"

nf=$(find "$TMP" -maxdepth 1 -name "failed.*" | wc -l)
echo "stdlib-docs: wrote $OUT_MD ($(wc -l < "$TMP/modules.tsv") modules) and $(find "$OUT_IMG" -maxdepth 1 -name "*.png" | wc -l) thumbnails in $OUT_IMG/ ($nf failed)"
for f in "$TMP"/failed.*; do
  [ -e "$f" ] || continue
  m="${f##*/failed.}"; echo "  failed: $m: $(tail -n 3 "$TMP/logs/$m.log" | tr '\n' ' ')" >&2
done
