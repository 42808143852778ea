// penumbra — shadow-edge stencil: fractional visibility per pixel from the hard pipeline's states
// (the twin: aaResolve). grid.w: PENUMBRA_AA_MODE_OFF the centre's state; _FULL the mean of the N
// sub-samples; _EDGE the mean where the stencil flags the pixel, else the centre's state. N a
// power of two keeps the means exact. One invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) readonly buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STATES) readonly buffer PenumbraAaStates { uint penumbraAaStates[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_VISIBLE) writeonly buffer PenumbraAaVisible { float penumbraAaVisible[]; };

void main() {
    uint p = penumbraAaParams.view.x * penumbraAaParams.view.y, n = penumbraAaParams.view.z, mode = penumbraAaParams.grid.w;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= p) return;
    if (mode == PENUMBRA_AA_MODE_OFF || (mode == PENUMBRA_AA_MODE_EDGE && (penumbraAaStencil[i] & PENUMBRA_AA_FLAG) == 0u)) {
        penumbraAaVisible[i] = penumbraAaStates[i] == PENUMBRA_AFH_LIT ? 1.0 : 0.0;
        return;
    }
    uint lit = 0u;
    for (uint k = 0u; k < n; ++k) lit += penumbraAaStates[p + i * n + k] == PENUMBRA_AFH_LIT ? 1u : 0u;
    penumbraAaVisible[i] = float(lit) / float(n);
}
