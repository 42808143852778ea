// penumbra — shadow-edge stencil: the edge layout's ranks, step 1 of 2: 1 per flagged pixel, 0 for
// the others and for entry P (the scanner's exclusive scan then gives each flagged pixel its rank
// and entry P the flagged count). One invocation per entry, P + 1.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) readonly buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_RANKS) writeonly buffer PenumbraAaRanks { uint penumbraAaRanks[]; };

void main() {
    uint p = penumbraAaParams.view.x * penumbraAaParams.view.y;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i > p) return;
    penumbraAaRanks[i] = i < p && (penumbraAaStencil[i] & PENUMBRA_AA_FLAG) != 0u ? 1u : 0u;
}
