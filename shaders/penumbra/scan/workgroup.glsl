// penumbra — a work-group-wide prefix sum of one uint per invocation, for integrators' own kernels.
//
// sintorn2008 §3.1 turns per-texel list counts into list offsets with a scan [Harris, Sengupta,
// Owens 2007, GPU Gems 3 ch. 39]; penumbra's buffer scan (scan.comp.glsl) builds on these
// functions, and a kernel that produces one count per invocation can call them directly.
//
// Integration
//   include it after the kernel's layout(local_size_x = ...) in; line: the snippet checks its hook
//   against gl_WorkGroupSize, which GLSL only knows from there on.
//   hooks (define before including):
//     PENUMBRA_SCAN_GROUP_SIZE  required: invocations per work group (the product of the
//                               local_size_x/y/z the kernel declares), a plain integer >= 1. A
//                               value that differs from that product (or an include before the
//                               layout line) fails to compile — the array
//                               penumbraScanGroupSizeMustEqualLocalSize gets size -1 — instead of
//                               returning wrong sums.
//     PENUMBRA_SCAN_SUBGROUPS   optional, default PENUMBRA_SCAN_SUBGROUPS_NONE (0, shared memory
//                               only). PENUMBRA_SCAN_SUBGROUPS_KHR (1): the entry shader enables
//                               GL_KHR_shader_subgroup_arithmetic, the driver runs compute subgroups
//                               with the basic and arithmetic features. PENUMBRA_SCAN_SUBGROUPS_BALLOT
//                               (2): the entry enables GL_ARB_shader_ballot. Both subgroup modes
//                               assume full subgroups (group size a multiple of the subgroup size)
//                               made of consecutive gl_LocalInvocationIndex values in lane order, as
//                               common drivers form them (penumbra::Scanner checks ballot by running).
//   declares: shared uint penumbraScanShared[PENUMBRA_SCAN_GROUP_SIZE + 1] and
//             shared uint penumbraScanSharedSegments[...]; nothing else may use them.
//   functions (call from uniform control flow, every invocation of the group; invocations are
//   ordered by gl_LocalInvocationIndex; sums wrap mod 2^32; any sequence of calls is race-free
//   without extra barriers):
//     uint penumbraScanWorkgroupExclusive(uint value)               sum of the values before this
//     uint penumbraScanWorkgroupExclusive(uint value, out uint total)   ... and the group's sum
//     uint penumbraScanWorkgroupInclusive(uint value[, out uint total]) the same plus value
//     uint penumbraScanWorkgroupReduce(uint value)                  the group's sum, everywhere
//   Cost: scans take 3 barriers on the shared-memory path, 2 with subgroups; Reduce 3 / 2. The
//   totals come from one more shared read; the last invocation can get the total for free as its
//   exclusive prefix plus its value (scan.comp.glsl does).
#ifndef PENUMBRA_SCAN_WORKGROUP_GLSL
#define PENUMBRA_SCAN_WORKGROUP_GLSL

#include "penumbra/scan/scan_shared.h"

#ifndef PENUMBRA_SCAN_GROUP_SIZE
#error penumbra/scan/workgroup.glsl needs the hook PENUMBRA_SCAN_GROUP_SIZE (invocations per work group)
#endif
#ifndef PENUMBRA_SCAN_SUBGROUPS
#define PENUMBRA_SCAN_SUBGROUPS PENUMBRA_SCAN_SUBGROUPS_NONE
#endif
#if PENUMBRA_SCAN_SUBGROUPS == PENUMBRA_SCAN_SUBGROUPS_KHR && !defined(GL_KHR_shader_subgroup_arithmetic)
#error PENUMBRA_SCAN_SUBGROUPS is PENUMBRA_SCAN_SUBGROUPS_KHR but GL_KHR_shader_subgroup_arithmetic is not enabled
#endif
#if PENUMBRA_SCAN_SUBGROUPS == PENUMBRA_SCAN_SUBGROUPS_BALLOT && !defined(GL_ARB_shader_ballot)
#error PENUMBRA_SCAN_SUBGROUPS is PENUMBRA_SCAN_SUBGROUPS_BALLOT but GL_ARB_shader_ballot is not enabled
#endif

