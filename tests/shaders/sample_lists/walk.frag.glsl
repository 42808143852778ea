#version 450
// Test-only entry (tests/sample_lists_test.cpp): an integrator-style light pass. Drawn as a
// full-screen triangle into a W x H framebuffer without attachments, one fragment per light texel
// walks block `walkBlock` (of `walkBlockSize` slots) of that texel's list through
// penumbra/sample_lists/sample_lists.glsl (the test draws one pass per block), re-projects every
// stored position (it must land in this very texel), checks the sample's slot back-pointer,
// counts the visit, and sets a known pattern of shadow bits through shadow_bits.glsl (single
// bits for even ids, whole masks for odd ids), reading each one back.
//
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_SHADOW_BITS=1
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_SHADOW_BITS=5
// penumbra-permutation: PENUMBRA_SAMPLE_LISTS_SHADOW_BITS=40
//
// Bindings: uniform block 0 = PenumbraSampleListsParams of the build; SSBO 0 counts, 1 offsets,
// 2 list positions, 3 list ids, 4 sample slots, 5 shadow words, 6 results {errors, first bad
// slot, 2 x pad, visits[sample count]}. Uniforms: location 0 = walkBlock, 1 = walkBlockSize.
#include "penumbra/sample_lists/sample_lists_shared.h"

layout(std140, binding = 0) uniform WalkParamsBlock { PenumbraSampleListsParams walkParams; };
layout(std430, binding = 0) readonly buffer WalkCounts { uint walkCounts[]; };
layout(std430, binding = 1) readonly buffer WalkOffsets { uint walkOffsets[]; };
layout(std430, binding = 2) readonly buffer WalkPositions { vec4 walkPositions[]; };
layout(std430, binding = 3) readonly buffer WalkIds { uint walkIds[]; };
layout(std430, binding = 4) readonly buffer WalkSlots { uint walkSlots[]; };
layout(std430, binding = 5) coherent buffer WalkShadow { uint walkShadow[]; };
layout(location = 0) uniform uint walkBlock;
layout(location = 1) uniform uint walkBlockSize;
layout(std430, binding = 6) buffer WalkResults {
    uint walkErrors;
    uint walkFirstBad;
    uint walkPad0;
    uint walkPad1;
    uint walkVisits[];
};

#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) walkCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) walkOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) walkPositions[slot]
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) walkIds[slot]
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH walkParams.grid.x
#define PENUMBRA_SAMPLE_LISTS_SHADOW_OR(word, mask) atomicOr(walkShadow[word], mask)
#define PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW(word) walkShadow[word]
#include "penumbra/sample_lists/project.glsl"
#include "penumbra/sample_lists/sample_lists.glsl"
#include "penumbra/sample_lists/shadow_bits.glsl"

// Bit k of sample `id` is set iff this is true (the test computes the same on the CPU).
bool walkPattern(uint id, uint k) {
    return (((id * 2654435761u) ^ (k * 40503u)) & 4u) != 0u;
}

void walkFail(uint slot) {
    atomicAdd(walkErrors, 1u);
    atomicMin(walkFirstBad, slot);
}

void main() {
    const ivec2 texel = ivec2(gl_FragCoord.xy);
    const uint list = penumbraSampleListsIndex(texel);
    const uvec2 range = penumbraSampleListsBlock(texel, walkBlock, walkBlockSize);
    // Re-project without the light-facing test (the walk has no normals).
    const uvec4 grid = uvec4(walkParams.grid.xyz, walkParams.grid.w & ~PENUMBRA_SAMPLE_LISTS_FLAG_CULL_BACK_FACING);
    for (uint slot = range.x; slot < range.x + range.y; ++slot) {
        const uint id = penumbraSampleListsId(slot);
        const vec3 p = penumbraSampleListsPosition(slot);
        vec4 t;
        const uint code = penumbraSampleListsClassify(walkParams.light_texture, walkParams.light, grid, vec4(p, 1.0),
                                                      vec3(0.0), t);
        if (id >= walkParams.grid.z || code != list || walkSlots[id] != slot ||
            walkPositions[slot].w != 1.0) {
            walkFail(slot);
            continue;
        }
        atomicAdd(walkVisits[id], 1u);
        if ((id & 1u) == 0u) {
            for (uint k = 0u; k < penumbraSampleListsShadowBits; ++k) {
                if (walkPattern(id, k)) penumbraSampleListsSetShadowBit(slot, k);
            }
        } else {
            for (uint word = 0u; word * 32u < penumbraSampleListsShadowBits; ++word) {
                uint mask = 0u;
                for (uint i = 0u; i < 32u && word * 32u + i < penumbraSampleListsShadowBits; ++i) {
                    if (walkPattern(id, word * 32u + i)) mask |= 1u << i;
                }
                penumbraSampleListsOrShadowMask(slot, word, mask);
                if (penumbraSampleListsShadowMask(slot, word) != mask) walkFail(slot);
            }
        }
        for (uint k = 0u; k < penumbraSampleListsShadowBits; ++k) {
            if (penumbraSampleListsShadowBit(slot, k) != walkPattern(id, k)) walkFail(slot);
        }
    }
}
