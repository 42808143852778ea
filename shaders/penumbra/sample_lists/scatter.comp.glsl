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
#include "penumbra/sample_lists/kernel.glsl"

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
    uint id;
    if (!penumbraSampleListsSampleId(id)) return;
    const uint texel = penumbraSampleListsSampleTexels[id];
    if (texel >= PENUMBRA_SAMPLE_LISTS_REJECTED) return;  // its slot is already NO_SLOT
    const uint slot = penumbraSampleListsOffsets[texel] + penumbraSampleListsSampleSlots[id];
    // The same precise arithmetic as pass 1, so the position is bit-identical to the classified one.
    const vec4 position = penumbraSampleListsLoadPosition(penumbraSampleListsParams, id);
    penumbraSampleListsListPositions[slot] = vec4(position.xyz, 1.0);
    penumbraSampleListsListIds[slot] = id;
    penumbraSampleListsSampleSlots[id] = slot;
}