const uint penumbraScanGroupSize = uint(PENUMBRA_SCAN_GROUP_SIZE);
// Compile-time check of the hook (GLSL has no static_assert: a negative array size is the error).
// If the compiler stops here, PENUMBRA_SCAN_GROUP_SIZE differs from local_size_x * local_size_y *
// local_size_z, or this file was included before the layout(local_size_...) in; line.
const uint penumbraScanGroupSizeMustEqualLocalSize[
    gl_WorkGroupSize.x * gl_WorkGroupSize.y * gl_WorkGroupSize.z == penumbraScanGroupSize ? 1 : -1] = uint[1](0u);
const uint penumbraScanRakingWidth = penumbraScanGroupSize > 256u ? uint(PENUMBRA_SCAN_RAKING_WIDTH_LARGE)
                                                                  : uint(PENUMBRA_SCAN_RAKING_WIDTH_SMALL);
const uint penumbraScanSegmentCount = (penumbraScanGroupSize + penumbraScanRakingWidth - 1u) / penumbraScanRakingWidth;

// Shared-memory path: one value per invocation, scanned in place by the raking invocations.
// Subgroup paths: the scanned subgroup sums. Both: the group total in the last slot.
shared uint penumbraScanShared[penumbraScanGroupSize + 1u];
// Shared-memory path: the raking segments' sums. Subgroup paths: the subgroups' sums (at most one
// per invocation).
shared uint penumbraScanSharedSegments[PENUMBRA_SCAN_SUBGROUPS != PENUMBRA_SCAN_SUBGROUPS_NONE
                                           ? penumbraScanGroupSize
                                           : penumbraScanSegmentCount];

#if PENUMBRA_SCAN_SUBGROUPS != PENUMBRA_SCAN_SUBGROUPS_NONE

#if PENUMBRA_SCAN_SUBGROUPS == PENUMBRA_SCAN_SUBGROUPS_KHR
uint penumbraScanLane() { return gl_SubgroupInvocationID; }
uint penumbraScanSubgroupSize() { return gl_SubgroupSize; }
uint penumbraScanSubgroup() { return gl_SubgroupID; }
uint penumbraScanSubgroupCount() { return gl_NumSubgroups; }
uint penumbraScanSubgroupExclusive(uint value, out uint sum) {
    sum = subgroupAdd(value);
    return subgroupExclusiveAdd(value);
}
#else
// GL_ARB_shader_ballot has no subgroup arithmetic: every lane reads every lane's value with
// readInvocationARB (a broadcast; the index is dynamically uniform) and keeps those before it.
// Cheap where subgroups are narrow — llvmpipe's are its 8-wide SIMD vectors — and still correct on
// 32/64-wide GPUs, which have the KHR path anyway.
uint penumbraScanLane() { return gl_SubGroupInvocationARB; }
uint penumbraScanSubgroupSize() { return gl_SubGroupSizeARB; }
uint penumbraScanSubgroup() { return gl_LocalInvocationIndex / gl_SubGroupSizeARB; }
uint penumbraScanSubgroupCount() { return (penumbraScanGroupSize + gl_SubGroupSizeARB - 1u) / gl_SubGroupSizeARB; }
uint penumbraScanSubgroupExclusive(uint value, out uint sum) {
    uint lane = gl_SubGroupInvocationARB;
    uint before = 0u;
    sum = 0u;
    for (uint j = 0u; j < gl_SubGroupSizeARB; ++j) {
        uint x = readInvocationARB(value, j);
        before += j < lane ? x : 0u;
        sum += x;
    }
    return before;
}
#endif

// Subgroup scans, then subgroup 0 scans the subgroup sums (in slices of the subgroup size) into
// penumbraScanShared, total in the last slot. Write-after-read safety between calls: the first
// phase writes penumbraScanSharedSegments, read only between this call's two barriers.
uint penumbraScanWorkgroupExclusive(uint value) {
    uint sum;
    uint before = penumbraScanSubgroupExclusive(value, sum);
    uint subgroup = penumbraScanSubgroup();
    if (penumbraScanLane() == 0u) penumbraScanSharedSegments[subgroup] = sum;
    barrier();
    if (subgroup == 0u) {
        uint count = penumbraScanSubgroupCount();
        uint run = 0u;
        for (uint base = 0u; base < count; base += penumbraScanSubgroupSize()) {
            uint i = base + penumbraScanLane();
            uint x = i < count ? penumbraScanSharedSegments[i] : 0u;
            uint slice_sum;
            uint prefix = penumbraScanSubgroupExclusive(x, slice_sum);
            if (i < count) penumbraScanShared[i] = run + prefix;
            run += slice_sum;
        }
        if (penumbraScanLane() == 0u) penumbraScanShared[penumbraScanGroupSize] = run;
    }
    barrier();
    return penumbraScanShared[subgroup] + before;
}

