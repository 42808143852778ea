// penumbra — shadow-edge stencil, pass 6: the stencil word's final bits (the twin:
// provableEdgeStencilCpu). FLAG = flagged before the light pass (mixed facing, outside the light,
// over the limits) or SPLIT by some triangle and COVERED by none; SHADOWED = not flagged and all
// points shadowed (COVERED, or all light-back-facing); LIT = classified (ACTIVE), neither SPLIT nor
// COVERED: no triangle blocks any point. One invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) buffer PenumbraAaStencil { uint penumbraAaStencil[]; };

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= penumbraAaParams.view.x * penumbraAaParams.view.y) return;
    uint s = penumbraAaStencil[i];
    bool flag = (s & PENUMBRA_AA_FLAG) != 0u || ((s & PENUMBRA_AA_SPLIT) != 0u && (s & PENUMBRA_AA_COVERED) == 0u);
    bool shadowed = !flag && (s & (PENUMBRA_AA_SHADOWED | PENUMBRA_AA_COVERED)) != 0u;
    bool lit = (s & (PENUMBRA_AA_ACTIVE | PENUMBRA_AA_FLAG | PENUMBRA_AA_SPLIT | PENUMBRA_AA_COVERED)) == PENUMBRA_AA_ACTIVE;
    penumbraAaStencil[i] = (flag ? PENUMBRA_AA_FLAG : 0u) | (shadowed ? PENUMBRA_AA_SHADOWED : 0u) | (lit ? PENUMBRA_AA_LIT : 0u);
}
