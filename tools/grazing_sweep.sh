#!/usr/bin/env bash
# Issue 41 item 1: the grazing light (8, 0.02, 0.5), radius 0.01, at 128 x 96 against the oracle
# (--reference: mismatched_bits) for N = 128 and 1024, --lut exact and brute, over skip
# combinations. Usage: tools/grazing_sweep.sh [BUILD_DIR] [all64]; run from the repository root
# (the demo finds its default scene there). Default combinations: none, each skip alone, every
# pair with fit or silhouette, all; all64: every subset of the six soft skips. Prints a TSV table.
set -euo pipefail
build=${1:-build}
exe=$(find "$build" -type f -name soft_shadows -perm -u+x | head -n 1)
light=${LIGHT:-8,0.02,0.5}
out=$(mktemp -d)
skips=(empty cull cut fit silhouette wedge)
combos=()
if [[ "${2:-}" == all64 ]]; then
    for ((m = 0; m < 64; ++m)); do
        c=""
        for ((i = 0; i < 6; ++i)); do ((m >> i & 1)) && c="${c:+$c,}${skips[i]}"; done
        combos+=("${c:-none}")
    done
else
    combos=(none empty cull cut fit silhouette wedge fit,silhouette fit,cut fit,wedge fit,empty fit,cull silhouette,cut
            silhouette,wedge silhouette,empty silhouette,cull all)
fi
printf 'N\tlut\tskips\tmismatched_bits\tmismatched_view_samples\tties\tpairs_hard\n'
for n in ${NS:-128 1024}; do
    for lut in ${LUTS:-exact brute}; do
        for c in "${combos[@]}"; do
            PENUMBRA_GL=egl "$exe" --mode soft --lut "$lut" --samples "$n" --reference --width 128 --height 96 \
                --light-pos "$light" --light-radius 0.01 --skips "$c" --json --out "$out/f.png" > "$out/r.json" 2> "$out/err" ||
                { printf '%s\t%s\t%s\tFAILED\n' "$n" "$lut" "$c"; continue; }
            /usr/bin/python3 -c "
import json, sys
j = json.load(open('$out/r.json')); r = j['reference']; s = j['soft']
print('\t'.join(str(x) for x in ['$n', '$lut', '$c', r['mismatched_bits'], r['mismatched_view_samples'], r['ties'], s.get('pairs_hard', 0)]))"
        done
    done
done
rm -rf "$out"
