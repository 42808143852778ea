// penumbra — sample-based soft shadows, resolve (sintorn2008 §4: "the visibility is the number
// of unset bits divided by N"): one float per view-sample id, the visible fraction
// 1 - popcount(mask) / N, or PENUMBRA_SBS_VISIBILITY_NO_SAMPLE (background) /
// PENUMBRA_SBS_VISIBILITY_UNTESTED (outside the light frustum, non-finite, or past the list blocks
// the light pass walked: counted in the work buffer's OVERFLOW word). Dispatch
// foldDispatch(divUp(count, 256)). Parameters: PenumbraSbsParams (counts.x = sample count,
// counts.y = samples per list walked, config.y = N, config.w = words per sample).
#include "penumbra/common/dispatch.glsl"
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

layout(local_size_x = 256) in;
layout(std430, binding = PENUMBRA_SBS_SLOTS_BINDING) readonly buffer PenumbraSbsSlots { uint penumbraSbsSlots[]; };
layout(std430, binding = PENUMBRA_SBS_TEXELS_BINDING) readonly buffer PenumbraSbsTexels { uint penumbraSbsTexels[]; };
layout(std430, binding = PENUMBRA_SBS_RESOLVE_OFFSETS_BINDING) readonly buffer PenumbraSbsOffsets { uint penumbraSbsOffsets[]; };
layout(std430, binding = PENUMBRA_SBS_MASKS_BINDING) readonly buffer PenumbraSbsMasks { uint penumbraSbsMasks[]; };
layout(std430, binding = PENUMBRA_SBS_VISIBILITY_BINDING) writeonly buffer PenumbraSbsVisibility { float penumbraSbsVisibility[]; };
layout(std430, binding = PENUMBRA_SBS_WORK_BINDING) buffer PenumbraSbsWork { uint penumbraSbsWork[]; };
layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};

void main() {
    const uint group = penumbraLinearGroup();
    const uint count = penumbraSbsParams.counts.x;
    const uint id = group * 256u + gl_LocalInvocationID.x;
    if (group >= (count + 255u) / 256u || id >= count) return;
    const uint slot = penumbraSbsSlots[id];
    float visibility;
    if (slot != PENUMBRA_SAMPLE_LISTS_NO_SLOT) {
        const uint local = slot - penumbraSbsOffsets[penumbraSbsTexels[id]];
        if (local >= penumbraSbsParams.counts.y) {
            visibility = float(PENUMBRA_SBS_VISIBILITY_UNTESTED);
            atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_OVERFLOW], 1u);
        } else {
            const uint words = penumbraSbsParams.config.w, n = penumbraSbsParams.config.y;
            uint blocked = 0u;
            for (uint w = 0u; w < words; ++w) blocked += uint(bitCount(penumbraSbsMasks[id * words + w]));
            visibility = 1.0 - float(blocked) / float(n);
        }
    } else {
        const uint reason = penumbraSbsTexels[id] - PENUMBRA_SAMPLE_LISTS_REJECTED;
        visibility = reason == PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND ? float(PENUMBRA_SBS_VISIBILITY_NO_SAMPLE)
                                                                       : float(PENUMBRA_SBS_VISIBILITY_UNTESTED);
    }
    penumbraSbsVisibility[id] = visibility;
}
