#!/usr/bin/env bash
# Installs the Debian 12 packages crackle needs (only those missing), then configures and builds
# into build/. Usage: scripts/build.sh [extra cmake arguments]
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(
  g++ cmake make ninja-build pkg-config
  libeigen3-dev libpetsc-real-dev libptscotch-dev libslepc-real-dev libarpack2-dev libfftw3-dev
  libsuitesparse-dev libceres-dev libyaml-cpp-dev libgtest-dev libcli11-dev nlohmann-json3-dev
  libopenblas0-pthread openmpi-bin gnuplot-nox
  pybind11-dev pybind11-json-dev python3-dev python3-numpy python3-pytest python3-matplotlib
  python3-petsc4py-real
)
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "scripts/build.sh: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Ninja when present (ninja-build, in the list above): it schedules the two cores better than make
# across targets (docs/benchmarks.md, "Build and test time"). A build/ configured earlier keeps its
# generator.
generator=()
if [ ! -f build/CMakeCache.txt ] && command -v ninja > /dev/null; then generator=(-G Ninja); fi
cmake -S . -B build "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@" > build.log 2>&1 || { cat build.log; exit 1; }
cmake --build build -j"$(nproc)" >> build.log 2>&1 || { tail -n 60 build.log; exit 1; }
echo "scripts/build.sh: built build/apps/crackle (log in build.log)"
