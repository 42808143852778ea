// penumbra — the buffer scan's kernels (reduce-then-scan over per-invocation tiles). sintorn2008
// §3.1 turns per-texel list counts into list offsets with a scan [Harris, Sengupta, Owens 2007];
// penumbra::Scanner (include/penumbra/scan.hpp) drives these kernels, engines normally never bind
// them themselves.
//
// Work split: every invocation owns a tile of PENUMBRA_SCAN_ITEMS_PER_THREAD consecutive elements
// (tile t = elements [t * items, (t + 1) * items)), loads it as uvec4s and reduces or scans it
// serially in registers. The two bulk passes need no barrier and no shared memory at all:
//   reduce pass: partials[partials_index + t] = sum of tile t.
//   scan pass:   tile t's outputs = partials[partials_index + t] (its scanned offset) + the serial
//                scan of the tile.
//   top pass:    one work group scans up to GROUP_SIZE tiles: serial scans, one workgroup scan
//                (workgroup.glsl), offset = partials[carry_in_index] when FLAG_READ_OFFSETS is set
//                (else 0), and with FLAG_WRITE_CARRY partials[carry_out_index] = offset + sum
//                afterwards — how the host carries the running total from one binding window to the
//                next. The two indices always differ (window w reads word w % 2 and writes word
//                (w + 1) % 2): barrier() orders shared memory only, so no invocation may read a
//                buffer word another invocation of the same dispatch writes. The last invocation's
//                inclusive sum is the carry, so no workgroup total is needed.
// FLAG_INCLUSIVE selects inclusive output in the scan and top passes.
//
// Defines (all required, plain integers): PENUMBRA_SCAN_PASS (PENUMBRA_SCAN_PASS_REDUCE, _SCAN or
// _TOP), PENUMBRA_SCAN_GROUP_SIZE, PENUMBRA_SCAN_ITEMS_PER_THREAD (a multiple of 4),
// PENUMBRA_SCAN_VEC4 (1: both shifts and penumbraScanCount are multiples of 4 and all data goes
// through the uvec4 views; 0: scalar addressing, any shift and count). Optional:
// PENUMBRA_SCAN_SUBGROUPS (see workgroup.glsl; scan_subgroups.comp.glsl and scan_ballot.comp.glsl
// set it; it only changes the top pass). Bindings: PENUMBRA_SCAN_BINDING_* in scan_shared.h (a
// host may re-point the blocks with glShaderStorageBlockBinding / glUniformBlockBinding, as
// penumbra::Scanner does for ScanBindings). Constants: the uniform block PenumbraScanConstantsBlock
// holding one PenumbraScanConstants (scan_shared.h), one per dispatch — penumbra::planScan lists
// them with the dispatches. Dispatch: reduce and scan a 2D-folded grid (penumbra::detail::foldDispatch)
// of ceil(tiles / GROUP_SIZE) groups, tiles = ceil(count / ITEMS_PER_THREAD); top 1 group.
//
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_REDUCE PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=1
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_SCAN PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=1
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=1
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_REDUCE PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=0
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_SCAN PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=0
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=0
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=32 PENUMBRA_SCAN_ITEMS_PER_THREAD=4 PENUMBRA_SCAN_VEC4=1
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=1024 PENUMBRA_SCAN_ITEMS_PER_THREAD=64 PENUMBRA_SCAN_VEC4=0
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_SCAN PENUMBRA_SCAN_GROUP_SIZE=128 PENUMBRA_SCAN_ITEMS_PER_THREAD=32 PENUMBRA_SCAN_VEC4=1
#include "penumbra/scan/scan_shared.h"
#include "penumbra/common/dispatch.glsl"

#ifndef PENUMBRA_SCAN_PASS
#error penumbra/scan/scan.comp.glsl needs PENUMBRA_SCAN_PASS (PENUMBRA_SCAN_PASS_REDUCE, _SCAN or _TOP)
#endif
#ifndef PENUMBRA_SCAN_ITEMS_PER_THREAD
#error penumbra/scan/scan.comp.glsl needs PENUMBRA_SCAN_ITEMS_PER_THREAD (a multiple of 4)
#endif
#ifndef PENUMBRA_SCAN_VEC4
#error penumbra/scan/scan.comp.glsl needs PENUMBRA_SCAN_VEC4 (0 or 1)
#endif
#if (PENUMBRA_SCAN_ITEMS_PER_THREAD) % 4 != 0
#error PENUMBRA_SCAN_ITEMS_PER_THREAD must be a multiple of 4
#endif

