// penumbra — alias-free hard shadows, list-block occupancy, fragment stage
// (AliasFreeHardOptions::skip_empty_texels): a full-screen triangle
// (penumbra/common/fullscreen.vert.glsl) in the W x H grid viewport, once per list block b
// (params.pass.x), with the stencil op GL_INCR: survives on the texels whose block b holds view
// samples. After blocks 0 .. b a texel's stencil value is the number of its non-empty blocks up to
// b, so the light pass of block b, drawn with the stencil test GL_LESS b and early fragment tests,
// never shades a fragment whose block holds no sample (it would test nothing: the same bits).
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};
layout(std430, binding = PENUMBRA_AFH_COUNTS_BINDING) readonly buffer PenumbraAfhCounts { uint penumbraAfhCounts[]; };
layout(std430, binding = PENUMBRA_AFH_OFFSETS_BINDING) readonly buffer PenumbraAfhOffsets { uint penumbraAfhOffsets[]; };

#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) penumbraAfhCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) penumbraAfhOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) vec4(0.0)  // not read here
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) 0u               // not read here
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH penumbraAfhParams.grid.x
#include "penumbra/sample_lists/sample_lists.glsl"

void main() {
    if (penumbraSampleListsBlock(ivec2(gl_FragCoord.xy), penumbraAfhParams.pass.x, penumbraAfhParams.grid.z).y == 0u) discard;
}
