#!/usr/bin/env bash
# run.sh [--smoke] [--tar] [OUTDIR] — penumbra's real-GPU tier, from a bundle tools/gpu_bundle.sh
# made (this file is its template, tools/gpu_bundle/run.sh). Needs only bash, coreutils (timeout),
# grep, sed and the machine's GL driver: no network, no package manager, no checkout.
#
# Steps, each under `timeout`, each one line in OUTDIR/summary.txt (status, seconds, step, detail)
# and one object in OUTDIR/summary.json:
#   1. gl_info: the GL context on the EGL device platform (vendor, renderer, version, subgroups,
#      fp64, timer queries) -> OUTDIR/gl_info.json, printed; nothing else runs without a context.
#   2. tests/NAME: every GL test's portable tier (PENUMBRA_TIER=portable: assertions that hold on
#      llvmpipe only report as skipped), doctest suite "stress" excluded -> OUTDIR/tests/NAME.log.
#      Run in parallel (PENUMBRA_BUNDLE_JOBS): they check results, they do not time anything.
#   3. bench/BLOCK: penumbra_bench once per block of share/bench_blocks.txt, one at a time,
#      --benchmark_format=json -> OUTDIR/bench/BLOCK.json (stderr: BLOCK.log). A timed-out block
#      keeps the entries it finished (the JSON reporter writes each as it ends; run.sh closes it).
#      Entries that no block's filter matches run last as the block "unlisted".
#   4. demo/MODE: soft_shadows --mode soft|hard --reference --json, and --mode reference --json
#      -> OUTDIR/demo/MODE.png (+ _reference/_error PNGs), MODE.json, MODE.log.
# Exit status 0 when every step passed, 1 when one failed, timed out or was skipped because the
# time budget ran out, 2 on bad arguments or no GL context.
#
# --smoke: the ctest's quick run on llvmpipe: the first test case of each test, one cheap entry
#   per block with PENUMBRA_BENCH_SMOKE=1, a 64 x 48 demo.
# --tar:   also writes OUTDIR.tar.gz (to carry the results back from the GPU machine).
#
# Time boxes (seconds; the whole run stays under PENUMBRA_BUNDLE_BUDGET, default 420 = 7 min:
# the tests' phase ends at 45% of it, the benchmarks' at 85%, the demo's at 100%; a step gets at
# most its own limit and what its phase has left, a benchmark block at most an equal share of it):
#   PENUMBRA_BUNDLE_BUDGET (420)       PENUMBRA_BUNDLE_TEST_TIMEOUT (120, smoke 60)
#   PENUMBRA_BUNDLE_BENCH_TIMEOUT (45, smoke 60)   PENUMBRA_BUNDLE_DEMO_TIMEOUT (60, smoke 60)
#   PENUMBRA_BUNDLE_BENCH_MIN_TIME (0.05, smoke 0.001)   PENUMBRA_BUNDLE_JOBS (nproc, at most 8)
#   PENUMBRA_BUNDLE_DEMO_SIZE (256x192, smoke 64x48)
# PENUMBRA_GL (egl) and PENUMBRA_TIER (portable) may be overridden too.
set -u

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
smoke=0
make_tar=0
out=""
for arg in "$@"; do
  case "$arg" in
    --smoke) smoke=1 ;;
    --tar) make_tar=1 ;;
    -h|--help) sed -n '2,/^set -u/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    -*) echo "run.sh: unknown option $arg (run.sh --help)" >&2; exit 2 ;;
    *) [ -z "$out" ] || { echo "run.sh: one OUTDIR only" >&2; exit 2; }; out=$arg ;;
  esac
done
out=${out:-$here/out}
# A rerun replaces its results; anything else in the way is left alone.
if [ -e "$out" ] && [ -n "$(ls -A "$out" 2>/dev/null)" ] && [ ! -e "$out/summary.txt" ] && [ ! -d "$out/.steps" ]; then
  echo "run.sh: $out exists and holds no run.sh results: pick another OUTDIR" >&2
  exit 2
