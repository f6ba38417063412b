#!/usr/bin/env bash
# Installs the Debian packages Atelier needs, only those missing.
# Usage: scripts/install-deps.sh [--bench]   (--bench adds the optional peers)
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config
      libtbb-dev libeigen3-dev libembree-dev libopenvdb-dev libboost-iostreams-dev
      libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libcli11-dev libfmt-dev libcgal-dev
      zlib1g-dev chromium libopenmpi-dev openmpi-bin)
if [[ "${1:-}" == "--bench" ]]; then
  pkgs+=(libopenmesh-dev libnanoflann-dev)
fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}"
  SUDO=""
  [[ $(id -u) -ne 0 ]] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
