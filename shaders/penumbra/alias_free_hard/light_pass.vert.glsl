// penumbra — alias-free hard shadows, light pass, vertex stage (sintorn2008 §3.2). Caster
// positions come from the hook penumbraAfhCasterPosition() (caster_position.glsl: attribute 0 by
// default; replace it for skinning, instancing or packed positions) and are projected with the
// light view-projection of the frustum block the sample lists were built with (fitted on the GPU,
// §4.3: the host never sees it).
// PENUMBRA_CONSERVATIVE_SPILL_DRAW=1: the vertex stage of the Fixed-6 spill pass, drawn with
// glDrawArraysIndirect and no vertex attributes: it outputs nothing (the geometry stage reads the
// spilled triangle from the spill buffers) and never calls the caster hook.
// penumbra-permutation: PENUMBRA_CONSERVATIVE_SPILL_DRAW=0
// penumbra-permutation: PENUMBRA_CONSERVATIVE_SPILL_DRAW=1
#ifndef PENUMBRA_CONSERVATIVE_SPILL_DRAW
#define PENUMBRA_CONSERVATIVE_SPILL_DRAW 0
#endif

#if PENUMBRA_CONSERVATIVE_SPILL_DRAW
void main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); }
#else
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

layout(std140, binding = PENUMBRA_AFH_FRUSTUM_BINDING) uniform PenumbraAfhFrustumBlock {
    PenumbraSampleListsFrustum penumbraAfhFrustum;
};

#include "penumbra/alias_free_hard/caster_position.glsl"

layout(location = 0) out vec3 penumbraAfhWorld;

void main() {
    const vec3 p = penumbraAfhCasterPosition();
    penumbraAfhWorld = p;
    gl_Position = penumbraAfhFrustum.view_projection * vec4(p, 1.0);
}
#endif
