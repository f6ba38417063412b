#!/usr/bin/env bash
# Installs the Debian packages Atelier needs, only those missing.
# Usage: scripts/install-deps.sh [--test] [--bench] [--python] [--fuzz]
#   (none)    what the library and the CLI need (`make demo`)
#   --python  adds what the Python module needs (`make python`): pybind11,
#             the Python headers and NumPy, for Debian's /usr/bin/python3
#   --test    adds GoogleTest, Chromium (HTML report test), Open MPI (the
#             2-rank regen test; the CLI uses MPI when it is installed),
#             OpenSubdiv (oracle of the Catmull-Clark tests), python3-ezdxf
#             (the pattern tests read the DXF files back) and the Python
#             module's packages with pytest (its suite runs in `make test`)
#   --bench   adds Google Benchmark and the optional peers (OpenMesh,
#             nanoflann, OpenSubdiv), and the Python module's packages (the
#             binding's overhead benchmark embeds the interpreter)
#   --fuzz    adds Debian's clang and libFuzzer (`make fuzz`, docs/reliability.md)
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config
      libtbb-dev libeigen3-dev libembree-dev libopenvdb-dev libboost-iostreams-dev
      nlohmann-json3-dev libcli11-dev libcgal-dev zlib1g-dev libpng-dev)
python=(pybind11-dev python3-dev python3-numpy)
for arg in "$@"; do
  case "$arg" in
    --python) pkgs+=("${python[@]}") ;;
    --test) pkgs+=(libgtest-dev libgmock-dev chromium libopenmpi-dev openmpi-bin libosd-dev python3-ezdxf
                   "${python[@]}" python3-pytest) ;;
    --bench) pkgs+=(libbenchmark-dev libopenmesh-dev libnanoflann-dev libosd-dev "${python[@]}") ;;
    --fuzz) pkgs+=(clang libfuzzer-14-dev) ;;
    *) echo "install-deps: unknown option $arg (use --test, --bench, --python, --fuzz)" >&2; exit 2 ;;
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
