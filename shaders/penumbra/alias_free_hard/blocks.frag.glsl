// penumbra — alias-free hard shadows, list-block predicate, fragment stage (see blocks.vert.glsl):
// survives (counts one sample for the occlusion query) when block `penumbraAfhBlock` of the
// longest list holds samples.
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

layout(std430, binding = PENUMBRA_AFH_HEADER_BINDING) readonly buffer PenumbraAfhHeaderBlock {
    PenumbraSampleListsHeader penumbraAfhHeader;
};
layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};
layout(location = 0) flat in uint penumbraAfhBlock;

void main() {
    // grid.z = samples per block: blocks needed = ceil(max_list_length / block), without overflow.
    const uint length = penumbraAfhHeader.max_list_length, block = penumbraAfhParams.grid.z;
    const uint needed = length / block + ((length % block) != 0u ? 1u : 0u);
    if (penumbraAfhBlock >= needed) discard;
}
