#!/usr/bin/env bash
# tools/gpu_bundle.sh DIR — the real-GPU tier: a self-contained folder another machine (a GPU with
# only its driver and GL loader installed, no network, no package manager) runs with DIR/run.sh.
#
# From the build in PENUMBRA_BUILD_DIR (default build/; configured Release and built when it has
# no CMakeCache.txt) it copies into DIR:
#   bin/    every GL test, penumbra_bench, soft_shadows, gl_info (stripped, rpath $ORIGIN/../lib)
#   lib/    every shared library they load (ldd) except glibc and the GL/EGL vendor stack, which
#           must come from the target's driver (rpath $ORIGIN: their own dependencies too)
#   share/  tests/shaders (test-only GLSL, PENUMBRA_TEST_SHADER_DIR), the library's shaders/ and
#           the embedded shader table, ../shared/scenes when present, bench_blocks.txt, the test list
#   run.sh  from tools/gpu_bundle/run.sh; manifest.txt (files, sizes, version, build type)
# and fails when DIR would exceed PENUMBRA_BUNDLE_MAX_MIB (default 64) MiB.
#
# Environment: PENUMBRA_BUILD_DIR; PENUMBRA_BUNDLE_NO_BUILD=1 copies what is built and builds
# nothing (the ctest `gpu_bundle` runs after `all`); PENUMBRA_BUNDLE_MAX_MIB.
# Needs: cmake, ldd, patchelf (tools/setup.sh), strip, objdump.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=${PENUMBRA_BUILD_DIR:-$root/build}
max_mib=${PENUMBRA_BUNDLE_MAX_MIB:-64}
marker="penumbra gpu bundle"

die() { echo "gpu_bundle: $*" >&2; exit 1; }

