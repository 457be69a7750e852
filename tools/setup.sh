#!/usr/bin/env bash
# kdmesh setup: install Debian 12 dependencies (if missing), build, then run a goal.
#
#   bash tools/setup.sh demo    install + build + mesh the shipped models (README command 1)
#   bash tools/setup.sh test    install + build + run the whole test suite (README command 2)
#   bash tools/setup.sh sanitize  install + build with ASan/UBSan (CMake preset "sanitize") + run all tests
#   bash tools/setup.sh fuzz    install + run each libFuzzer target FUZZ_SECONDS (default 60) s
#   bash tools/setup.sh memcheck  install + build + valgrind memcheck of small end-to-end runs
#   bash tools/setup.sh build   install + build only
#   bash tools/setup.sh deps    install only
#
# Environment: BUILD_DIR (default: build), BUILD_TYPE (default: Release), JOBS (default: nproc).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
goal="${1:-build}"
BUILD_DIR="${BUILD_DIR:-build}"
BUILD_TYPE="${BUILD_TYPE:-Release}"
JOBS="${JOBS:-$(nproc)}"

# One package per line; keep sorted. Everything the build, the tests and the tools need.
PACKAGES=(
  build-essential
  calculix-ccx
  clang
  cmake
  gmsh
  gnuplot-nox
  libbenchmark-dev
  libcgal-dev
  libclang-rt-14-dev
  libcli11-dev
  libdeflate-dev
  libeigen3-dev
  libfmt-dev
  libgmp-dev
  libgtest-dev
  libhdf5-dev
  libopenmpi-dev
  libtbb-dev
  libtet1.5-dev
  libvtk9-dev
  libyaml-cpp-dev
  nlohmann-json3-dev
  openmpi-bin
  pybind11-dev
  python3-dev
  python3-dolfinx
  python3-meshio
  python3-netcdf4
  python3-numpy
  python3-pytest
  python3-scipy
  python3-vtk9
  tetgen
  time
  valgrind
  zlib1g-dev
)

install_deps() {
  local missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "setup: all ${#PACKAGES[@]} Debian packages present"
    return
  fi
  echo "setup: installing ${#missing[@]} missing package(s): ${missing[*]}"
  local sudo=()
  [ "$(id -u)" -eq 0 ] || sudo=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

build() {
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE="$BUILD_TYPE"
  cmake --build "$BUILD_DIR" -j "$JOBS"
}

case "$goal" in
  deps)  install_deps ;;
  build) install_deps; build ;;
  test)
    install_deps; build
    KDMESH_REQUIRE_CLIENTS=1 ctest --test-dir "$BUILD_DIR" --output-on-failure -j "$JOBS"
    ;;
  sanitize)
    install_deps
    cmake --preset sanitize
    cmake --build --preset sanitize -j "$JOBS"
    KDMESH_REQUIRE_CLIENTS=1 ctest --preset sanitize -j "$JOBS" -LE solver  # the CalculiX solves run in the Release stage
    ;;
  fuzz)
    # Each libFuzzer target for FUZZ_SECONDS (default 60) under ASan + UBSan (issue 6).
    install_deps
    bash tests/fuzz/run.sh "${FUZZ_SECONDS:-60}"
    ;;
  memcheck)
    install_deps; build
    bash tools/memcheck.sh "$BUILD_DIR"
    ;;
  demo)
    install_deps; build
    "$BUILD_DIR/kdmesh" batch models/all.yaml --jobs 2 --out-dir out
    echo "setup: wrote out/gearbox.vtu and out/block.vtu (summaries: out/*.json), the gear box assembly for FEniCSx and MOOSE: out/gearbox.xdmf (+ .h5), out/gearbox.exo, and the block for solvers: out/block.msh, out/block.inp"
    ;;
  *) echo "usage: bash tools/setup.sh {demo|test|sanitize|fuzz|memcheck|build|deps}" >&2; exit 2 ;;
esac