fi
rm -rf "$out"
mkdir -p "$out/tests" "$out/bench" "$out/demo" || exit 2
out=$(cd "$out" && pwd)

# ---- environment: what the binaries read instead of the build machine's paths ----------------
export PENUMBRA_GL=${PENUMBRA_GL:-egl}
export PENUMBRA_TIER=${PENUMBRA_TIER:-portable}
export PENUMBRA_TEST_SHADER_DIR="$here/share/tests/shaders"
if [ -d "$here/share/scenes" ]; then
  export PENUMBRA_SHARED_SCENES_DIR="$here/share/scenes"
else
  export PENUMBRA_SHARED_SCENES_DIR="$here/share/no-scenes"  # absent: tests skip the OBJ scenes
fi
unset PENUMBRA_STRESS PENUMBRA_BENCH_SMOKE
# Mesa's and NVIDIA's shader caches want a writable home; keep them inside OUTDIR when there is none.
if [ -z "${HOME:-}" ] || [ ! -w "${HOME:-/nonexistent}" ]; then export HOME="$out/home"; mkdir -p "$HOME"; fi

if [ "$smoke" = 1 ]; then
  test_timeout=${PENUMBRA_BUNDLE_TEST_TIMEOUT:-60}
  bench_timeout=${PENUMBRA_BUNDLE_BENCH_TIMEOUT:-60}
  demo_timeout=${PENUMBRA_BUNDLE_DEMO_TIMEOUT:-60}
  bench_min_time=${PENUMBRA_BUNDLE_BENCH_MIN_TIME:-0.001}
  demo_size=${PENUMBRA_BUNDLE_DEMO_SIZE:-64x48}
  demo_samples=32
else
  test_timeout=${PENUMBRA_BUNDLE_TEST_TIMEOUT:-120}
  bench_timeout=${PENUMBRA_BUNDLE_BENCH_TIMEOUT:-45}
  demo_timeout=${PENUMBRA_BUNDLE_DEMO_TIMEOUT:-60}
  bench_min_time=${PENUMBRA_BUNDLE_BENCH_MIN_TIME:-0.05}
  demo_size=${PENUMBRA_BUNDLE_DEMO_SIZE:-256x192}
  demo_samples=128
fi
budget=${PENUMBRA_BUNDLE_BUDGET:-420}
jobs=${PENUMBRA_BUNDLE_JOBS:-$(nproc 2>/dev/null || echo 2)}
[ "$jobs" -gt 8 ] && jobs=8
start_all=$SECONDS

# ---- bookkeeping ----------------------------------------------------------------------------
# Each step leaves OUTDIR/.steps/NNN: "status<TAB>seconds<TAB>step<TAB>detail" (files, not shell
# variables, because the tests run in background subshells).
mkdir -p "$out/.steps"
step_index=0
record() {  # record STATUS SECONDS STEP [DETAIL]
  step_index=$((step_index + 1))
  printf '%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "${4:-}" > "$out/.steps/$(printf '%03d' "$step_index")"
  printf '%-8s %6ss  %s  %s\n' "$1" "$2" "$3" "${4:-}"
}
status_of() {  # status_of EXIT_CODE -> pass | timeout | fail
  case "$1" in 0) echo pass ;; 124|137) echo timeout ;; *) echo fail ;; esac
}
# Seconds a step may take: its own limit, capped by what the phase (ends at $1 seconds into the
# run) has left; 0 when nothing is left.
step_limit() {
  local phase_left=$(($1 - (SECONDS - start_all)))
  local limit=$2
  [ "$phase_left" -lt "$limit" ] && limit=$phase_left
  [ "$limit" -lt 0 ] && limit=0
  echo "$limit"
}
# Closes the JSON of a penumbra_bench that timeout killed: keeps the entries it finished (the JSON
# reporter writes each as it ends; an entry closes with a 4-space "}" line) so the file parses.
close_bench_json() {
  local file=$1 last
  last=$(grep -n '^    }$' "$file" | tail -1 | cut -d: -f1)
  if [ -n "$last" ]; then
    head -n "$last" "$file" > "$file.tmp"
  elif grep -q '^  "benchmarks": \[' "$file"; then
    sed -n '1,/^  "benchmarks": \[/p' "$file" > "$file.tmp"
  else
    return 0
  fi
  printf '\n  ]\n}\n' >> "$file.tmp" && mv "$file.tmp" "$file"
}
now_us() {  # microseconds since the epoch (bash 5's EPOCHREALTIME; date where it is missing)
  if [ -n "${EPOCHREALTIME:-}" ]; then echo "${EPOCHREALTIME/[.,]/}"; else echo $(($(date +%s%N) / 1000)); fi
}
elapsed() {  # elapsed START_US -> seconds with one decimal
  local us=$(($(now_us) - $1))
  printf '%d.%d' $((us / 1000000)) $((us / 100000 % 10))
}

