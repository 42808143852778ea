// penumbra — sample-based soft shadows, list-block predicate, fragment stage (the vertex stage is
// the hard pipeline's penumbra/alias_free_hard/blocks.vert.glsl: one point per list block b,
// drawn inside occlusion query b): survives when block b of the longest list holds samples, so
// the light pass of block b runs under glBeginConditionalRender (sintorn2008 §3.1 multi-pass,
// decided on the GPU; the host never sees the list lengths).
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

layout(std430, binding = PENUMBRA_SBS_HEADER_BINDING) readonly buffer PenumbraSbsHeaderBlock {
    PenumbraSampleListsHeader penumbraSbsHeader;
};
layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(location = 0) flat in uint penumbraAfhBlock;

void main() {
    const uint length = penumbraSbsHeader.max_list_length, block = penumbraSbsParams.grid.z;
    const uint needed = length / block + ((length % block) != 0u ? 1u : 0u);
    if (penumbraAfhBlock >= needed) discard;
}
