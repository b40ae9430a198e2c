#!/usr/bin/env bash
# Installs what iqc needs to build and test on a fresh Debian (bookworm) machine.
# Only packages that are missing are installed; `apt-get update` runs once, and only
# when something is missing. Run as root (or with sudo available).
set -euo pipefail

PKGS=(
  build-essential cmake pkg-config
  glslang-dev glslang-tools spirv-tools
  libcli11-dev libtomlplusplus-dev libfmt-dev catch2
  libpng-dev libegl-dev libgles-dev libegl-mesa0 libgl1-mesa-dri
  nlohmann-json3-dev
  nodejs libcpp-httplib-dev
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: everything is installed"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
