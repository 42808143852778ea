// penumbra — shadow-edge stencil, Chebyshev moment map (galoppo2010 step 1), vertex stage: caster
// positions (attribute 0) projected with the light's float view-projection for the conservative
// emitter; the world position goes on (the geometry stage redoes the projection in double).
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"

layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };

layout(location = 0) in vec3 penumbraAaPosition;
layout(location = 0) out vec3 penumbraAaWorld;

void main() {
    penumbraAaWorld = penumbraAaPosition;
    gl_Position = penumbraAaParams.light_clip * vec4(penumbraAaPosition, 1.0);
}
