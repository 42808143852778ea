// penumbra — batch deep shadow map lookups: query i = (u, v, light depth, lod) -> V per channel
// (vec4: rgb, a = 1). For tests, tools and engines that shade on the CPU side of a compute pass.
// penumbra-permutation: PENUMBRA_DSM_CHANNELS=1
// penumbra-permutation: PENUMBRA_DSM_CHANNELS=3
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"

#ifndef PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_CHANNELS 1
#endif
#define PENUMBRA_DSM_BINDING_QUERIES 0
#define PENUMBRA_DSM_BINDING_RESULTS 2

layout(local_size_x = PENUMBRA_DSM_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_DSM_BINDING_PARAMS) uniform PenumbraDsmParamsBlock { PenumbraDsmParams penumbraDsmParams; };
layout(std430, binding = PENUMBRA_DSM_BINDING_QUERIES) readonly buffer PenumbraDsmQueries { vec4 penumbraDsmQueries[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_RESULTS) writeonly buffer PenumbraDsmResults { vec4 penumbraDsmResults[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_MAP_OFFSETS) readonly buffer PenumbraDsmMapOffsets { uint penumbraDsmMapOffsets[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_MAP_VERTICES) readonly buffer PenumbraDsmMapVertices { uint penumbraDsmMapWords[]; };

#define PENUMBRA_DSM_LOAD_OFFSET(word) penumbraDsmMapOffsets[word]
#define PENUMBRA_DSM_LOAD_WORD(index) penumbraDsmMapWords[index]
#define PENUMBRA_DSM_VERTEX_CAPACITY penumbraDsmParams.capacity.y
#define PENUMBRA_DSM_RESOLUTION penumbraDsmParams.size.x
#define PENUMBRA_DSM_LEVELS penumbraDsmParams.size.w
#include "penumbra/deep_shadow_map/lookup.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (i >= penumbraDsmParams.capacity.x) return;  // query count
    vec4 q = penumbraDsmQueries[i];
    vec4 r = vec4(1.0);
    for (uint c = 0u; c < uint(PENUMBRA_DSM_CHANNELS); ++c) r[c] = penumbraDsmLookup(q.x, q.y, q.z, q.w, c);
    penumbraDsmResults[i] = r;
}
