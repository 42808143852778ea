// Test entry: penumbraBentShade / penumbraBentDirect over (l_bend, l_f, c) triples, for
// bent_normals_gl_test (bit-identical to bentShade / bentDirect).
#include "penumbra/bent_normals/bent_normals.glsl"

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Inputs { vec4 inputs[]; };  // l_bend, l_f, c
layout(std430, binding = 1) writeonly buffer Outputs { vec2 outputs[]; };  // shade, direct
layout(location = 0) uniform uint count;

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    const vec4 in_ = inputs[i];
    outputs[i] = vec2(penumbraBentShade(in_.x, in_.y, in_.z), penumbraBentDirect(in_.x, in_.y, in_.z));
}
