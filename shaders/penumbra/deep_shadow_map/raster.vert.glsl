// penumbra — deep shadow map build, vertex stage: casters projected with the light's view-projection
// (float, the twin's operation order) and their light depth; per-vertex opacity when the build uses
// it (attribute 1).
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"
#include "penumbra/deep_shadow_map/deep_shadow_map.glsl"

layout(std140, binding = PENUMBRA_DSM_BINDING_PARAMS) uniform PenumbraDsmParamsBlock { PenumbraDsmParams penumbraDsmParams; };

layout(location = 0) in vec3 penumbraDsmPosition;
layout(location = 1) in vec3 penumbraDsmVertexOpacity;
layout(location = 0) out float penumbraDsmVertexDepth;
layout(location = 1) out vec3 penumbraDsmVertexAlpha;

void main() {
    gl_Position = penumbraDsmTransform(penumbraDsmParams.light_view_projection, penumbraDsmPosition);
    penumbraDsmVertexDepth = penumbraDsmDepth(penumbraDsmParams.depth_row, penumbraDsmPosition);
    penumbraDsmVertexAlpha = penumbraDsmVertexOpacity;
}
