// penumbra — sample-based soft shadows, list-block occupancy, fragment stage (SoftSkips::
// empty_blocks): a full-screen triangle (penumbra/common/fullscreen.vert.glsl) in the W x H grid
// viewport, once per list block b (params.grid.w), with the stencil op GL_INCR: survives on the
// texels whose block b holds view samples. After blocks 0 .. b a texel's stencil value is the
// number of its non-empty blocks up to b (capped at 255), so the light pass of block b, drawn with
// the stencil test GL_LESS b and early fragment tests, never shades an empty block's fragment.
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std430, binding = PENUMBRA_SBS_COUNTS_BINDING) readonly buffer PenumbraSbsCounts { uint penumbraSbsCounts[]; };
layout(std430, binding = PENUMBRA_SBS_OFFSETS_BINDING) readonly buffer PenumbraSbsOffsets { uint penumbraSbsOffsets[]; };

#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) penumbraSbsCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) penumbraSbsOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) vec4(0.0)  // not read here
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) 0u               // not read here
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH penumbraSbsParams.grid.x
#include "penumbra/sample_lists/sample_lists.glsl"

void main() {
    const PenumbraSbsParams P = penumbraSbsParams;
    if (penumbraSampleListsBlock(ivec2(gl_FragCoord.xy), P.grid.w, P.grid.z).y == 0u) discard;
}
