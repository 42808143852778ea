// penumbra — sample-based soft shadows, light pass, compute stage of deferred pairs
// (SampleBasedSoftGpuOptions::deferred_pairs): one invocation per (triangle slot, texel) pair the
// fragment stage appended during the draws before it (light_pass.frag.glsl), doing that pair's
// work (light_pass_work.glsl) with its draw's parameter block (list block and flags from the
// triangle's slot) and the vertices the geometry stage stored there (triangle_slots.glsl).
// Dispatched indirectly with the group counts light_pass_args.comp.glsl wrote; reads the pairs it
// let through (PENUMBRA_SBS_DEFERRAL_DISPATCHED).
// Samples that need the LUT's tables go to the tables pass (light_pass_tables.comp.glsl), the
// pending exact-test words to the exact-test pass (light_pass_tests.comp.glsl), each as far as its
// buffer holds them, else they run here.
// Defines: light_pass_work.glsl's.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_SILHOUETTES=1 PENUMBRA_SBS_CLOSED_CASTERS=1
#define PENUMBRA_SBS_STAGE 1  // tables to light_pass_tables.comp.glsl, exact tests to light_pass_tests.comp.glsl
#include "penumbra/sample_based_soft/light_pass_work.glsl"

layout(local_size_x = PENUMBRA_SBS_DEFERRAL_GROUP) in;

layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) readonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };
#include "penumbra/sample_based_soft/triangle_slots.glsl"

void main() {
    const uint k = gl_GlobalInvocationID.x;
    if (k >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_DISPATCHED]) return;
    const uvec2 pair = penumbraSbsPairs[k];
    const uvec2 texel = uvec2(pair.y & 0xFFFFu, pair.y >> 16u);
    const PenumbraSbsParams P = penumbraSbsSlotParams(pair.x);
    penumbraSbsTestTriangle = pair.x;
    penumbraSbsTexelWork(P, texel, penumbraSampleListsBlock(ivec2(texel), P.grid.w, P.grid.z), penumbraSbsSlotVertex(pair.x, 0u),
                         penumbraSbsSlotVertex(pair.x, 1u), penumbraSbsSlotVertex(pair.x, 2u));
}