echo "penumbra gpu bundle: $(head -3 "$here/manifest.txt" 2>/dev/null | tail -2 | tr '\n' ' ')"
echo "output: $out (smoke=$smoke, budget ${budget}s, PENUMBRA_GL=$PENUMBRA_GL, PENUMBRA_TIER=$PENUMBRA_TIER)"
{
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "host: $(uname -srm), $(nproc 2>/dev/null) cores"
  command -v nvidia-smi >/dev/null && timeout 20 nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1
  echo "glibc: $(ldd --version 2>/dev/null | head -1)"
  grep '^needs:' "$here/manifest.txt" 2>/dev/null
} > "$out/system.txt"

# ---- 1. gl_info ---------------------------------------------------------------------------------
t0=$(now_us)
timeout -k 5 30 "$here/bin/gl_info" > "$out/gl_info.json" 2> "$out/gl_info.log"
rc=$?
record "$(status_of $rc)" "$(elapsed "$t0")" gl_info "$(head -c 300 "$out/gl_info.log" | tr '\n\t' '  ')"
cat "$out/gl_info.json" "$out/gl_info.log"
if [ $rc -ne 0 ]; then
  echo "run.sh: no GL context (gl_info exit $rc); see $out/system.txt for the glibc the bundle needs" >&2
  gl_ok=0
else
  gl_ok=1
fi

# ---- 2. tests (parallel) -----------------------------------------------------------------------
# Phases end at fixed shares of the budget: tests 45%, benchmarks 85%, the demo the rest.
tests_end=$((budget * 45 / 100))
bench_end=$((budget * 85 / 100))
run_test() {  # run_test NAME LIMIT: writes tests/NAME.log and tests/NAME.result
  local name=$1 limit=$2 t rc detail
  t=$(now_us)
  # --duration: one "<seconds> s: <name>" line per test case that ran (doctest's closing counts
  # are of the cases passing the filters, also with --first/--last).
  local args=(--test-suite-exclude=stress --no-colors=true --duration=true)
  [ "$smoke" = 1 ] && args+=(--first=1 --last=1)
  timeout -k 5 "$limit" "$here/bin/$name" "${args[@]}" > "$out/tests/$name.log" 2>&1
  rc=$?
  # doctest's closing lines: "[doctest] test cases: 3 | 3 passed | 0 failed | 1 skipped"
  detail="ran $(grep -cE '^[0-9.]+ s: ' "$out/tests/$name.log"); "
  detail+=$(grep -E '^\[doctest\] (test cases|assertions):' "$out/tests/$name.log" | sed 's/^\[doctest\] //' | tr -s ' ' | paste -sd';' -)
  # gl_test_support.hpp's exit line: "penumbra-tier: N bitwise check(s) skipped ..." (docs/portable_tier.md)
  detail+=$(grep -m1 -o 'penumbra-tier: [0-9]* bitwise check(s) skipped' "$out/tests/$name.log" | sed 's/^/; /')
  [ "$rc" = 124 ] || [ "$rc" = 137 ] && detail="killed after ${limit}s; $detail"
  printf '%s\t%s\t%s\n' "$(status_of $rc)" "$(elapsed "$t")" "$detail" > "$out/tests/$name.result"
}
mapfile -t tests < "$here/share/gl_tests.txt"
running=0
for name in "${tests[@]}"; do
  limit=$(step_limit "$tests_end" "$test_timeout")
  if [ "$gl_ok" = 0 ] || [ "$limit" -le 0 ]; then
    printf 'skipped\t0\t%s\n' "$([ "$gl_ok" = 0 ] && echo "no GL context" || echo "time budget spent")" > "$out/tests/$name.result"
    continue
  fi
  run_test "$name" "$limit" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