if [ $# -ne 1 ] || [ "${1:0:1}" = "-" ]; then
  echo "usage: [PENUMBRA_BUILD_DIR=build] [PENUMBRA_BUNDLE_NO_BUILD=1] tools/gpu_bundle.sh DIR" >&2
  exit 2
fi
for tool in cmake ldd patchelf strip objdump; do
  command -v "$tool" >/dev/null || die "$tool is missing (tools/setup.sh installs it)"
done
build=$(mkdir -p "$build" && cd "$build" && pwd)
targets_file="$build/gpu_bundle_targets.txt"  # written by tests/CMakeLists.txt (file(GENERATE))

# ---- build ----------------------------------------------------------------------------------
if [ "${PENUMBRA_BUNDLE_NO_BUILD:-0}" != 1 ]; then
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release
  elif [ ! -f "$targets_file" ]; then
    cmake "$build"  # a build configured before the list existed: regenerate
  fi
  [ -f "$targets_file" ] || die "$targets_file was not generated (tests, benchmarks and examples must be ON)"
  mapfile -t names < <(cut -f2 "$targets_file")
  cmake --build "$build" -j"$(nproc 2>/dev/null || echo 2)" --target "${names[@]}"
fi
[ -f "$targets_file" ] || die "$targets_file is missing: configure $build with tests, benchmarks and examples ON"

# Every benchmarks/*_bench.cpp needs its line in bench_blocks.txt, or run.sh would time it as
# "unlisted" only: checked here, where the sources are, so the ctest fails on a new block.
blocks_file="$root/tools/gpu_bundle/bench_blocks.txt"
for source in "$root"/benchmarks/*_bench.cpp; do
  block=$(basename "$source" _bench.cpp)
  grep -q "^${block}	" "$blocks_file" || die "benchmarks/${block}_bench.cpp has no line in $blocks_file"
done

# ---- DIR: refuse to empty a folder that is not a bundle ---------------------------------------
dir=$1
if [ -e "$dir" ]; then
  if [ -n "$(ls -A "$dir")" ] && ! grep -qs "^$marker" "$dir/manifest.txt"; then
    die "$dir exists and is not a bundle (no $dir/manifest.txt): refusing to replace it"
  fi
  rm -rf "$dir"
fi
mkdir -p "$dir"/bin "$dir"/lib "$dir"/share
dir=$(cd "$dir" && pwd)

# ---- binaries ---------------------------------------------------------------------------------
test_names=()
binaries=()
while IFS=$'\t' read -r kind name file; do
  [ -x "$file" ] || die "$name is not built ($file); build it or drop PENUMBRA_BUNDLE_NO_BUILD"
  cp "$file" "$dir/bin/$name"
  binaries+=("$file")
  if [ "$kind" = test ]; then test_names+=("$name"); fi
done < "$targets_file"
printf '%s\n' "${test_names[@]}" > "$dir/share/gl_tests.txt"

# ---- shared libraries ---------------------------------------------------------------------------
# Left to the target machine: glibc (its loader must match it) and the GL/EGL vendor stack (the
# driver's libEGL/glvnd pick the hardware; a copied Mesa would hide the GPU). X11/xcb/wayland
# must not appear at all: penumbra is headless.
system_re='^(linux-vdso|ld-linux[^ ]*|libc|libm|libdl|libpthread|librt|libresolv|libutil|libmvec|libanl)\.so'
vendor_re='^lib(EGL|GL|GLX|GLdispatch|GLESv1_CM|GLESv2|OpenGL|OSMesa|gbm|drm[^.]*|glapi|nvidia[^.]*|cuda|vulkan|LLVM[^.]*)\.so'
windowing_re='^lib(X[^.]*|xcb[^.]*|wayland[^.]*)\.so'
declare -A lib_source=()
for file in "${binaries[@]}"; do
  # ldd lists direct and indirect dependencies: "soname => /path (0x...)" or "soname (0x...)".
  while read -r soname arrow path _; do
    [[ $soname =~ $system_re || $soname =~ $vendor_re ]] && continue
    [[ $soname =~ $windowing_re ]] && die "$(basename "$file") needs $soname: bundled binaries must be headless"
    [ "$arrow" = "=>" ] || continue
    [ "$path" = "not" ] && die "$(basename "$file"): $soname not found"
    lib_source[$soname]=$path
  done < <(ldd "$file")
done
for soname in "${!lib_source[@]}"; do
  cp -L "${lib_source[$soname]}" "$dir/lib/$soname"
  chmod u+w "$dir/lib/$soname"
  # shellcheck disable=SC2016  # a literal $ORIGIN: the loader expands it to the library's folder
  patchelf --set-rpath '$ORIGIN' "$dir/lib/$soname"
done
for file in "$dir"/bin/*; do
  # --strip-unneeded keeps what the dynamic loader needs; the size limit needs it (debug info
  # and symbol tables of the test binaries are most of their bytes).
  strip --strip-unneeded "$file"
  # shellcheck disable=SC2016  # a literal $ORIGIN
  patchelf --set-rpath '$ORIGIN/../lib' "$file"
done

# ---- data: shaders, the shader table, scenes, run.sh --------------------------------------------
mkdir -p "$dir/share/tests" "$dir/share/generated/penumbra/detail"
cp -r "$root/tests/shaders" "$dir/share/tests/shaders"
cp -r "$root/shaders" "$dir/share/shaders"
cp "$build/generated/include/penumbra/detail/embedded_shaders.inc" "$dir/share/generated/penumbra/detail/"
cp "$blocks_file" "$dir/share/bench_blocks.txt"
scenes="$root/../shared/scenes"  # PENUMBRA_SHARED_SCENES_DIR's default (CMakeLists.txt)
if [ -d "$scenes" ]; then
  mkdir -p "$dir/share/scenes"
  cp "$scenes"/*.obj "$dir/share/scenes/" 2>/dev/null || true
fi
cp "$root/tools/gpu_bundle/run.sh" "$dir/run.sh"
chmod +x "$dir/run.sh"

# ---- manifest + size limit --------------------------------------------------------------------
glibc_needed=$(objdump -T "$dir"/bin/* "$dir"/lib/* 2>/dev/null | grep -o 'GLIBC_[0-9.]*' | sort -uV | tail -1)
{
  echo "$marker"
  echo "created: $(date -u +%Y-%m-%dT%H:%M:%SZ) on $(uname -srm)"
  echo "version: $(git -C "$root" describe --always --dirty 2>/dev/null || echo unknown)"
  echo "build: $build"
  grep -E '^(CMAKE_BUILD_TYPE|CMAKE_CXX_COMPILER|PENUMBRA_SANITIZE):' "$build/CMakeCache.txt" | sed 's/^/  /'
  echo "needs: glibc >= ${glibc_needed#GLIBC_} (built against $(ldd --version | head -1)), libEGL.so.1 from the GL driver"
  echo "libraries:"
  for soname in $(printf '%s\n' "${!lib_source[@]}" | sort); do echo "  $soname <- ${lib_source[$soname]}"; done
  echo "files (bytes path):"
  (cd "$dir" && find . -type f ! -name manifest.txt -printf '%s %P\n' | sort -k2 | sed 's/^/  /')
} > "$dir/manifest.txt"

bytes=$(du -sb "$dir" | cut -f1)
mib=$(( (bytes + 1048575) / 1048576 ))
echo "total: $bytes bytes" >> "$dir/manifest.txt"
if [ "$bytes" -ge $(( max_mib * 1048576 )) ]; then
  die "$dir is $mib MiB, over the ${max_mib} MiB limit"
fi
echo "gpu_bundle: $dir ($mib MiB: ${#binaries[@]} binaries, ${#lib_source[@]} libraries); run $dir/run.sh [--smoke] [OUTDIR]"
