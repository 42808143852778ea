#!/usr/bin/env bash
# The demo command: installs what it needs, builds soft_shadows and renders the default built-in
# scene to out/soft_shadows.png, printing the JSON report. Extra arguments go to soft_shadows.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/setup.sh" >&2
build=${PENUMBRA_BUILD_DIR:-$root/build}
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >&2
cmake --build "$build" -j"$jobs" --target soft_shadows >&2
mkdir -p "$root/out"
"$build/examples/soft_shadows" --scene builtin:torus_knot --out "$root/out/soft_shadows.png" --json "$@"
echo "wrote $root/out/soft_shadows.png" >&2
