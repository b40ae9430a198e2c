#!/usr/bin/env bash
# tests/cmake_package_test.sh BUILD_DIR SOURCE_DIR GENERATOR
#
# iqc as an engine build step (issue 14): installs the build into a fresh prefix (`cmake --install`), builds
# examples/cmake_consumer against it with GENERATOR ("Ninja" or "Unix Makefiles") through find_package(iqc)
# and iqc_add_shader(), then checks the depfile rebuild rules:
#   1. a second build runs no iqc;
#   2. editing the module the scene includes from a subfolder rebuilds the shaders, with the edit in them;
#   3. an edit that changes no output byte (a comment) reruns iqc but leaves the outputs' times alone.
set -euo pipefail
BUILD="$1"; SRC="$2"; GEN="$3"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

cmake --install "$BUILD" --prefix "$tmp/prefix" >/dev/null
[ -x "$tmp/prefix/bin/iqc" ] || fail "no bin/iqc in the installed prefix"
[ -f "$tmp/prefix/lib/cmake/iqc/iqcConfig.cmake" ] || fail "no iqcConfig.cmake in the installed prefix"

cp -r "$SRC/examples/cmake_consumer" "$tmp/src"
cmake -S "$tmp/src" -B "$tmp/b" -G "$GEN" -DCMAKE_PREFIX_PATH="$tmp/prefix" >"$tmp/configure.log" 2>&1 ||
  { cat "$tmp/configure.log"; fail "configure"; }
build() { cmake --build "$tmp/b" 2>&1 | tee "$tmp/build.log"; [ "${PIPESTATUS[0]}" -eq 0 ] || fail "build"; }
out="$tmp/b/shaders/scene.webgl2.frag"
st="$tmp/b/shaders/scene.frag"
meta="$tmp/b/shaders/scene.json"

build >/dev/null
for f in "$out" "$st" "$meta"; do [ -s "$f" ] || fail "$f was not generated"; done
grep -q "uniform" "$out" || fail "the webgl2 shader has no uniforms"
grep -q "mainImage" "$st" || fail "the shadertoy shader has no mainImage"
grep -q '"R"' "$meta" || fail "the JSON description lacks the ring's parameter R"
"$tmp/b/viewer" | grep -q "bytes" || fail "the consumer program did not read the shader"
grep -q "ring.iql" "$tmp/b/CMakeFiles/scene_webgl2.iqc.d" || fail "the depfile does not name the included module"

# 1. Nothing changed: no iqc run.
build >/dev/null
grep -q "iqc: scene_" "$tmp/build.log" && fail "a build with nothing changed ran iqc again"

# 2. Edit the included module (subfolder): both shaders rebuild with the new default.
sleep 1.1  # file times of one-second resolution
sed -i 's/default = 1.2: ring radius/default = 1.7: ring radius/' "$tmp/src/shaders/modules/ring.iql"
build >/dev/null
grep -q "iqc: scene_webgl2" "$tmp/build.log" || fail "editing the included module did not rebuild scene_webgl2"
grep -q "iqc: scene_shadertoy" "$tmp/build.log" || fail "editing the included module did not rebuild scene_shadertoy"
grep -q "1\.7" "$st" || fail "the rebuilt shadertoy shader lacks the edited default 1.7"
grep -q "1\.7" "$meta" || fail "the rebuilt description lacks the edited default 1.7"

# 3. An edit no output shows (a comment line): iqc runs, the outputs keep their modification times.
before=$(stat -c %Y.%N "$out" "$st" "$meta" | md5sum)
sleep 1.1
printf '%s\n' '# ring: a torus by its radii' | cat - "$tmp/src/shaders/modules/ring.iql" > "$tmp/ring" &&
  mv "$tmp/ring" "$tmp/src/shaders/modules/ring.iql"
build >/dev/null
grep -q "iqc: scene_webgl2" "$tmp/build.log" || fail "editing the included module (a comment) did not run iqc"
after=$(stat -c %Y.%N "$out" "$st" "$meta" | md5sum)
[ "$before" = "$after" ] || fail "outputs whose bytes did not change were rewritten"
echo "cmake package with $GEN: ok"
