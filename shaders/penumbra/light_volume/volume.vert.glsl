// penumbra — the light volume's vertex stage (billeter2010): vertex gl_VertexID of the tessellator's
// triangle list (packed lattice corner or the apex), displaced to the lattice depth and unprojected
// through the light, then projected by the camera. Drawn with the tessellator's indirect command,
// no vertex attributes.
#include "penumbra/light_volume/light_volume_shared.h"

layout(std140, binding = PENUMBRA_LV_BINDING_RENDER_PARAMS) uniform PenumbraLvRenderBlock { PenumbraLightVolumeRenderParams penumbraLvRender; };
layout(std430, binding = PENUMBRA_LV_BINDING_CORNERS) readonly buffer PenumbraLvCorners { float penumbraLvCorners[]; };
layout(std430, binding = PENUMBRA_LV_BINDING_TRIANGLES) readonly buffer PenumbraLvTriangles { uint penumbraLvTriangles[]; };

out vec3 penumbraLvRelative;  // position relative to the eye

void main() {
    const uint vertex = penumbraLvTriangles[gl_VertexID];
    vec3 p;
    if (vertex == PENUMBRA_LV_APEX) {
        p = penumbraLvRender.light.xyz;
    } else {
        const uint r = penumbraLvRender.size.x, i = vertex & 0xffffu, j = vertex >> 16u;
        const float depth = penumbraLvCorners[j * (r + 1u) + i];
        const vec4 q = penumbraLvRender.light_to_eye * vec4(2.0 * float(i) / float(r) - 1.0, 2.0 * float(j) / float(r) - 1.0, 2.0 * depth - 1.0, 1.0);
        p = q.xyz / q.w;
    }
    penumbraLvRelative = p;
    gl_Position = penumbraLvRender.camera_view_projection * vec4(p, 1.0);
}
