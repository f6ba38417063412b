#!/usr/bin/env bash
# Installs the Debian packages Atelier needs, only those missing.
# Usage: scripts/install-deps.sh [--test] [--bench] [--fuzz]
#   (none)   what the library and the CLI need (`make demo`)
#   --test   adds GoogleTest, Chromium (HTML report test) and Open MPI (the
#            2-rank regen test; the CLI uses MPI when it is installed)
#   --bench  adds Google Benchmark and the optional peers (OpenMesh, nanoflann)
#   --fuzz   adds Debian's clang and libFuzzer (`make fuzz`, docs/reliability.md)
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config
      libtbb-dev libeigen3-dev libembree-dev libopenvdb-dev libboost-iostreams-dev
      nlohmann-json3-dev libcli11-dev libcgal-dev zlib1g-dev libpng-dev)
for arg in "$@"; do
  case "$arg" in
    --test) pkgs+=(libgtest-dev libgmock-dev chromium libopenmpi-dev openmpi-bin) ;;
    --bench) pkgs+=(libbenchmark-dev libopenmesh-dev libnanoflann-dev) ;;
    --fuzz) pkgs+=(clang libfuzzer-14-dev) ;;
    *) echo "install-deps: unknown option $arg (use --test, --bench, --fuzz)" >&2; exit 2 ;;
  esac
done
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
