// penumbra — what both hard-shadow light passes read (the raster pass's fragment stage,
// light_pass.frag.glsl, and the compute pass's tiles, light_pass_tiles.comp.glsl): the parameter
// block, the sample lists and the shadow bits at the pipeline's bindings, the list walk and shadow
// bit hooks, the box clip and the blocker test. No hooks of its own.
#ifndef PENUMBRA_AFH_LIGHT_PASS_LISTS_GLSL
#define PENUMBRA_AFH_LIGHT_PASS_LISTS_GLSL

layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};
layout(std430, binding = PENUMBRA_AFH_COUNTS_BINDING) readonly buffer PenumbraAfhCounts { uint penumbraAfhCounts[]; };
layout(std430, binding = PENUMBRA_AFH_OFFSETS_BINDING) readonly buffer PenumbraAfhOffsets { uint penumbraAfhOffsets[]; };
layout(std430, binding = PENUMBRA_AFH_POSITIONS_BINDING) readonly buffer PenumbraAfhPositions { vec4 penumbraAfhPositions[]; };
layout(std430, binding = PENUMBRA_AFH_SHADOW_BINDING) coherent buffer PenumbraAfhShadow { uint penumbraAfhShadow[]; };

#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) penumbraAfhCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) penumbraAfhOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) penumbraAfhPositions[slot]
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) 0u
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH penumbraAfhParams.grid.x
#define PENUMBRA_SAMPLE_LISTS_SHADOW_BITS 1
#define PENUMBRA_SAMPLE_LISTS_SHADOW_OR(word, mask) atomicOr(penumbraAfhShadow[word], mask)
#define PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW(word) penumbraAfhShadow[word]
#include "penumbra/sample_lists/sample_lists.glsl"
#include "penumbra/sample_lists/shadow_bits.glsl"
#include "penumbra/conservative_raster/conservative_raster_clip.glsl"
#include "penumbra/alias_free_hard/blocker_test.glsl"

#endif
