#!/usr/bin/env bash
# The test command: installs what it needs, configures, builds and runs ctest.
#   1. a Release build of everything and its ctest run (every GL test on EGL; on OSMesa the quick
#      ones, see tests/CMakeLists.txt; the `stress` label is excluded: run `ctest -L stress` in
#      build/ for the long sweeps and the slow OSMesa duplicates, `ctest -L osmesa` for every
#      OSMesa entry);
#   2. an ASan+UBSan build (-DPENUMBRA_SANITIZE=ON) running the CPU tests (label `cpu`, leak
#      checking on) and the GL tests on EGL (their CPU twins and host code; leak checking and the
#      new/free mismatch check off there: Mesa's drivers keep allocations until exit, and its LLVM
#      JIT frees with free() what it allocated with a nothrow new), then the demo on the hostile
#      inputs (label `hostile`: every mode at small sizes, bad flags and OBJ files). That tree
#      builds only what these runs execute (PENUMBRA_BUILD_EXTRAS=OFF: no readme_examples, gl_info,
#      light_lut_error, obj_fuzz, nor the checks of compilers and flags: no_gl_headers_test,
#      shader_glslang_test -- its harness is shader_gl_test's, which runs; the rest is the external
#      glslangValidator --, twin_digest_fp_contract, conservative_raster_twin_bits), and skips
#      consumer_epoxy (its own unsanitized project, built and run the same in the main run).
# Environment: PENUMBRA_BUILD_DIR (default build), PENUMBRA_SANITIZE_BUILD_DIR (default
# <build dir>-sanitize), PENUMBRA_SKIP_SANITIZE=1 to skip step 2.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/tools/setup.sh"

jobs=$(nproc 2>/dev/null || echo 2)
build=${PENUMBRA_BUILD_DIR:-$root/build}
phase_start=$SECONDS
phase() {  # phase NAME: the seconds since the last call, for the CI log
  echo "== test.sh: $1 took $((SECONDS - phase_start)) s =="
  phase_start=$SECONDS
}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release
cmake --build "$build" -j"$jobs"
phase "Release build"

if [ "${PENUMBRA_SKIP_SANITIZE:-0}" != 1 ]; then
  asan=${PENUMBRA_SANITIZE_BUILD_DIR:-${build}-sanitize}
  # -O1 (what the sanitizers' documentation advises; -O2 took 1.8x the compile time, e.g. 118 s
  # against 66 s for tests/sample_based_soft_gl_test.cpp) and -g1: line tables only (what the
  # sanitizers' stack traces print), much quicker to build than -g.
  cmake -S "$root" -B "$asan" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPENUMBRA_SANITIZE=ON \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
        -DPENUMBRA_BUILD_BENCHMARKS=OFF -DPENUMBRA_BUILD_EXAMPLES=ON -DPENUMBRA_BUILD_EXTRAS=OFF
  cmake --build "$asan" -j"$jobs"
  phase "sanitizer build"
  echo "== sanitizer run (ASan+UBSan, CPU tests) =="
  (cd "$asan" && ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
     ctest --output-on-failure -j"$jobs" -L cpu -LE "stress|example")
  phase "sanitizer CPU run"
  echo "== sanitizer run (ASan+UBSan, GL tests on EGL) =="
  # alloc_dealloc_mismatch=0: Mesa's LLVM (libLLVM-15) frees with free() what it allocated with a
  # nothrow operator new when llvmpipe destroys a program's JIT; that is inside the driver, not
  # penumbra (the CPU run above keeps the check on).
  (cd "$asan" && ASAN_OPTIONS=detect_leaks=0:alloc_dealloc_mismatch=0 UBSAN_OPTIONS=print_stacktrace=1 \
     ctest --output-on-failure -j"$jobs" -L egl -LE "stress|bench|example|consumer")
  phase "sanitizer EGL run"
  echo "== sanitizer run (ASan+UBSan, the demo on hostile inputs: every mode at small sizes, bad flags, bad OBJ files) =="
  (cd "$asan" && ASAN_OPTIONS=detect_leaks=1:exitcode=86 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     ctest --output-on-failure -j"$jobs" -L hostile -LE gl)
  (cd "$asan" && ASAN_OPTIONS=detect_leaks=0:alloc_dealloc_mismatch=0:exitcode=86 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
     ctest --output-on-failure -j"$jobs" -L hostile -LE cpu)
  phase "sanitizer hostile runs"
fi

echo "== main run =="
cd "$build"
ctest --output-on-failure -j"$jobs" -LE stress
phase "main run"
