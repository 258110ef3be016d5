#!/usr/bin/env bash
# Install mpmfsi's dependencies from Debian (if missing) and build it.
# Usage: tools/setup.sh [BUILD_DIR [extra cmake args...]]    (idempotent)
# MPMFSI_EXTRA_PACKAGES (space-separated Debian packages) adds what only some callers need:
# tools/run_tests.sh brings the test tools (clang-format, ParaView and Xvfb for the rendering
# check) that the main job does not.
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$src/build}
shift || true

packages=(build-essential cmake pkg-config libopenmpi-dev openmpi-bin libhdf5-openmpi-dev
          hdf5-tools libsundials-dev libinih-dev libmatheval-dev libcmocka-dev python3-h5py python3-numpy
          python3-matplotlib python3-scipy libxml2-utils)
read -r -a extra <<< "${MPMFSI_EXTRA_PACKAGES:-}"
packages+=("${extra[@]}")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  sudo_=""; [ "$(id -u)" -eq 0 ] || sudo_="sudo"
  $sudo_ apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo_ apt-get -o DPkg::Lock::Timeout=600 install -y -q "${missing[@]}"
fi

cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
cmake --build "$build" -j "$(nproc)"
