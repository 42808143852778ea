// penumbra — scan constants shared by C++ (include/penumbra/scan.hpp, through
// include/penumbra/detail/shared.hpp) and GLSL (scan.comp.glsl, workgroup.glsl). Valid as both.
//
// Every value here is a plain decimal so it also works in GLSL layout qualifiers and #if lines;
// code that needs a uint writes uint(PENUMBRA_SCAN_...). PenumbraScanConstants (below) is the one
// constants block of the kernels: std140-safe (eight uints, 32 bytes, no padding rules involved),
// static_assert'ed by include/penumbra/scan.hpp, which includes penumbra/detail/shared.hpp first.
#ifndef PENUMBRA_SCAN_SHARED_H
#define PENUMBRA_SCAN_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

// ScanOptions{} defaults: 16 uints (four uvec4 loads) per invocation — each level of the scan
// shrinks the data 16-fold, so the levels above the first add ~7% of its traffic — and 256
// invocations per work group, so the single-group top pass covers 4096 elements. Measured on
// llvmpipe at 2^24 elements (CPU time of the whole scan on a shared 2-core machine, one noisy
// sweep): 8 items 75 ms, 12 90 ms, 16 63 ms, 24 78 ms, 32 71 ms; group size 64-1024 within noise.
#define PENUMBRA_SCAN_DEFAULT_GROUP_SIZE 256
#define PENUMBRA_SCAN_DEFAULT_ITEMS_PER_THREAD 16

// Accepted ranges (Scanner checks them; the kernels assume them).
#define PENUMBRA_SCAN_MIN_GROUP_SIZE 32
#define PENUMBRA_SCAN_MAX_GROUP_SIZE 1024
#define PENUMBRA_SCAN_MAX_ITEMS_PER_THREAD 64

// Portable workgroup scan: values per raking segment (workgroup.glsl). Group sizes up to 256 rake
// 16 values per segment, larger ones 32, so invocation 0 then scans at most 32 segment sums.
#define PENUMBRA_SCAN_RAKING_WIDTH_SMALL 16
#define PENUMBRA_SCAN_RAKING_WIDTH_LARGE 32

// Workgroup-scan modes (the PENUMBRA_SCAN_SUBGROUPS define of workgroup.glsl).
#define PENUMBRA_SCAN_SUBGROUPS_NONE 0
#define PENUMBRA_SCAN_SUBGROUPS_KHR 1
#define PENUMBRA_SCAN_SUBGROUPS_BALLOT 2

// Kernel passes (the PENUMBRA_SCAN_PASS define of scan.comp.glsl).
#define PENUMBRA_SCAN_PASS_REDUCE 0
#define PENUMBRA_SCAN_PASS_SCAN 1
#define PENUMBRA_SCAN_PASS_TOP 2

// Default bindings of scan.comp.glsl (penumbra::ScanBindings can move them: the Scanner re-points
// its programs' blocks at construction). Shader storage: bindings 3 and 4 view the same ranges as 0
// and 1 as uvec4 and exist only when PENUMBRA_SCAN_VEC4 is 1. Uniform buffer: the constants block
// (the uniform-buffer binding space is separate from the shader-storage one).
#define PENUMBRA_SCAN_BINDING_INPUT 0
#define PENUMBRA_SCAN_BINDING_OUTPUT 1
#define PENUMBRA_SCAN_BINDING_PARTIALS 2
#define PENUMBRA_SCAN_BINDING_INPUT_VEC4 3
#define PENUMBRA_SCAN_BINDING_OUTPUT_VEC4 4
#define PENUMBRA_SCAN_BINDING_COUNT 5  // shader-storage bindings
#define PENUMBRA_SCAN_BINDING_CONSTANTS 0  // uniform block PenumbraScanConstantsBlock

// Bits of PenumbraScanConstants::flags (scan and top passes).
#define PENUMBRA_SCAN_FLAG_INCLUSIVE 1
#define PENUMBRA_SCAN_FLAG_READ_OFFSETS 2
#define PENUMBRA_SCAN_FLAG_WRITE_CARRY 4

// Carry words at the start of the scratch buffer: window w of a windowed scan reads word w % 2 and
// writes word (w + 1) % 2, so the top pass never reads a word one of its own invocations writes
// (barrier() orders shared memory only, not buffer memory).
#define PENUMBRA_SCAN_CARRY_WORDS 2

// The constants of one dispatch: uniform block PenumbraScanConstantsBlock (std140) of
// scan.comp.glsl at PENUMBRA_SCAN_BINDING_CONSTANTS. penumbra::planScan computes one per dispatch;
// penumbra::Scanner stores them all in one uniform buffer, each at a multiple of
// GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT, and binds that range per dispatch.
struct PenumbraScanConstants {
    uint count;            // elements this dispatch covers
    uint input_shift;      // element i is input[input_shift + i] (the bound range starts aligned,
    uint output_shift;     //   up to alignment - 4 bytes before the data); likewise the output
    uint partials_index;   // reduce: first tile-sum word it writes; scan: first tile-offset word it reads
    uint carry_in_index;   // top with FLAG_READ_OFFSETS: the word holding the earlier windows' total
    uint carry_out_index;  // top with FLAG_WRITE_CARRY: the word that receives the running total
    uint flags;            // PENUMBRA_SCAN_FLAG_* bits
    uint reserved;         // 0 (pads the block to 32 bytes)
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
