// penumbra — shadow-edge stencil: fractional visibility per pixel from the hard pipeline's states
// (the twin: aaResolve). grid.w: PENUMBRA_AA_MODE_OFF the centre's state; _FULL the mean of the N
// sub-samples at P + i N; _EDGE the mean of those at P + rank N where the stencil flags the pixel
// and its rank is within the budget (limits.z), else the centre's state; _EDGE_PROVEN the same
// for flagged pixels, and an unflagged pixel's verdict from the provable stencil's word (1 where
// PENUMBRA_AA_LIT, else 0). Invocation 0 of either edge mode writes the flagged pixels past the
// budget to the status. N a power of two keeps the means exact. One invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_STATUS) buffer PenumbraAaStatus { uint penumbraAaStatus[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) readonly buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STATES) readonly buffer PenumbraAaStates { uint penumbraAaStates[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_VISIBLE) writeonly buffer PenumbraAaVisible { float penumbraAaVisible[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_RANKS) readonly buffer PenumbraAaRanks { uint penumbraAaRanks[]; };

void main() {
    uint p = penumbraAaParams.view.x * penumbraAaParams.view.y, n = penumbraAaParams.view.z, mode = penumbraAaParams.grid.w;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= p) return;
    uint budget = min(penumbraAaParams.limits.z, p);
    bool edge = mode == PENUMBRA_AA_MODE_EDGE || mode == PENUMBRA_AA_MODE_EDGE_PROVEN;
    if (edge && i == 0u) {
        uint flagged = penumbraAaRanks[p];
        penumbraAaStatus[PENUMBRA_AA_STATUS_BUDGET_OVERFLOW] = flagged > budget ? flagged - budget : 0u;
    }
    uint word = edge ? penumbraAaStencil[i] : 0u;
    if (mode == PENUMBRA_AA_MODE_EDGE_PROVEN && (word & PENUMBRA_AA_FLAG) == 0u) {
        penumbraAaVisible[i] = (word & PENUMBRA_AA_LIT) != 0u ? 1.0 : 0.0;
        return;
    }
    uint slot = edge ? penumbraAaRanks[i] : i;
    bool multi = mode == PENUMBRA_AA_MODE_FULL || (edge && (word & PENUMBRA_AA_FLAG) != 0u && slot < budget);
    if (!multi) {
        penumbraAaVisible[i] = penumbraAaStates[i] == PENUMBRA_AFH_LIT ? 1.0 : 0.0;
        return;
    }
    uint lit = 0u;
    for (uint k = 0u; k < n; ++k) lit += penumbraAaStates[p + slot * n + k] == PENUMBRA_AFH_LIT ? 1u : 0u;
    penumbraAaVisible[i] = float(lit) / float(n);
}