uint penumbraScanWorkgroupReduce(uint value) {
    uint sum;
    penumbraScanSubgroupExclusive(value, sum);
    uint subgroup = penumbraScanSubgroup();
    if (penumbraScanLane() == 0u) penumbraScanSharedSegments[subgroup] = sum;
    barrier();
    if (subgroup == 0u) {
        uint count = penumbraScanSubgroupCount();
        uint run = 0u;
        for (uint base = 0u; base < count; base += penumbraScanSubgroupSize()) {
            uint i = base + penumbraScanLane();
            uint slice_sum;
            penumbraScanSubgroupExclusive(i < count ? penumbraScanSharedSegments[i] : 0u, slice_sum);
            run += slice_sum;
        }
        if (penumbraScanLane() == 0u) penumbraScanShared[penumbraScanGroupSize] = run;
    }
    barrier();
    return penumbraScanShared[penumbraScanGroupSize];
}

#else

// Shared-memory path [Harris/Sengupta/Owens's raking variant]: (1) every invocation stores its
// value; (2) one invocation per segment of penumbraScanRakingWidth values scans it in place and
// stores the segment sum; (3) invocation 0 scans the segment sums and stores the total; then every
// invocation adds two words. Few shared accesses per invocation on purpose: llvmpipe (and other
// SIMD-over-invocations CPUs) pay a scalar loop per shared access. Write-after-read safety between
// calls: an invocation's first write is its own slot, which at the end only it reads; all other
// writes follow a barrier.
uint penumbraScanWorkgroupExclusive(uint value) {
    uint self = gl_LocalInvocationIndex;
    penumbraScanShared[self] = value;
    barrier();
    if (self < penumbraScanSegmentCount) {
        uint begin = self * penumbraScanRakingWidth;
        uint end = min(begin + penumbraScanRakingWidth, penumbraScanGroupSize);
        uint run = 0u;
        for (uint i = begin; i < end; ++i) {
            uint x = penumbraScanShared[i];
            penumbraScanShared[i] = run;
            run += x;
        }
        penumbraScanSharedSegments[self] = run;
    }
    barrier();
    if (self == 0u) {
        uint run = 0u;
        for (uint s = 0u; s < penumbraScanSegmentCount; ++s) {
            uint x = penumbraScanSharedSegments[s];
            penumbraScanSharedSegments[s] = run;
            run += x;
        }
        penumbraScanShared[penumbraScanGroupSize] = run;
    }
    barrier();
    return penumbraScanShared[self] + penumbraScanSharedSegments[self / penumbraScanRakingWidth];
}

uint penumbraScanWorkgroupReduce(uint value) {
    uint self = gl_LocalInvocationIndex;
    penumbraScanShared[self] = value;
    barrier();
    if (self < penumbraScanSegmentCount) {
        uint begin = self * penumbraScanRakingWidth;
        uint end = min(begin + penumbraScanRakingWidth, penumbraScanGroupSize);
        uint run = 0u;
        for (uint i = begin; i < end; ++i) run += penumbraScanShared[i];
        penumbraScanSharedSegments[self] = run;
    }
    barrier();
    if (self == 0u) {
        uint run = 0u;
        for (uint s = 0u; s < penumbraScanSegmentCount; ++s) run += penumbraScanSharedSegments[s];
        penumbraScanShared[penumbraScanGroupSize] = run;
    }
    barrier();
    return penumbraScanShared[penumbraScanGroupSize];
}

#endif

// Every path leaves the total in penumbraScanShared[group size] before its last barrier, and no
// path writes that slot before its first barrier.
uint penumbraScanWorkgroupExclusive(uint value, out uint total) {
    uint before = penumbraScanWorkgroupExclusive(value);
    total = penumbraScanShared[penumbraScanGroupSize];
    return before;
}

uint penumbraScanWorkgroupInclusive(uint value) { return penumbraScanWorkgroupExclusive(value) + value; }

uint penumbraScanWorkgroupInclusive(uint value, out uint total) {
    return penumbraScanWorkgroupExclusive(value, total) + value;
}

#endif
