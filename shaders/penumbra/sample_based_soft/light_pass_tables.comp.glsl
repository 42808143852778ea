// penumbra — sample-based soft shadows, deferred pairs' tables pass: one invocation per pair the
// pairs' compute pass (light_pass.comp.glsl) found to need the LUT's tables (its index in the pairs
// buffer), running the pair's work (light_pass_work.glsl) again: the same steps on the same inputs
// up to the tables (the pairs' pass counted them), then the tables and the exact tests (handed on
// to light_pass_tests.comp.glsl as far as its buffer holds them). Densely packed: in the pairs'
// pass a group of lanes would run the tables as long as one of its pairs needed them (most end
// before), and llvmpipe would run them in every group. Dispatched indirectly
// (light_pass_args.comp.glsl with PENUMBRA_SBS_ARGS_KIND=2).
// Defines: light_pass_work.glsl's.
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_SBS_MODE=1 PENUMBRA_SBS_COUNT_WORK=0
// penumbra-permutation: PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_SILHOUETTES=1 PENUMBRA_SBS_CLOSED_CASTERS=1
#define PENUMBRA_SBS_STAGE 2
#include "penumbra/sample_based_soft/light_pass_work.glsl"

layout(local_size_x = PENUMBRA_SBS_DEFERRAL_GROUP) in;

layout(std430, binding = PENUMBRA_SBS_TABLE_PAIRS_BINDING) readonly buffer PenumbraSbsTableWorkIn { uint penumbraSbsTableWork[]; };
layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) readonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };
#include "penumbra/sample_based_soft/triangle_slots.glsl"

void main() {
    const uint k = gl_GlobalInvocationID.x;
    if (k >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SAMPLES_DISPATCHED]) return;
    const PenumbraSbsPair pair = penumbraSbsUnpackPair(penumbraSbsPairs[penumbraSbsTableWork[k]]);
    penumbraSbsSlotWork(pair.triangle, pair.texel, pair.index);
}
