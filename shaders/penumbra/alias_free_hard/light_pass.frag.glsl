// penumbra — alias-free hard shadows, light pass, fragment stage (sintorn2008 §3.2, §3.3). One
// fragment per (caster triangle, light texel it may touch): walk one block of the texel's list of
// view samples and set the shadow bit of every sample the triangle blocks from the light
// (atomicOr: the result of all casters is combined, §3.3). No colour output; bind a framebuffer
// with no attachments of the grid's size.
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=0 PENUMBRA_AFH_SKIP_SHADOWED=0
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_AFH_FILTERED=0 PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=0 PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=1 PENUMBRA_AFH_COUNT_WORK=1
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

#ifndef PENUMBRA_AFH_COUNT_WORK
#define PENUMBRA_AFH_COUNT_WORK 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_CLIP_TO_BOX
#define PENUMBRA_CONSERVATIVE_CLIP_TO_BOX 1
#endif

#if PENUMBRA_AFH_COUNT_WORK
layout(std430, binding = PENUMBRA_AFH_WORK_BINDING) buffer PenumbraAfhWork { uint penumbraAfhWork[]; };
#endif
#include "penumbra/alias_free_hard/light_pass_lists.glsl"

// skip_empty_texels: the pipeline's occupancy stencil (occupancy.frag.glsl) culls the fragments of
// texels whose list block is empty before they are shaded, which needs the test before the stores.
layout(early_fragment_tests) in;

layout(location = 0) flat in vec3 penumbraAfhVertex0;
layout(location = 1) flat in vec3 penumbraAfhVertex1;
layout(location = 2) flat in vec3 penumbraAfhVertex2;
layout(location = 3) flat in vec4 penumbraAfhBox;

void main() {
#if PENUMBRA_CONSERVATIVE_CLIP_TO_BOX
    // Pixels outside the triangle's pixel-expanded bounding box cannot hold a blocked sample.
    if (!penumbraConservativeInsideBox(gl_FragCoord.xy, penumbraAfhBox)) {
#if PENUMBRA_AFH_COUNT_WORK
        atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_FRAGMENTS_SKIPPED], 1u);
#endif
        discard;
    }
#endif
    const uvec2 range = penumbraSampleListsBlock(ivec2(gl_FragCoord.xy), penumbraAfhParams.pass.x, penumbraAfhParams.grid.z);
    uint tests = 0u, fallbacks = 0u, skipped = 0u;
    penumbraAfhWalk(range, penumbraAfhVertex0, penumbraAfhVertex1, penumbraAfhVertex2, tests, fallbacks, skipped);
#if PENUMBRA_AFH_COUNT_WORK
    atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_FRAGMENTS], 1u);
    atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TESTS], tests);
    if (fallbacks > 0u) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_FALLBACKS], fallbacks);
    if (skipped > 0u) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TESTS_SKIPPED], skipped);
#endif
}
