#!/usr/bin/env bash
# Installs the Debian packages penumbra's build, tests, benchmarks and examples need.
# Idempotent: only missing packages are installed (and apt-get update runs only then).
# Needs root (or sudo) on Debian 12; no network beyond Debian's archive.
set -euo pipefail

packages=(
  cmake make g++ pkg-config
  libglm-dev doctest-dev libbenchmark-dev
  python3-glad                       # glad 2 generator, run with --reproducible (no network)
  libegl-dev libegl1 libegl-mesa0 libgl-dev libgl1-mesa-dri   # EGL surfaceless + llvmpipe
  libosmesa6 libosmesa6-dev          # the second headless backend
  glslang-tools                      # glslangValidator for the shader tests
  libtinyobjloader-dev libstb-dev    # penumbra::support: OBJ scenes, PNG output
  libcli11-dev nlohmann-json3-dev    # soft_shadows: command line, JSON report
  clang libclang-rt-14-dev           # the libFuzzer target on the OBJ loader (tests/fuzz)
  libepoxy-dev                       # a second GL loader, for the consumer test
  libgmp-dev                         # exact rational signs in blocker_filter_test
  libmeshoptimizer-dev               # support/scene/weld.hpp: welding split vertices (bent normals)
  python3-matplotlib                 # tools/plot_bench.py, tools/plot_lut_error.py (their ctest plots)
  libembree-dev                      # benchmarks/penumbra_casting_bench.cpp: Embree 3 shadow rays, the baseline
  patchelf                           # tools/gpu_bundle.sh: rpath $ORIGIN/../lib on the bundled binaries
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi
echo "setup: installing ${missing[*]}"
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
$sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
