#!/usr/bin/env bash
# The demo command: installs what it needs, builds soft_shadows and renders the default built-in
# scene with the GPU soft-shadow pipeline (--mode soft, exact LUT mode, depth-buffer view samples,
# on llvmpipe when there is no GPU) to out/soft_shadows.png, checks it against the oracle
# (out/soft_shadows_reference.png, out/soft_shadows_error.png) and prints the JSON report. Extra
# arguments go to soft_shadows (e.g. --samples 1024, --scene ../shared/scenes/spot.obj).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/setup.sh" >&2
build=${PENUMBRA_BUILD_DIR:-$root/build}
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >&2
cmake --build "$build" -j"$jobs" --target soft_shadows >&2
mkdir -p "$root/out"
"$build/examples/soft_shadows" --scene builtin:torus_knot --mode soft --reference --out "$root/out/soft_shadows.png" --json "$@"
echo "wrote $root/out/soft_shadows.png, soft_shadows_reference.png and soft_shadows_error.png" >&2
