// penumbra — alias-free hard shadows, resolve: one state per view sample id (sintorn2008 §3:
// "each view-sample recovers its corresponding shadow value"): PENUMBRA_AFH_LIT / SHADOWED from
// its shadow bit, BACK_FACING for light-back-facing samples (Fig. 2: dark by shading anyway),
// NO_SAMPLE for background, UNTESTED for samples outside the light frustum or non-finite, and for
// samples past the list blocks the light pass walked (each counted in the work buffer's OVERFLOW
// word). Parameters: PenumbraAfhParams (pass.y = sample count, pass.z = samples per list walked).
// Dispatch foldDispatch(divUp(count, 256)).
#include "penumbra/common/dispatch.glsl"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"
#include "penumbra/sample_lists/sample_lists_shared.h"

layout(local_size_x = 256) in;
layout(std430, binding = PENUMBRA_AFH_SLOTS_BINDING) readonly buffer PenumbraAfhSlots { uint penumbraAfhSlots[]; };
layout(std430, binding = PENUMBRA_AFH_TEXELS_BINDING) readonly buffer PenumbraAfhTexels { uint penumbraAfhTexels[]; };
layout(std430, binding = PENUMBRA_AFH_SHADOW_BINDING) readonly buffer PenumbraAfhShadow { uint penumbraAfhShadow[]; };
layout(std430, binding = PENUMBRA_AFH_STATES_BINDING) writeonly buffer PenumbraAfhStates { uint penumbraAfhStates[]; };
layout(std430, binding = PENUMBRA_AFH_OFFSETS_BINDING) readonly buffer PenumbraAfhOffsets { uint penumbraAfhOffsets[]; };
layout(std430, binding = PENUMBRA_AFH_WORK_BINDING) buffer PenumbraAfhWork { uint penumbraAfhWork[]; };
layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};

void main() {
    const uint group = penumbraLinearGroup();
    const uint count = penumbraAfhParams.pass.y;
    const uint id = group * 256u + gl_LocalInvocationID.x;
    if (group >= (count + 255u) / 256u || id >= count) return;
    const uint slot = penumbraAfhSlots[id];
    uint state;
    if (slot != PENUMBRA_SAMPLE_LISTS_NO_SLOT) {
        const uint local = slot - penumbraAfhOffsets[penumbraAfhTexels[id]];
        if (local >= penumbraAfhParams.pass.z) {
            state = PENUMBRA_AFH_UNTESTED;
            atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_OVERFLOW], 1u);
        } else {
            state = ((penumbraAfhShadow[slot >> 5u] >> (slot & 31u)) & 1u) != 0u ? PENUMBRA_AFH_SHADOWED
                                                                                  : PENUMBRA_AFH_LIT;
        }
    } else {
        const uint texel = penumbraAfhTexels[id];
        const uint reason = texel - PENUMBRA_SAMPLE_LISTS_REJECTED;
        state = reason == PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND    ? PENUMBRA_AFH_NO_SAMPLE
                : reason == PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING ? PENUMBRA_AFH_BACK_FACING
                                                                      : PENUMBRA_AFH_UNTESTED;
    }
    penumbraAfhStates[id] = state;
}