#ifndef PENUMBRA_SCAN_GROUP_SIZE
#error penumbra/scan/scan.comp.glsl needs PENUMBRA_SCAN_GROUP_SIZE (invocations per work group)
#endif

layout(local_size_x = PENUMBRA_SCAN_GROUP_SIZE) in;

// After the layout line: the snippet checks its hook against gl_WorkGroupSize.
#include "penumbra/scan/workgroup.glsl"

layout(std430, binding = PENUMBRA_SCAN_BINDING_INPUT) readonly buffer PenumbraScanInput {
    uint penumbraScanInput[];
};
layout(std430, binding = PENUMBRA_SCAN_BINDING_OUTPUT) writeonly buffer PenumbraScanOutput {
    uint penumbraScanOutput[];
};
layout(std430, binding = PENUMBRA_SCAN_BINDING_PARTIALS) buffer PenumbraScanPartials {
    uint penumbraScanPartials[];
};
#if PENUMBRA_SCAN_VEC4
layout(std430, binding = PENUMBRA_SCAN_BINDING_INPUT_VEC4) readonly buffer PenumbraScanInputQuads {
    uvec4 penumbraScanInputQuads[];
};
layout(std430, binding = PENUMBRA_SCAN_BINDING_OUTPUT_VEC4) writeonly buffer PenumbraScanOutputQuads {
    uvec4 penumbraScanOutputQuads[];
};
#endif

layout(std140, binding = PENUMBRA_SCAN_BINDING_CONSTANTS) uniform PenumbraScanConstantsBlock {
    PenumbraScanConstants penumbraScanConstants;
};
#define penumbraScanCount (penumbraScanConstants.count)
#define penumbraScanInputShift (penumbraScanConstants.input_shift)
#define penumbraScanOutputShift (penumbraScanConstants.output_shift)
#define penumbraScanPartialsIndex (penumbraScanConstants.partials_index)
#define penumbraScanFlags (penumbraScanConstants.flags)

const uint penumbraScanItems = uint(PENUMBRA_SCAN_ITEMS_PER_THREAD);
const uint penumbraScanQuadsPerThread = penumbraScanItems / 4u;

// Elements 4q .. 4q+3 of the dispatch; elements at or past penumbraScanCount read as 0. One code
// path per permutation on purpose: llvmpipe runs both sides of a branch under an execution mask,
// so a scalar fallback beside the uvec4 load would cost as much as the load itself.
uvec4 penumbraScanLoadQuad(uint quad) {
    uvec4 value = uvec4(0u);
#if PENUMBRA_SCAN_VEC4
    // penumbraScanCount is a multiple of 4 here (the host scans a ragged tail separately).
    if (quad < (penumbraScanCount >> 2u)) value = penumbraScanInputQuads[(penumbraScanInputShift >> 2u) + quad];
#else
    uint first = quad * 4u;
    uint at = penumbraScanInputShift + first;
    if (first < penumbraScanCount) value.x = penumbraScanInput[at];
    if (first + 1u < penumbraScanCount) value.y = penumbraScanInput[at + 1u];
    if (first + 2u < penumbraScanCount) value.z = penumbraScanInput[at + 2u];
    if (first + 3u < penumbraScanCount) value.w = penumbraScanInput[at + 3u];
#endif
    return value;
}

// Stores the in-range elements of quad q (never writes past the caller's range).
void penumbraScanStoreQuad(uint quad, uvec4 value) {
#if PENUMBRA_SCAN_VEC4
    if (quad < (penumbraScanCount >> 2u)) penumbraScanOutputQuads[(penumbraScanOutputShift >> 2u) + quad] = value;
#else
    uint first = quad * 4u;
    uint at = penumbraScanOutputShift + first;
    if (first < penumbraScanCount) penumbraScanOutput[at] = value.x;
    if (first + 1u < penumbraScanCount) penumbraScanOutput[at + 1u] = value.y;
    if (first + 2u < penumbraScanCount) penumbraScanOutput[at + 2u] = value.z;
    if (first + 3u < penumbraScanCount) penumbraScanOutput[at + 3u] = value.w;
#endif
}

