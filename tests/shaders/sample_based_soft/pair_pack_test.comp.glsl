// Test entry: a deferred pair's entry packed as the light pass's fragment stage packs it
// (PENUMBRA_SBS_PAIR_X / _Y) and unpacked as the compute passes unpack it (penumbraSbsUnpackPair),
// over (triangle slot, index in the list block, texel x, texel y) at the options' limits, for
// sample_based_soft_gl_test.
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"
layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;  // read by triangle_slots.glsl's penumbraSbsSlotParams (unused here)
};
#include "penumbra/sample_based_soft/triangle_slots.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Inputs { uvec4 inputs[]; };  // slot, index, x, y
layout(std430, binding = 1) writeonly buffer Outputs { uvec4 outputs[]; };
layout(location = 0) uniform uint count;

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    const uvec4 v = inputs[i];
    const PenumbraSbsPair pair = penumbraSbsUnpackPair(uvec2(PENUMBRA_SBS_PAIR_X(v.x, v.y), PENUMBRA_SBS_PAIR_Y(v.z, v.w, v.y)));
    outputs[i] = uvec4(pair.triangle, pair.index, pair.texel);
}
