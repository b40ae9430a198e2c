#!/usr/bin/env bash
# Installs what iqc needs to build and test on a fresh Debian (bookworm) machine; with --main, only what
# iqc itself needs to build and run (no test tools, browser, Node or clang).
# Only packages that are missing are installed; `apt-get update` runs once, and only
# when something is missing. Run as root (or with sudo available). Then the browser tests'
# npm packages (tests/browser/package-lock.json: playwright-core) are installed with `npm ci`.
set -euo pipefail
cd "$(dirname "$0")/.."

# What iqc itself needs (`--main`: the README's main job, scripts/demo.sh) ...
PKGS=(
  build-essential cmake pkg-config
  glslang-dev spirv-tools libspirv-cross-c-shared-dev
  libcli11-dev libtomlplusplus-dev libfmt-dev
  libpng-dev libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri
  nlohmann-json3-dev libcpp-httplib-dev
)
MAIN_ONLY=0
[ "${1:-}" = "--main" ] && MAIN_ONLY=1
# ... and what the tests need besides (the default: scripts/test.sh, CI).
if [ $MAIN_ONLY -eq 0 ]; then
  PKGS+=(
    glslang-tools catch2 ninja-build
    imagemagick libmagickcore-6.q16-6-extra fonts-dejavu-core  # the accuracy plots render in ImageMagick too (its SVG coder, the plots' font)
    nodejs chromium
    clang libclang-rt-14-dev   # the sanitizer build and libFuzzer (scripts/sanitize.sh, scripts/fuzz.sh)
    python3                    # scripts/fuzz.sh's dictionary check, bench/ablate/variants.py (test [ablate])
  )
  # npm: Debian's package, unless a node distribution that bundles npm is already installed.
  if ! command -v npm >/dev/null 2>&1; then PKGS+=(npm); fi
fi

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: every Debian package is installed"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# Browser tests: playwright-core drives /usr/bin/chromium (no browser download).
[ $MAIN_ONLY -eq 1 ] && exit 0
if [ ! -d tests/browser/node_modules/playwright-core ] ||
   [ tests/browser/package-lock.json -nt tests/browser/node_modules/.package-lock.json ]; then
  echo "install-deps: npm ci in tests/browser"
  PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --prefix tests/browser --no-audit --no-fund
fi
