// penumbra — sample-based soft shadows, list-block predicate, fragment stage (the vertex stage is
// the hard pipeline's penumbra/alias_free_hard/blocks.vert.glsl: one point per list block b,
// drawn inside occlusion query b): survives when block b of the longest list holds samples, so
// the light pass of block b runs under glBeginConditionalRender (sintorn2008 §3.1 multi-pass,
// decided on the GPU; the host never sees the list lengths).
// PENUMBRA_SBS_FALLBACK_PREDICATE=1 (deferred pairs): survives only when, besides, the deferring
// draws just overflowed (light_pass_args.comp.glsl's fallback flag): the predicate of their redraw
// with the fragment-stage program. GL conditional renders do not nest, so one query holds both.
// penumbra-permutation: PENUMBRA_SBS_FALLBACK_PREDICATE=0
// penumbra-permutation: PENUMBRA_SBS_FALLBACK_PREDICATE=1
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

#ifndef PENUMBRA_SBS_FALLBACK_PREDICATE
#define PENUMBRA_SBS_FALLBACK_PREDICATE 0
#endif

layout(std430, binding = PENUMBRA_SBS_HEADER_BINDING) readonly buffer PenumbraSbsHeaderBlock {
    PenumbraSampleListsHeader penumbraSbsHeader;
};
layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
#if PENUMBRA_SBS_FALLBACK_PREDICATE
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) readonly buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
#endif
layout(location = 0) flat in uint penumbraAfhBlock;

void main() {
    const uint length = penumbraSbsHeader.max_list_length, block = penumbraSbsParams.grid.z;
    const uint needed = length / block + ((length % block) != 0u ? 1u : 0u);
    if (penumbraAfhBlock >= needed) discard;
#if PENUMBRA_SBS_FALLBACK_PREDICATE
    if (penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FALLBACK] == 0u) discard;
#endif
}
