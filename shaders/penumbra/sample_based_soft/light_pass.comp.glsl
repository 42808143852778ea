// penumbra — sample-based soft shadows, light pass, compute stage of deferred pairs
// (SampleBasedSoftGpuOptions::deferred_pairs): one invocation per (triangle slot, texel) pair the
// fragment stage appended during the draws before it (light_pass.frag.glsl), doing that pair's
// work (light_pass_work.glsl) with its draw's parameter block (list block and flags from the
// triangle's slot) and the vertices the geometry stage stored there. Dispatched indirectly with the group counts light_pass_args.comp.glsl
// wrote; reads the pairs light_pass_args.comp.glsl let through (PENUMBRA_SBS_DEFERRAL_DISPATCHED).
// The exact tests of its pairs' pending words go to the exact-test pass (light_pass_tests.comp.glsl)
// as far as its buffer holds them, else they run here.
// Defines: light_pass_work.glsl's.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_SILHOUETTES=1 PENUMBRA_SBS_CLOSED_CASTERS=1
#define PENUMBRA_SBS_DEFER_TESTS 1  // pending exact tests go to light_pass_tests.comp.glsl
#include "penumbra/sample_based_soft/light_pass_work.glsl"

layout(local_size_x = PENUMBRA_SBS_DEFERRAL_GROUP) in;

layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) readonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) readonly buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };

vec3 penumbraSbsStoredVertex(uint base) {
    return uintBitsToFloat(uvec3(penumbraSbsTriangles[base], penumbraSbsTriangles[base + 1u], penumbraSbsTriangles[base + 2u]));
}

void main() {
    const uint k = gl_GlobalInvocationID.x;
    if (k >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_DISPATCHED]) return;
    const uvec2 pair = penumbraSbsPairs[k];
    const uvec2 texel = uvec2(pair.y & 0xFFFFu, pair.y >> 16u);
    const uint base = PENUMBRA_SBS_TRIANGLE_WORDS * pair.x;
    // The draw's parameter block: every slot shares all but the list block and the flags.
    PenumbraSbsParams P = penumbraSbsParams;
    const uint draw = penumbraSbsTriangles[base + 9u];
    penumbraSbsTestTriangle = pair.x;
    P.grid.w = draw & 0xFFFFu;
    P.reserved.y = draw >> 16u;
    penumbraSbsTexelWork(P, texel, penumbraSampleListsBlock(ivec2(texel), P.grid.w, P.grid.z), dvec3(penumbraSbsStoredVertex(base)),
                         dvec3(penumbraSbsStoredVertex(base + 3u)), dvec3(penumbraSbsStoredVertex(base + 6u)));
}
