#!/usr/bin/env bash
# Installs the Debian packages Atelier needs, only those missing.
# Usage: scripts/install-deps.sh [--test] [--bench]
#   (none)   what the library and the CLI need (`make demo`)
#   --test   adds GoogleTest, Chromium (HTML report test) and Open MPI (the
#            2-rank regen test; the CLI uses MPI when it is installed)
#   --bench  adds Google Benchmark and the optional peers (OpenMesh, nanoflann;
#            Node.js and npm for manifold-3d, installed into bench/net/manifold)
#   --test   adds GoogleTest, Chromium (HTML report test), Open MPI (the
#            2-rank regen test; the CLI uses MPI when it is installed) and
#            python3-ezdxf (the pattern tests read the DXF files back)
#   --bench  adds Google Benchmark and the optional peers (OpenMesh, nanoflann)
#   --test   adds GoogleTest, Chromium (HTML report test), Open MPI (the
#            2-rank regen test; the CLI uses MPI when it is installed) and
#            OpenSubdiv (oracle of the Catmull-Clark tests)
#   --bench  adds Google Benchmark and the optional peers (OpenMesh, nanoflann,
#            OpenSubdiv)
# Usage: scripts/install-deps.sh [--test] [--bench] [--python]
#   (none)    what the library and the CLI need (`make demo`)
#   --python  adds what the Python module needs (`make python`): pybind11,
#             the Python headers and NumPy, for Debian's /usr/bin/python3
#   --test    adds GoogleTest, Chromium (HTML report test), Open MPI (the
#             2-rank regen test; the CLI uses MPI when it is installed), and
#             the Python module's packages with pytest (its suite runs in
#             `make test`)
#   --bench   adds Google Benchmark and the optional peers (OpenMesh,
#             nanoflann), and the Python module's packages (the binding's
#             overhead benchmark embeds the interpreter)
set -euo pipefail
bench=0
pkgs=(build-essential cmake ninja-build pkg-config
      libtbb-dev libeigen3-dev libembree-dev libopenvdb-dev libboost-iostreams-dev
      nlohmann-json3-dev libcli11-dev libcgal-dev zlib1g-dev libpng-dev)
python=(pybind11-dev python3-dev python3-numpy)
for arg in "$@"; do
  case "$arg" in
    --test) pkgs+=(libgtest-dev libgmock-dev chromium libopenmpi-dev openmpi-bin) ;;
    --bench) pkgs+=(libbenchmark-dev libopenmesh-dev libnanoflann-dev nodejs npm); bench=1 ;;
    --test) pkgs+=(libgtest-dev libgmock-dev chromium libopenmpi-dev openmpi-bin python3-ezdxf) ;;
    --bench) pkgs+=(libbenchmark-dev libopenmesh-dev libnanoflann-dev) ;;
    --test) pkgs+=(libgtest-dev libgmock-dev chromium libopenmpi-dev openmpi-bin libosd-dev) ;;
    --bench) pkgs+=(libbenchmark-dev libopenmesh-dev libnanoflann-dev libosd-dev) ;;
    *) echo "install-deps: unknown option $arg (use --test, --bench)" >&2; exit 2 ;;
    --python) pkgs+=("${python[@]}") ;;
    --test) pkgs+=(libgtest-dev libgmock-dev chromium libopenmpi-dev openmpi-bin "${python[@]}" python3-pytest) ;;
    --bench) pkgs+=(libbenchmark-dev libopenmesh-dev libnanoflann-dev "${python[@]}") ;;
    *) echo "install-deps: unknown option $arg (use --test, --bench, --python)" >&2; exit 2 ;;
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
if ((bench)); then
  # The net Booleans' peer manifold-3d (bench/net/net_bench.cpp runs it with node).
  npm install --no-audit --no-fund --prefix "$(dirname "$0")/../bench/net/manifold" >/dev/null
fi
