// penumbra — the compute-shader copy every GPU block's benchmark is measured against: it moves
// the same bytes with the same dispatch folding, so "block bytes/s ÷ copy bytes/s" is a ratio
// that transfers between devices.
//
// Bindings: 0 = source uvec4[], 1 = destination uvec4[]. Uniform 0 = element count (uvec4s).
#include "penumbra/common/dispatch.glsl"

#ifndef PENUMBRA_COPY_GROUP_SIZE
#define PENUMBRA_COPY_GROUP_SIZE 256
#endif

layout(local_size_x = PENUMBRA_COPY_GROUP_SIZE) in;
layout(std430, binding = 0) readonly buffer PenumbraCopySource { uvec4 penumbraCopySource[]; };
layout(std430, binding = 1) writeonly buffer PenumbraCopyDestination { uvec4 penumbraCopyDestination[]; };
layout(location = 0) uniform uint penumbraCopyCount;

void main() {
    uint i = penumbraLinearGroup() * PENUMBRA_COPY_GROUP_SIZE + gl_LocalInvocationID.x;
    if (i < penumbraCopyCount) penumbraCopyDestination[i] = penumbraCopySource[i];
}
