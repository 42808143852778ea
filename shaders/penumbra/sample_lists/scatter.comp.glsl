// penumbra — sample lists pass 3, "scatter" (sintorn2008 §3.1, Construction and Storage): after
// the exclusive scan of the list lengths (pass 2, penumbra::Scanner) gave every list its offset,
// an accepted sample's global slot is offset + local index. "Instead of having one array IA with
// heterogenous data ... we store them in separate arrays using the same offsets": positions and
// sample ids are written structure-of-arrays, and the per-sample slot replaces the local index so
// later passes find the sample's shadow bits ("this final offset ... we store it in the view
// texture").
//
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_INPUT=0
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_INPUT=1
//
// Bindings: uniform block 0 = params; buffer input: SSBO 0 positions (1 normals: declared, never
// read); depth input: texture unit 0 depth (1 normals: never read); SSBO 3 offsets uint[W*H],
// 4 list positions vec4[], 5 list ids uint[], 6 sample slots uint[n] (local index in, slot out),
// 7 sample texels uint[n] (read).
#include "penumbra/common/dispatch.glsl"
#include "penumbra/sample_lists/sample_lists_shared.h"

#ifndef PENUMBRA_SAMPLE_LISTS_INPUT
#error "penumbra/sample_lists/scatter.comp.glsl: define PENUMBRA_SAMPLE_LISTS_INPUT (0 = buffer, 1 = depth)"
#endif

layout(local_size_x = PENUMBRA_SAMPLE_LISTS_GROUP_SIZE) in;

layout(std140, binding = PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS) uniform PenumbraSampleListsParamsBlock {
    PenumbraSampleListsParams penumbraSampleListsParams;
};
#if PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS) readonly buffer PenumbraSampleListsInputPositionsBlock {
    vec4 penumbraSampleListsInputPositions[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS) readonly buffer PenumbraSampleListsInputNormalsBlock {
    vec4 penumbraSampleListsInputNormals[];
};
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION(id) penumbraSampleListsInputPositions[id]
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(id) penumbraSampleListsInputNormals[id].xyz
#else
layout(binding = PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH) uniform sampler2D penumbraSampleListsInputDepth;
layout(binding = PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS) uniform sampler2D penumbraSampleListsInputNormals;
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH(pixel) texelFetch(penumbraSampleListsInputDepth, ivec2(pixel), 0).r
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(pixel) texelFetch(penumbraSampleListsInputNormals, ivec2(pixel), 0).xyz
#endif
#include "penumbra/sample_lists/input.glsl"

layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS) readonly buffer PenumbraSampleListsOffsetsBlock {
    uint penumbraSampleListsOffsets[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS) writeonly buffer PenumbraSampleListsListPositionsBlock {
    vec4 penumbraSampleListsListPositions[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS) writeonly buffer PenumbraSampleListsListIdsBlock {
    uint penumbraSampleListsListIds[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS) buffer PenumbraSampleListsSampleSlotsBlock {
    uint penumbraSampleListsSampleSlots[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS) readonly buffer PenumbraSampleListsSampleTexelsBlock {
    uint penumbraSampleListsSampleTexels[];
};

void main() {
    const uint id = penumbraLinearGroup() * uint(PENUMBRA_SAMPLE_LISTS_GROUP_SIZE) + gl_LocalInvocationID.x;
    if (id >= penumbraSampleListsParams.grid.z) return;
    const uint texel = penumbraSampleListsSampleTexels[id];
    if (texel >= PENUMBRA_SAMPLE_LISTS_REJECTED) return;  // its slot is already NO_SLOT
    const uint slot = penumbraSampleListsOffsets[texel] + penumbraSampleListsSampleSlots[id];
    // The same precise arithmetic as pass 1, so the position is bit-identical to the classified one.
    const vec4 position = penumbraSampleListsLoadPosition(penumbraSampleListsParams, id);
    penumbraSampleListsListPositions[slot] = vec4(position.xyz, 1.0);
    penumbraSampleListsListIds[slot] = id;
    penumbraSampleListsSampleSlots[id] = slot;
}