done
wait
for name in "${tests[@]}"; do
  IFS=$'\t' read -r status seconds detail < "$out/tests/$name.result"
  record "$status" "$seconds" "tests/$name" "$detail"
done

# ---- 3. benchmarks (one block at a time: timings must not share the machine) ---------------------
bench_args=(--benchmark_format=json --benchmark_min_time="$bench_min_time")
blocks=()
filters=()
while IFS=$'\t' read -r block filter smoke_filter; do
  case "$block" in ''|'#'*) continue ;; esac
  [ "$filter" = "-" ] && continue  # not in penumbra_bench (bench_blocks.txt says why)
  blocks+=("$block")
  if [ "$smoke" = 1 ]; then filters+=("$smoke_filter"); else filters+=("$filter"); fi
done < "$here/share/bench_blocks.txt"
if [ "$smoke" = 1 ]; then export PENUMBRA_BENCH_SMOKE=1; fi
# Entries no block's filter matches (a benchmark added without its line) run as "unlisted".
if [ "$smoke" = 0 ] && [ "$gl_ok" = 1 ]; then
  all=$(IFS='|'; echo "${filters[*]}")
  unlisted=$("$here/bin/penumbra_bench" --benchmark_list_tests 2>/dev/null | grep -Ev "$all" | sed 's/[][().*+?^$|\\]/\\&/g; s/^/^/; s/$/$/' | paste -sd'|' -)
  if [ -n "$unlisted" ]; then blocks+=(unlisted); filters+=("$unlisted"); fi
