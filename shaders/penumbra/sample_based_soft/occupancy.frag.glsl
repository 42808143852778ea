// penumbra — sample-based soft shadows, full-screen passes over the light grid (a full-screen
// triangle, penumbra/common/fullscreen.vert.glsl, in the W x H grid viewport), by
// PENUMBRA_SBS_OCCUPANCY:
// 0 (default) — list-block occupancy (SoftSkips::empty_blocks): drawn once per list block b
//   (params.grid.w) with the stencil op GL_INCR, survives on the texels whose block b holds view
//   samples. After blocks 0 .. b a texel's stencil value is the number of its non-empty blocks up
//   to b (capped at 255), so the light pass of block b, drawn with the stencil test GL_LESS b and
//   early fragment tests, never shades an empty block's fragment.
// 1 — the closed casters' second pass (SoftSkips::closed_casters), its stencil: drawn once after
//   the first pass with the stencil op GL_ZERO, survives on the texels without a sample flagged
//   near a kept closed triangle, so their occupancy drops to 0 and the second pass never shades
//   them (light_pass.frag.glsl would return on the same flag).
// 2 — the closed casters' second pass, its predicates: drawn once per list block b inside an
//   occlusion query, survives on the texels whose block b holds samples and that hold a flagged
//   sample. The second pass draws block b only where some fragment survived: usually none, and
//   then the pass costs nothing.
// penumbra-permutation: PENUMBRA_SBS_OCCUPANCY=1
// penumbra-permutation: PENUMBRA_SBS_OCCUPANCY=2
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

#ifndef PENUMBRA_SBS_OCCUPANCY
#define PENUMBRA_SBS_OCCUPANCY 0
#endif

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std430, binding = PENUMBRA_SBS_COUNTS_BINDING) readonly buffer PenumbraSbsCounts { uint penumbraSbsCounts[]; };
layout(std430, binding = PENUMBRA_SBS_OFFSETS_BINDING) readonly buffer PenumbraSbsOffsets { uint penumbraSbsOffsets[]; };
#if PENUMBRA_SBS_OCCUPANCY != 0
layout(std430, binding = PENUMBRA_SBS_NEAR_BINDING) readonly buffer PenumbraSbsNear { uint penumbraSbsNear[]; };
#endif

#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) penumbraSbsCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) penumbraSbsOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) vec4(0.0)  // not read here
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) 0u               // not read here
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH penumbraSbsParams.grid.x
#include "penumbra/sample_lists/sample_lists.glsl"

void main() {
    const PenumbraSbsParams P = penumbraSbsParams;
    const uvec2 texel = uvec2(gl_FragCoord.xy);
#if PENUMBRA_SBS_OCCUPANCY != 0
    // The texel's flag: past the per-sample flags (light_pass_work.glsl).
    const bool near = penumbraSbsNear[P.counts.x + texel.y * P.grid.x + texel.x] != 0u;
#endif
#if PENUMBRA_SBS_OCCUPANCY == 1
    if (near) discard;
#else
#if PENUMBRA_SBS_OCCUPANCY == 2
    if (!near) discard;
#endif
    if (penumbraSampleListsBlock(ivec2(texel), P.grid.w, P.grid.z).y == 0u) discard;
#endif
}