// Serial inclusive scan of tile `tile` into registers; returns the tile's sum.
uint penumbraScanLoadTile(uint tile, out uvec4 items[penumbraScanQuadsPerThread]) {
    uint first_quad = tile * penumbraScanQuadsPerThread;
    uint run = 0u;
    for (uint j = 0u; j < penumbraScanQuadsPerThread; ++j) {
        uvec4 x = penumbraScanLoadQuad(first_quad + j);
        x.y += x.x;
        x.z += x.y;
        x.w += x.z;
        items[j] = x + run;
        run = items[j].w;
    }
    return run;
}

// Stores tile `tile` = prefix + its inclusive scan (exclusive unless FLAG_INCLUSIVE).
void penumbraScanStoreTile(uint tile, uvec4 items[penumbraScanQuadsPerThread], uint prefix) {
    uint first_quad = tile * penumbraScanQuadsPerThread;
    bool inclusive = (penumbraScanFlags & uint(PENUMBRA_SCAN_FLAG_INCLUSIVE)) != 0u;
    uint previous = prefix;  // exclusive value of the next element
    for (uint j = 0u; j < penumbraScanQuadsPerThread; ++j) {
        uvec4 sums = items[j] + prefix;
        penumbraScanStoreQuad(first_quad + j, inclusive ? sums : uvec4(previous, sums.xyz));
        previous = sums.w;
    }
}

void main() {
    uint tiles = (penumbraScanCount + penumbraScanItems - 1u) / penumbraScanItems;
#if PENUMBRA_SCAN_PASS == PENUMBRA_SCAN_PASS_REDUCE
    uint tile = penumbraLinearGroup() * penumbraScanGroupSize + gl_LocalInvocationIndex;
    if (tile >= tiles) return;  // the folded grid's padding (no barriers in this pass)
    uint first_quad = tile * penumbraScanQuadsPerThread;
    uint sum = 0u;
    for (uint j = 0u; j < penumbraScanQuadsPerThread; ++j) {
        uvec4 x = penumbraScanLoadQuad(first_quad + j);
        sum += (x.x + x.y) + (x.z + x.w);
    }
    penumbraScanPartials[penumbraScanPartialsIndex + tile] = sum;
#elif PENUMBRA_SCAN_PASS == PENUMBRA_SCAN_PASS_SCAN
    uint tile = penumbraLinearGroup() * penumbraScanGroupSize + gl_LocalInvocationIndex;
    if (tile >= tiles) return;
    uvec4 items[penumbraScanQuadsPerThread];
    penumbraScanLoadTile(tile, items);
    penumbraScanStoreTile(tile, items, penumbraScanPartials[penumbraScanPartialsIndex + tile]);
#elif PENUMBRA_SCAN_PASS == PENUMBRA_SCAN_PASS_TOP
    // One group; every invocation takes part in the workgroup scan (tiles past the data are 0).
    uint tile = gl_LocalInvocationIndex;
    uvec4 items[penumbraScanQuadsPerThread];
    uint run = penumbraScanLoadTile(tile, items);
    // carry_in_index != carry_out_index (the host alternates two words): no invocation reads the
    // word the last invocation writes, whatever the order of buffer accesses across invocations.
    uint offset = (penumbraScanFlags & uint(PENUMBRA_SCAN_FLAG_READ_OFFSETS)) != 0u
                      ? penumbraScanPartials[penumbraScanConstants.carry_in_index]
                      : 0u;
    uint prefix = offset + penumbraScanWorkgroupExclusive(run);
    if ((penumbraScanFlags & uint(PENUMBRA_SCAN_FLAG_WRITE_CARRY)) != 0u &&
        gl_LocalInvocationIndex == penumbraScanGroupSize - 1u) {
        penumbraScanPartials[penumbraScanConstants.carry_out_index] = prefix + run;
    }
    penumbraScanStoreTile(tile, items, prefix);
#else
#error PENUMBRA_SCAN_PASS must be PENUMBRA_SCAN_PASS_REDUCE, PENUMBRA_SCAN_PASS_SCAN or PENUMBRA_SCAN_PASS_TOP
#endif
}