fi
for i in "${!blocks[@]}"; do
  block=${blocks[$i]}
  # At most an equal share of what the phase has left, so one slow block cannot starve the
  # blocks after it (a block that finishes early leaves its rest to the others).
  share=$(( (bench_end - (SECONDS - start_all)) / (${#blocks[@]} - i) ))
  [ "$share" -lt "$bench_timeout" ] && limit=$share || limit=$bench_timeout
  limit=$(step_limit "$bench_end" "$limit")
  if [ "$gl_ok" = 0 ] || [ "$limit" -le 0 ]; then
    record skipped 0 "bench/$block" "$([ "$gl_ok" = 0 ] && echo "no GL context" || echo "time budget spent")"
    continue
  fi
  t0=$(now_us)
  timeout -k 5 "$limit" "$here/bin/penumbra_bench" --benchmark_filter="${filters[$i]}" "${bench_args[@]}" \
    > "$out/bench/$block.json" 2> "$out/bench/$block.log"
  rc=$?
  entries=$(grep -c '"run_name"' "$out/bench/$block.json")
  errors=$(grep -c '"error_occurred": true' "$out/bench/$block.json")
  detail="$entries entries"
  [ "$errors" -gt 0 ] && detail="$detail, $errors with errors" && [ "$rc" = 0 ] && rc=1
  # A filter that matches nothing measured nothing: a failure, not a pass (bench_blocks.txt is wrong).
  [ "$entries" = 0 ] && [ "$rc" = 0 ] && rc=1 && detail="no entry matched the filter ${filters[$i]}"
  if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
    detail="killed after ${limit}s; $detail"
    close_bench_json "$out/bench/$block.json"
  fi
  record "$(status_of $rc)" "$(elapsed "$t0")" "bench/$block" "$detail"
done
unset PENUMBRA_BENCH_SMOKE

# ---- 4. the demo ---------------------------------------------------------------------------------
width=${demo_size%x*}
height=${demo_size#*x}
for mode in soft hard reference; do
  args=(--mode "$mode" --json --width "$width" --height "$height" --out "$out/demo/$mode.png")
  [ "$mode" != reference ] && args+=(--reference)
  [ "$mode" != hard ] && args+=(--samples "$demo_samples")
  limit=$(step_limit "$budget" "$demo_timeout")
  if { [ "$gl_ok" = 0 ] && [ "$mode" != reference ]; } || [ "$limit" -le 0 ]; then
    record skipped 0 "demo/$mode" "$([ "$limit" -le 0 ] && echo "time budget spent" || echo "no GL context")"
    continue
  fi
  t0=$(now_us)
  timeout -k 5 "$limit" "$here/bin/soft_shadows" "${args[@]}" > "$out/demo/$mode.json" 2> "$out/demo/$mode.log"
  rc=$?
  # The oracle's verdict (the first "mismatched" key: reference.mismatched / mismatched_bits) and
  # the run's total milliseconds.
  detail=$(grep -oE '"(mismatched[a-z_]*|total)":[0-9.]+' "$out/demo/$mode.json" | grep -m1 mismatched)
  detail+=" $(grep -oE '"total":[0-9.]+' "$out/demo/$mode.json" | tail -1)"
  [ "$rc" = 124 ] || [ "$rc" = 137 ] && detail="killed after ${limit}s"
  record "$(status_of $rc)" "$(elapsed "$t0")" "demo/$mode" "$detail"
done

# ---- summary ---------------------------------------------------------------------------------------
json_string() {  # a JSON string literal of $1 (backslash, quote, control characters escaped)
  local s=$1
  s=${s//\\/\\\\}
  s=${s//\"/\\\"}
  s=$(printf '%s' "$s" | tr -d '\000-\037')
  printf '"%s"' "$s"
}
failed=0
{
  printf '%-8s %7s  %s  %s\n' status seconds step detail
  for f in "$out"/.steps/*; do
    IFS=$'\t' read -r status seconds step detail < "$f"
    printf '%-8s %7s  %s  %s\n' "$status" "$seconds" "$step" "$detail"
  done
  echo "total: $((SECONDS - start_all)) s (budget $budget s), smoke=$smoke"
} > "$out/summary.txt"
{
  printf '{"smoke":%s,"budget_s":%s,"total_s":%s,"gl":%s,"tier":%s,"gl_info":' \
    "$([ "$smoke" = 1 ] && echo true || echo false)" "$budget" "$((SECONDS - start_all))" \
    "$(json_string "$PENUMBRA_GL")" "$(json_string "$PENUMBRA_TIER")"
  if [ "$gl_ok" = 1 ] && [ -s "$out/gl_info.json" ]; then tr -d '\n' < "$out/gl_info.json"; else printf 'null'; fi
  printf ',"steps":['
  sep=""
  for f in "$out"/.steps/*; do
    IFS=$'\t' read -r status seconds step detail < "$f"
    printf '%s{"step":%s,"status":%s,"seconds":%s,"detail":%s}' "$sep" "$(json_string "$step")" \
      "$(json_string "$status")" "$seconds" "$(json_string "$detail")"
    sep=","
  done
  printf ']}\n'
} > "$out/summary.json"
for f in "$out"/.steps/*; do
  IFS=$'\t' read -r status _ < "$f"
  [ "$status" = pass ] || failed=$((failed + 1))
done
rm -rf "$out/.steps"
echo
cat "$out/summary.txt"

if [ "$make_tar" = 1 ]; then
  tar czf "$out.tar.gz" -C "$(dirname "$out")" "$(basename "$out")" && echo "results: $out.tar.gz"
fi
if [ "$gl_ok" = 0 ]; then exit 2; fi
[ "$failed" -eq 0 ] || { echo "run.sh: $failed step(s) did not pass" >&2; exit 1; }
exit 0
