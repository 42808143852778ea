// penumbra — sample-based soft shadows, the closed casters' second pass (SoftSkips::closed_casters
// with SoftSkips::empty_blocks): a full-screen triangle (penumbra/common/fullscreen.vert.glsl) in
// the W x H grid viewport after the first pass, with the stencil op GL_ZERO: survives on the
// texels without a sample flagged near a kept closed triangle, so the occupancy stencil's count
// there drops to 0 and the second pass (stencil test GL_LESS b, early fragment tests) never shades
// them. They had nothing to do there: light_pass.frag.glsl returns on the same flag.
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std430, binding = PENUMBRA_SBS_NEAR_BINDING) readonly buffer PenumbraSbsNear { uint penumbraSbsNear[]; };

void main() {
    const PenumbraSbsParams P = penumbraSbsParams;
    const uvec2 texel = uvec2(gl_FragCoord.xy);
    if (penumbraSbsNear[P.counts.x + texel.y * P.grid.x + texel.x] != 0u) discard;
}
