// penumbra — sample-based soft shadows, silhouette pass, fragment stage (SoftSkips::silhouettes):
// marks the light texel as a penumbra texel (the light pass walks its view samples with the full
// N-sample test; unmarked texels take one exact test from the light centre per pair). Idempotent
// plain stores; no colour output.
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std430, binding = PENUMBRA_SBS_MARKS_BINDING) writeonly buffer PenumbraSbsMarks { uint penumbraSbsMarks[]; };

void main() {
    const uvec2 texel = uvec2(gl_FragCoord.xy);
    penumbraSbsMarks[texel.y * penumbraSbsParams.grid.x + texel.x] = 1u;
}
