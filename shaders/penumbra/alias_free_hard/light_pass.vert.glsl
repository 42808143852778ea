// penumbra — alias-free hard shadows, light pass, vertex stage (sintorn2008 §3.2). Caster
// positions come from the hook penumbraAfhCasterPosition() (caster_position.glsl: attribute 0 by
// default; replace it for skinning, instancing or packed positions) and are projected with the
// light view-projection of the frustum block the sample lists were built with (fitted on the GPU,
// §4.3: the host never sees it).
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
