// penumbra — sample-based soft shadows, light pass, compute stage of deferred pairs
// (SampleBasedSoftGpuOptions::deferred_pairs): one invocation per (triangle slot, view sample)
// pair the fragment stage appended during the draws before it (light_pass.frag.glsl: one per
// sample of its texel's list block), doing that pair's work (light_pass_work.glsl, on a block of
// that one sample) with its draw's parameter block (list block and flags from the triangle's
// slot) and the vertices the geometry stage stored there (triangle_slots.glsl).
// Dispatched indirectly with the group counts light_pass_args.comp.glsl wrote; reads the pairs it
// let through (PENUMBRA_SBS_DEFERRAL_DISPATCHED); empty pairs (below the capacity, of the
// fragment that straddled it) return at once.
// Pairs that need the LUT's tables go to the tables pass (light_pass_tables.comp.glsl; its buffer
// holds every pair), the pending exact-test words to the exact-test pass
// (light_pass_tests.comp.glsl) as far as its buffer holds them, else they run here.
// PENUMBRA_SBS_PER_FRAGMENT=1: one invocation per fragment whose pairs did not fit the pairs
// buffer ((triangle slot, texel), SampleBasedSoftGpuOptions::deferred_fragments), walking its
// whole list block, the tables included (a second program, dispatched after the first; nothing to
// do unless the pairs buffer filled up).
// Defines: light_pass_work.glsl's, PENUMBRA_SBS_PER_FRAGMENT.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_SILHOUETTES=1 PENUMBRA_SBS_CLOSED_CASTERS=1
// penumbra-permutation: PENUMBRA_SBS_PER_FRAGMENT=1
// penumbra-permutation: PENUMBRA_SBS_PER_FRAGMENT=1 PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_PER_FRAGMENT=1 PENUMBRA_SBS_WEDGES=1
// penumbra-permutation: PENUMBRA_SBS_WEDGES=1
#define PENUMBRA_SBS_STAGE 1  // tables to light_pass_tables.comp.glsl, exact tests to light_pass_tests.comp.glsl
#include "penumbra/sample_based_soft/light_pass_work.glsl"

layout(local_size_x = PENUMBRA_SBS_DEFERRAL_GROUP) in;

#include "penumbra/sample_based_soft/triangle_slots.glsl"

#if PENUMBRA_SBS_PER_FRAGMENT
layout(std430, binding = PENUMBRA_SBS_FRAGMENTS_BINDING) readonly buffer PenumbraSbsFragments { uvec2 penumbraSbsFragments[]; };

void main() {
    const uint k = gl_GlobalInvocationID.x;
    if (k >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENTS_DISPATCHED]) return;
    const uvec2 entry = penumbraSbsFragments[k];
    penumbraSbsFragmentPairs = 1u;
    const uvec2 range = penumbraSbsSlotWork(entry.x, uvec2(entry.y & 0xFFFFu, entry.y >> 16u), PENUMBRA_SBS_WHOLE_BLOCK);
#if PENUMBRA_SBS_COUNT_WORK
    atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_DEFERRED], range.y - penumbraSbsWedged);
#endif
}
#else
layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) readonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };

void main() {
    const uint k = gl_GlobalInvocationID.x;
    if (k >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_DISPATCHED]) return;
    const uvec2 entry = penumbraSbsPairs[k];
    if (entry.y == PENUMBRA_SBS_PAIR_EMPTY) return;
    const PenumbraSbsPair pair = penumbraSbsUnpackPair(entry);
    penumbraSbsPairIndex = k;
    penumbraSbsFragmentPairs = 0u;  // the fragment stage counted the fragment
    penumbraSbsSlotWork(pair.triangle, pair.texel, pair.index);
}
#endif
