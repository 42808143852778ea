// penumbra — sample lists pass 1, "count" (sintorn2008 §3.1, Construction): every view sample is
// projected into the light grid (project.glsl); an accepted sample atomically increments its
// texel's counter, and the value read is its index inside that texel's list ("atomicInc() ...
// The read value is stored at pcam's position in the view texture"). The counters end up holding
// the list lengths. Rejections are counted by reason, per work group first, then once per group
// in the header.
//
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_INPUT=0
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_INPUT=1
//
// Bindings (defaults; host: penumbra::SampleListBuilder): uniform blocks 0 params, 1 frustum
// (projects with its light_texture); the inputs of kernel.glsl; SSBO 2 counts uint[W*H] (zeroed
// by the host), 3 header, 6 sample slots uint[n] (receives the local index, or
// PENUMBRA_SAMPLE_LISTS_NO_SLOT), 7 sample texels uint[n].
#include "penumbra/sample_lists/kernel.glsl"

layout(std140, binding = PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM) uniform PenumbraSampleListsFrustumBlock {
    PenumbraSampleListsFrustum penumbraSampleListsFrustum;
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS) buffer PenumbraSampleListsCountsBlock {
    uint penumbraSampleListsCounts[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_HEADER) buffer PenumbraSampleListsHeaderBlock {
    PenumbraSampleListsHeader penumbraSampleListsHeader;
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS) writeonly buffer PenumbraSampleListsSampleSlotsBlock {
    uint penumbraSampleListsSampleSlots[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS) writeonly buffer PenumbraSampleListsSampleTexelsBlock {
    uint penumbraSampleListsSampleTexels[];
};

// [0] accepted, [1 + reason] rejected: summed per group, added to the header once per group.
shared uint penumbraSampleListsGroupCounters[1u + PENUMBRA_SAMPLE_LISTS_REASON_COUNT];

void main() {
    const uint local = gl_LocalInvocationID.x;
    if (local < 1u + PENUMBRA_SAMPLE_LISTS_REASON_COUNT) penumbraSampleListsGroupCounters[local] = 0u;
    barrier();

    uint id;
    if (penumbraSampleListsSampleId(id)) {
        vec4 position = penumbraSampleListsLoadPosition(penumbraSampleListsParams, id);
        vec3 normal = penumbraSampleListsLoadNormal(penumbraSampleListsParams, id);
        vec4 t;
        uint code = penumbraSampleListsClassify(penumbraSampleListsFrustum.light_texture, penumbraSampleListsParams.light,
                                                penumbraSampleListsParams.grid, position, normal, t);
        if (code < PENUMBRA_SAMPLE_LISTS_REJECTED) {
            // §3.1: the counter's old value is the sample's index inside its list.
            penumbraSampleListsSampleSlots[id] = atomicAdd(penumbraSampleListsCounts[code], 1u);
            atomicAdd(penumbraSampleListsGroupCounters[0], 1u);
        } else {
            penumbraSampleListsSampleSlots[id] = PENUMBRA_SAMPLE_LISTS_NO_SLOT;
            atomicAdd(penumbraSampleListsGroupCounters[1u + (code - PENUMBRA_SAMPLE_LISTS_REJECTED)], 1u);
        }
        penumbraSampleListsSampleTexels[id] = code;
    }
    barrier();

    if (local < 1u + PENUMBRA_SAMPLE_LISTS_REASON_COUNT) {
        uint n = penumbraSampleListsGroupCounters[local];
        if (n != 0u) {
            if (local == 0u) {
                atomicAdd(penumbraSampleListsHeader.accepted, n);
            } else {
                atomicAdd(penumbraSampleListsHeader.rejected[local - 1u], n);
            }
        }
    }
}
