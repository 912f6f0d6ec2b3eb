#!/usr/bin/env bash
# Installs the Debian 12 packages the build needs, only if some are missing (run as root);
# with --test, also those the test suite needs.
set -euo pipefail
PACKAGES=(build-essential cmake ninja-build libtbb-dev libeigen3-dev libspdlog-dev nlohmann-json3-dev libcli11-dev
          libgtest-dev libgmock-dev libbenchmark-dev libpng-dev libhwy-dev python3 python3-numpy python3-matplotlib
          libopenvdb-dev libboost-iostreams-dev  # OpenVDB (its find module also asks for Boost.Iostreams)
          clang libclang-rt-14-dev)  # clang + its runtime: libFuzzer for tools/fuzz.sh
# --test: also the programs the tests open the outputs with (ParaView's pvbatch, headless
# under xvfb-run, and Blender).
if [ "${1:-}" = "--test" ]; then
  PACKAGES+=(paraview python3-paraview xvfb xauth blender)
fi
missing=()
for p in "${PACKAGES[@]}"; do
  [[ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null)" == *"install ok installed"* ]] || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
