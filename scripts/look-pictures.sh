#!/usr/bin/env bash
# Regenerates docs/look/*.png, the pictures of docs/look.md: one scene lit term by term (sun, its shadow, sky,
# bounce, ambient occlusion, the sRGB output and a sky background, a tone map, Fresnel), rendered by `iqc render`.
#
#   scripts/look-pictures.sh            # uses ./build/iqc
#   IQC=path/to/iqc SIZE=320x180 scripts/look-pictures.sh
#   TIMES=7 scripts/look-pictures.sh   # also the median frame time of 7 renders per picture
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
IQC="${IQC:-$ROOT/build/iqc}"
SIZE="${SIZE:-320x180}"
OUT="docs/look"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT
mkdir -p "$OUT"

# The scene: a ground, a red ball, a gold torus and a mirror ball (stdlib pbr), seen from a little above.
base() {
  cat <<'TOML'
[camera]
position = [0, 1.6, -5]
target = [0, 0.5, 0]
fov = 45

[render]
normals = "analytic"
max_dist = 60
TOML
  echo "$1"
  cat <<'TOML'

[[shapes]]
name = "ground"
type = "plane"
shape_params = { h = 0 }
material = "pbr"
material_params = { k_d = [0.18, 0.17, 0.16], rho = 0.6 }

[[shapes]]
name = "ball"
type = "sphere"
transform = "T((-1.1, 1, 0.6))"
material = "pbr"
material_params = { k_d = [0.75, 0.12, 0.08], rho = 0.35 }

[[shapes]]
name = "gold"
type = "torus"
transform = "T((1.3, 0.35, -0.3))"
material = "pbr"
material_params = { k_d = [1.0, 0.77, 0.34], m = 1, rho = 0.3 }

[[shapes]]
name = "mirror"
type = "sphere"
transform = "T((1.2, 0.6, 1.8))"
shape_params = { r = 0.6 }
material = "pbr"
material_params = { k_d = [0.9, 0.9, 0.9], m = 1, rho = 0.15, k_r = 0.85 }
TOML
}

SUN='[[lights]]
name = "sun"
direction = [-0.55, 0.7, -0.45]
color = [1.5, 1.35, 1.15]'
SKY='[[lights]]
name = "sky"
type = "sky"
color = [0.16, 0.22, 0.34]'
BOUNCE='[[lights]]
name = "bounce"
type = "bounce"
color = [0.2, 0.15, 0.1]'
LINEAR='output = "linear"
background = [0.05, 0.05, 0.08]'
GRADIENT='background = { zenith = [0.12, 0.28, 0.65], horizon = [0.55, 0.64, 0.8] }'

picture() {  # picture NAME RENDER-LINES EFFECTS-LINES LIGHTS
  { base "$2"; printf '\n[effects]\n%s\n\n%s\n' "$3" "$4"; } > "$TMP/$1.iq"
  local line times=() k
  line="$("$IQC" render "$TMP/$1.iq" -o "$OUT/$1.png" --size "$SIZE" 2>&1 | tail -1)"
  # TIMES=N: the median frame time of N more renders (what the term costs on this machine's renderer).
  for ((k = 0; k < ${TIMES:-0}; k++)); do
    times+=("$("$IQC" render "$TMP/$1.iq" -o "$TMP/t.png" --size "$SIZE" 2>&1 | tail -1 | sed -E 's/.*frame ([0-9.]+) ms.*/\1/')")
  done
  if [ ${#times[@]} -gt 0 ]; then
    echo "$1: median frame $(printf '%s\n' "${times[@]}" | sort -n | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}') ms of ${#times[@]}"
  else
    echo "$1: ${line#*llvmpipe}"  # the shader compile and frame times iqc render measured
  fi
}
picture 1_sun        "$LINEAR"   ""                                      "$SUN"
picture 2_shadow     "$LINEAR"   'shadows = "soft"'                      "$SUN"
picture 3_sky        "$LINEAR"   'shadows = "soft"'                      "$SUN
$SKY"
picture 4_bounce     "$LINEAR"   'shadows = "soft"'                      "$SUN
$SKY
$BOUNCE"
picture 5_ao         "$LINEAR"   'shadows = "soft"
ao = true'                                                               "$SUN
$SKY
$BOUNCE"
picture 6_srgb       "$GRADIENT" 'shadows = "soft"
ao = true'                                                               "$SUN
$SKY
$BOUNCE"
picture 7_fresnel    "$GRADIENT" 'shadows = "soft"
ao = true
reflections = 2'                                                         "$SUN
$SKY
$BOUNCE"
picture 8_aces       "$GRADIENT
tonemap = \"aces\"
exposure = 1.2"                   'shadows = "soft"
ao = true
reflections = 2'                                                         "$SUN
$SKY
$BOUNCE"
echo "look-pictures: wrote $(ls "$OUT"/*.png | wc -l) pictures in $OUT/"
