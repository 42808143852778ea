// penumbra — shadow-edge stencil, pass 1: each pixel's N sub-samples on its plane (the twin:
// aaFootprintsCpu) and its stencil word's first state from facing alone (the sample lists reject
// light-back-facing samples: all back-facing = SHADOWED, mixed = FLAG, none = ACTIVE). One
// invocation per pixel.
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_CENTRES) readonly buffer PenumbraAaCentres { vec4 penumbraAaCentres[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_NORMALS) readonly buffer PenumbraAaNormals { vec4 penumbraAaNormals[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_SUB_SAMPLES) writeonly buffer PenumbraAaSubSamples { vec4 penumbraAaSubSamples[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_STENCIL) writeonly buffer PenumbraAaStencil { uint penumbraAaStencil[]; };

void main() {
    uint width = penumbraAaParams.view.x, height = penumbraAaParams.view.y, n = penumbraAaParams.view.z;
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= width * height) return;
    vec4 c4 = penumbraAaCentres[i];
    if (c4.w == 0.0) {
        for (uint k = 0u; k < n; ++k) penumbraAaSubSamples[i * n + k] = vec4(0.0);
        penumbraAaStencil[i] = 0u;
        return;
    }
    dvec4 m0 = penumbraAaParams.inverse_view_projection[0], m1 = penumbraAaParams.inverse_view_projection[1];
    dvec4 m2 = penumbraAaParams.inverse_view_projection[2], m3 = penumbraAaParams.inverse_view_projection[3];
    double z_near = penumbraAaParams.numbers.z;
    uvec2 size = uvec2(width, height), pixel = uvec2(i % width, i / width);
    dvec3 c = dvec3(c4.xyz), nrm = dvec3(penumbraAaNormals[i].xyz);
    double s0 = penumbraAaCentreParameter(m0, m1, m2, m3, z_near, size, pixel, c);
    bool cull = penumbraAaParams.view.w != 0u;
    vec4 light = penumbraAaParams.light;
    vec3 facing_normal = penumbraAaNormals[i].xyz;
    uint back = (cull && penumbraAaBackFacing(light, c4, facing_normal)) ? 1u : 0u;
    for (uint k = 0u; k < n; ++k) {
        uint flags;
        vec4 q = penumbraAaSubSample(m0, m1, m2, m3, z_near, size, pixel, c, nrm, penumbraAaOffset(penumbraAaParams.offsets, k),
                                     s0, flags);
        penumbraAaSubSamples[i * n + k] = q;
        if (cull && penumbraAaBackFacing(light, q, facing_normal)) ++back;
    }
    penumbraAaStencil[i] = back == n + 1u ? PENUMBRA_AA_SHADOWED : back != 0u ? PENUMBRA_AA_FLAG : PENUMBRA_AA_ACTIVE;
}
