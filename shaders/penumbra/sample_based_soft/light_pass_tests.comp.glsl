// penumbra — sample-based soft shadows, deferred pairs' exact tests: one invocation per mask word
// the compute pass of deferred pairs (light_pass.comp.glsl) left pending — (list slot, triangle
// slot, word w, its uncertain bits) — deciding each bit b with the hard pipeline's exact fp64
// segment test against light sample 32 w + b of the view sample's set and rotation step (the test
// light_pass_work.glsl's exact-test site runs, on the same inputs: the same bits), then one
// atomicOr into the sample's mask word. Densely packed: a word's tests no longer wait on the
// longest pending list of its neighbours' pairs. Dispatched indirectly (light_pass_args.comp.glsl
// with PENUMBRA_SBS_ARGS_KIND=1); entries with no bits (a request past the buffer) are skipped.
// Defines: light_pass_work.glsl's.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_SILHOUETTES=1 PENUMBRA_SBS_CLOSED_CASTERS=1
#include "penumbra/sample_based_soft/light_pass_work.glsl"

layout(local_size_x = PENUMBRA_SBS_DEFERRAL_GROUP) in;

layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) readonly buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
layout(std430, binding = PENUMBRA_SBS_TESTS_BINDING) readonly buffer PenumbraSbsTests { uvec4 penumbraSbsTests[]; };
#include "penumbra/sample_based_soft/triangle_slots.glsl"

void main() {
    const uint k = gl_GlobalInvocationID.x;
    if (k >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TESTS_DISPATCHED]) return;
    const uvec4 entry = penumbraSbsTests[k];
    uint bits = entry.w;
    if (bits == 0u) return;
    const PenumbraSbsParams P = penumbraSbsParams;
    const uint slot = entry.x, w = entry.z, n = P.config.y;
    const dvec3 p = dvec3(penumbraSampleListsPosition(slot));
    const uint id = penumbraSampleListsId(slot);
    const uvec2 selection = penumbraSbsSelection(P, id);
    const uint sample_base = (selection.x * P.reserved.x + selection.y) * n + 32u * w;
    const dvec3 v0 = penumbraSbsSlotVertex(entry.y, 0u), v1 = penumbraSbsSlotVertex(entry.y, 1u), v2 = penumbraSbsSlotVertex(entry.y, 2u);
    uint m = 0u;
    while (bits != 0u) {
        const uint bit = uint(findLSB(bits));
        bits &= bits - 1u;
        if (penumbraAfhBlocks(v0, v1, v2, p, penumbraSbsSamples[sample_base + bit].xyz, P.epsilon.x, 0.0LF, P.center.w)) m |= 1u << bit;
    }
    if (m != 0u) atomicOr(penumbraSbsMasks[id * P.config.w + w], m);
}
