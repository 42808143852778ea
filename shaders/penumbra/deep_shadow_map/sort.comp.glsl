// penumbra — deep shadow map build: sorts every sub-sample list by (depth, triangle) in place (heap
// sort: O(n log n) per list, no recursion; the keys are unique, so the order, unlike the scatter's,
// is deterministic and equals the CPU twin's std::sort). One invocation per list.
// penumbra-permutation: PENUMBRA_DSM_CHANNELS=1
// penumbra-permutation: PENUMBRA_DSM_CHANNELS=3
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"

#ifndef PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_CHANNELS 1
#endif
#if PENUMBRA_DSM_CHANNELS == 3
#define PENUMBRA_DSM_STRIDE 2u
#else
#define PENUMBRA_DSM_STRIDE 1u
#endif

layout(local_size_x = PENUMBRA_DSM_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_DSM_BINDING_PARAMS) uniform PenumbraDsmParamsBlock { PenumbraDsmParams penumbraDsmParams; };
layout(std430, binding = PENUMBRA_DSM_BINDING_COUNTS) readonly buffer PenumbraDsmOffsets { uint penumbraDsmOffsets[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_RECORDS) buffer PenumbraDsmRecords { uvec4 penumbraDsmRecords[]; };

uint penumbraDsmBase;

bool penumbraDsmLess(uint a, uint b) {  // record a < record b by (z, triangle)
    uvec4 ra = penumbraDsmRecords[(penumbraDsmBase + a) * PENUMBRA_DSM_STRIDE];
    uvec4 rb = penumbraDsmRecords[(penumbraDsmBase + b) * PENUMBRA_DSM_STRIDE];
    float za = uintBitsToFloat(ra.x), zb = uintBitsToFloat(rb.x);
    return za < zb || (za == zb && ra.y < rb.y);
}

void penumbraDsmSwap(uint a, uint b) {
    for (uint k = 0u; k < PENUMBRA_DSM_STRIDE; ++k) {
        uvec4 t = penumbraDsmRecords[(penumbraDsmBase + a) * PENUMBRA_DSM_STRIDE + k];
        penumbraDsmRecords[(penumbraDsmBase + a) * PENUMBRA_DSM_STRIDE + k] = penumbraDsmRecords[(penumbraDsmBase + b) * PENUMBRA_DSM_STRIDE + k];
        penumbraDsmRecords[(penumbraDsmBase + b) * PENUMBRA_DSM_STRIDE + k] = t;
    }
}

void penumbraDsmSift(uint i, uint n) {  // max-heap
    for (;;) {
        uint m = i, l = 2u * i + 1u, r = l + 1u;
        if (l < n && penumbraDsmLess(m, l)) m = l;
        if (r < n && penumbraDsmLess(m, r)) m = r;
        if (m == i) return;
        penumbraDsmSwap(i, m);
        i = m;
    }
}

void main() {
    uint R = penumbraDsmParams.size.x, S = penumbraDsmParams.size.y;
    uint list = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (list >= R * R * S) return;
    uint cap = penumbraDsmParams.capacity.x;
    uint first = min(penumbraDsmOffsets[list], cap), last = min(penumbraDsmOffsets[list + 1u], cap);
    uint n = last - first;
    if (n < 2u) return;
    penumbraDsmBase = first;
    for (uint i = n / 2u; i-- > 0u;) penumbraDsmSift(i, n);
    for (uint end = n - 1u; end > 0u; --end) {
        penumbraDsmSwap(0u, end);
        penumbraDsmSift(0u, end);
    }
}
