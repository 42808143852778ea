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


#ifndef PENUMBRA_AFH_SKIP_SHADOWED
#define PENUMBRA_AFH_SKIP_SHADOWED 1
#endif

// Walks the list slots `range` (first, count) and sets the shadow bit of every sample the triangle
// (v0, v1, v2) blocks from the parameter block's light; counts tests, fp64 fallbacks and samples
// skipped because another caster already shadowed them (OR is idempotent: same bits).
void penumbraAfhWalk(uvec2 range, vec3 v0, vec3 v1, vec3 v2, inout uint tests, inout uint fallbacks, inout uint skipped) {
    // Directional light: the light point on the sample's own ray, `reach` away (exact: the segment
    // is parallel to the light direction; casters must lie within reach). Exact mode: filtered
    // (float with a proven bound, double where uncertain) unless PENUMBRA_AFH_FILTERED 0.
    const float reach = penumbraAfhParams.tolerance.z;
    const penumbraAfhReal eps = penumbraAfhReal(penumbraAfhParams.exact.x);  // double in exact mode, as the oracle's
    const penumbraAfhReal offset = penumbraAfhReal(penumbraAfhParams.tolerance.y);
    const double scene_extent = penumbraAfhParams.exact.y;  // E of the coplanar rule's scale
    for (uint slot = range.x; slot < range.x + range.y; ++slot) {
#if PENUMBRA_AFH_SKIP_SHADOWED
        if (penumbraSampleListsShadowBit(slot, 0u)) {
            ++skipped;
            continue;
        }
#endif
        ++tests;
        if (penumbraAfhBlocksLightCounted(v0, v1, v2, penumbraSampleListsPosition(slot), penumbraAfhParams.light, reach, eps,
                                          offset, scene_extent, fallbacks)) {
            penumbraSampleListsSetShadowBit(slot, 0u);
        }
    }
}

#endif
