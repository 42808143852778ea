// penumbra — shadow-edge stencil: the hard pipeline's input (the twin: aaSampleBuffer). Positions
// and normals: the P centres, then N sub-samples per multi-sampled pixel. grid.w
// PENUMBRA_AA_MODE_FULL: pixel i's at P + i N + k. _EDGE: packed, the flagged pixel of rank r
// (ranks, the scanned flags) at P + r N + k while r < limits.z (the budget), and its centre slot
// gets w == 0 (the resolve reads its sub-samples only: the lists skip the centre); invocation
// j < budget also writes w == 0 into block j when j >= the flagged count. _EDGE_PROVEN: the same,
// and the unflagged pixels' centre slots get w == 0 too (the resolve takes their states from the
// provable stencil's word). One invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_CENTRES) readonly buffer PenumbraAaCentres { vec4 penumbraAaCentres[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_NORMALS) readonly buffer PenumbraAaNormals { vec4 penumbraAaNormals[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_SUB_SAMPLES) readonly buffer PenumbraAaSubSamples { vec4 penumbraAaSubSamples[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) readonly buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_OUT_POSITIONS) writeonly buffer PenumbraAaOutPositions { vec4 penumbraAaOutPositions[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_OUT_NORMALS) writeonly buffer PenumbraAaOutNormals { vec4 penumbraAaOutNormals[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_RANKS) readonly buffer PenumbraAaRanks { uint penumbraAaRanks[]; };

void main() {
    uint p = penumbraAaParams.view.x * penumbraAaParams.view.y, n = penumbraAaParams.view.z;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= p) return;
    vec4 normal = penumbraAaNormals[i];
    if (penumbraAaParams.grid.w == PENUMBRA_AA_MODE_FULL) {
        penumbraAaOutPositions[i] = penumbraAaCentres[i];
        penumbraAaOutNormals[i] = normal;
        for (uint k = 0u; k < n; ++k) {
            penumbraAaOutPositions[p + i * n + k] = penumbraAaSubSamples[i * n + k];
            penumbraAaOutNormals[p + i * n + k] = normal;
        }
        return;
    }
    uint budget = min(penumbraAaParams.limits.z, p), flagged = penumbraAaRanks[p];
    if (i < budget && i >= flagged) {  // an unused block of the budget
        for (uint k = 0u; k < n; ++k) {
            penumbraAaOutPositions[p + i * n + k] = vec4(0.0);
            penumbraAaOutNormals[p + i * n + k] = vec4(0.0);
        }
    }
    uint rank = penumbraAaRanks[i];
    bool flag = (penumbraAaStencil[i] & PENUMBRA_AA_FLAG) != 0u, held = flag && rank < budget;
    bool sampled = !held && (flag || penumbraAaParams.grid.w != PENUMBRA_AA_MODE_EDGE_PROVEN);
    penumbraAaOutPositions[i] = sampled ? penumbraAaCentres[i] : vec4(0.0);
    penumbraAaOutNormals[i] = sampled ? normal : vec4(0.0);
    if (!held) return;
    for (uint k = 0u; k < n; ++k) {
        penumbraAaOutPositions[p + rank * n + k] = penumbraAaSubSamples[i * n + k];
        penumbraAaOutNormals[p + rank * n + k] = normal;
    }
}
