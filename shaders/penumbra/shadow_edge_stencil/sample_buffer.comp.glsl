// penumbra — shadow-edge stencil: the hard pipeline's input (the twin: aaSampleBuffer). Positions
// and normals [P * (1 + N)]: the P centres, then pixel i's N sub-samples at P + i N + k where the
// mode asks for them (grid.w: PENUMBRA_AA_MODE_FULL every pixel, _EDGE flagged pixels), w == 0
// elsewhere (the sample lists skip those). One invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_CENTRES) readonly buffer PenumbraAaCentres { vec4 penumbraAaCentres[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_NORMALS) readonly buffer PenumbraAaNormals { vec4 penumbraAaNormals[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_SUB_SAMPLES) readonly buffer PenumbraAaSubSamples { vec4 penumbraAaSubSamples[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) readonly buffer PenumbraAaStencil { uint penumbraAaStencil[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_OUT_POSITIONS) writeonly buffer PenumbraAaOutPositions { vec4 penumbraAaOutPositions[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_OUT_NORMALS) writeonly buffer PenumbraAaOutNormals { vec4 penumbraAaOutNormals[]; };

void main() {
    uint p = penumbraAaParams.view.x * penumbraAaParams.view.y, n = penumbraAaParams.view.z;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= p) return;
    vec4 normal = penumbraAaNormals[i];
    penumbraAaOutPositions[i] = penumbraAaCentres[i];
    penumbraAaOutNormals[i] = normal;
    bool take = penumbraAaParams.grid.w == PENUMBRA_AA_MODE_FULL || (penumbraAaStencil[i] & PENUMBRA_AA_FLAG) != 0u;
    for (uint k = 0u; k < n; ++k) {
        penumbraAaOutPositions[p + i * n + k] = take ? penumbraAaSubSamples[i * n + k] : vec4(0.0);
        penumbraAaOutNormals[p + i * n + k] = take ? normal : vec4(0.0);
    }
}
