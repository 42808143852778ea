#!/usr/bin/env bash
# The anti-aliasing conservativeness sweep (issue: galoppo2010 eye-view AA): soft_shadows --mode hard
# --aa edge --reference over every built-in scene and every ../shared/scenes/*.obj, each under 3
# light positions (the scene's own, a high one front-right, one behind-left
# shadows), printing per run the edge pixels the oracle finds, the provable and Chebyshev stencils'
# misses (and the Chebyshev-with-inner-coverage stencil's), edge vs full, the flagged fractions and the RMSE of off / edge / full against 64 oracle
# points per pixel, then the totals. Every run's JSON goes to OUT_DIR/aa_sweep.jsonl and its images
# beside it. Exit status 1 if the provable stencil missed any edge pixel or edge != full anywhere.
#   tools/aa_sweep.sh [BUILD_DIR [OUT_DIR [extra soft_shadows flags...]]]
#   e.g. tools/aa_sweep.sh build out --width 256 --height 192 --aa-samples 8
# Defaults: build, out/aa_sweep, 160 x 120, 4 sub-samples; PENUMBRA_GL picks the backend.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${1:-$root/build}
out=${2:-$root/out/aa_sweep}
shift $(( $# < 2 ? $# : 2 ))
exe="$build/examples/soft_shadows"
[ -x "$exe" ] || { echo "aa_sweep: $exe not built (cmake --build $build --target soft_shadows)" >&2; exit 2; }
mkdir -p "$out"
scenes=(builtin:torus_knot builtin:columns builtin:hairball builtin:grass)
shared="$root/../shared/scenes"
if [ -d "$shared" ]; then
  for f in "$shared"/*.obj; do [ -e "$f" ] && scenes+=("$f"); done
else
  echo "aa_sweep: $shared is absent: built-in scenes only" >&2
fi
lights=(default 1.6,2.4,1.4 -1.4,2.6,-2.2)
jsonl="$out/aa_sweep.jsonl"
: > "$jsonl"
bad=0
hdr='%-10s %-14s %7s %7s %7s %8s %8s %8s %8s %8s %8s %8s %8s %8s\n'
printf "$hdr" scene light edge_px missed edge!=fu flagged cheb_mis cheb_flg inner_mis inner_flg rmse_off rmse_edge rmse_full rmse_cheb
for scene in "${scenes[@]}"; do
  name=$(basename "${scene#builtin:}" .obj)
  for light in "${lights[@]}"; do
    tag="${name}_${light//,/_}"
    args=(--mode hard --aa edge --reference --json --scene "$scene" --width 160 --height 120 --out "$out/$tag.png")
    [ "$light" = default ] || args+=(--light-pos "$light")
    json=$("$exe" "${args[@]}" "$@" 2> "$out/$tag.log") || { echo "aa_sweep: $tag failed:"; cat "$out/$tag.log"; bad=1; continue; }
    echo "$json" >> "$jsonl"
    row=$(printf '%s' "$json" | /usr/bin/python3 -c '
import json, sys
j = json.load(sys.stdin); r = j["reference"]; a = j["aa"]; k = a["stencils"]
print(r["edge_pixels"], r["provable_missed"], a["edge_vs_full_differing_pixels"], "%.4f" % a["flagged_fraction"],
      k["chebyshev"]["missed_edge_pixels"], "%.4f" % k["chebyshev"]["flagged_fraction"],
      k["chebyshev_inner"]["missed_edge_pixels"], "%.4f" % k["chebyshev_inner"]["flagged_fraction"],
      "%.4f" % a["rmse"]["off"], "%.4f" % a["rmse"]["edge"], "%.4f" % a["rmse"]["full"], "%.4f" % k["chebyshev"]["rmse_edge"])')
    read -r edge missed differ flagged cm cf im if r_off r_edge r_full r_cheb <<< "$row"
    printf "$hdr" "$name" "$light" "$edge" "$missed" "$differ" "$flagged" "$cm" "$cf" "$im" "$if" "$r_off" "$r_edge" "$r_full" "$r_cheb"
    if [ "$missed" != 0 ] || [ "$differ" != 0 ]; then bad=1; fi
  done
done
/usr/bin/python3 - "$jsonl" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
t = lambda f: sum(f(j) for j in rows)
m = lambda name: t(lambda j: j["aa"]["stencils"][name]["missed_edge_pixels"])
print("runs %d: edge pixels %d; missed: provable %d, chebyshev %d, chebyshev_inner %d; edge != full pixels %d"
      % (len(rows), t(lambda j: j["reference"]["edge_pixels"]), m("provable"), m("chebyshev"), m("chebyshev_inner"),
         t(lambda j: j["aa"]["edge_vs_full_differing_pixels"])))
PY
exit $bad
