// penumbra — scan constants shared by C++ (include/penumbra/scan.hpp, through
// include/penumbra/detail/shared.hpp) and GLSL (scan.comp.glsl, workgroup.glsl). Valid as both.
//
// Every value here is a plain decimal so it also works in GLSL layout qualifiers and #if lines;
// code that needs a uint writes uint(PENUMBRA_SCAN_...).
#ifndef PENUMBRA_SCAN_SHARED_H
#define PENUMBRA_SCAN_SHARED_H

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

// Shader storage bindings of scan.comp.glsl. Bindings 3 and 4 view the same ranges as 0 and 1 as
// uvec4 and exist only when PENUMBRA_SCAN_VEC4 is 1.
#define PENUMBRA_SCAN_BINDING_INPUT 0
#define PENUMBRA_SCAN_BINDING_OUTPUT 1
#define PENUMBRA_SCAN_BINDING_PARTIALS 2
#define PENUMBRA_SCAN_BINDING_INPUT_VEC4 3
#define PENUMBRA_SCAN_BINDING_OUTPUT_VEC4 4
#define PENUMBRA_SCAN_BINDING_COUNT 5

// Bits of the penumbraScanFlags uniform (scan and top passes).
#define PENUMBRA_SCAN_FLAG_INCLUSIVE 1
#define PENUMBRA_SCAN_FLAG_READ_OFFSETS 2
#define PENUMBRA_SCAN_FLAG_WRITE_CARRY 4

#endif
