// penumbra — deep shadow map build, geometry stage: the triangle's homogeneous edge normals (the twin
// detail::dsmTriangle), normalised to a positive determinant, handed flat to the fragment stage, and
// its conservative coverage of the R x R light grid (penumbra/conservative_raster, single pass,
// near plane w >= min_w only): every texel holding a covered sub-sample gets a fragment.
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"
#include "penumbra/deep_shadow_map/deep_shadow_map.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};

layout(location = 0) in float penumbraDsmVertexDepth[];
layout(location = 1) in vec3 penumbraDsmVertexAlpha[];
layout(location = 0) flat out vec3 penumbraDsmN0;
layout(location = 1) flat out vec3 penumbraDsmN1;
layout(location = 2) flat out vec3 penumbraDsmN2;
layout(location = 3) flat out vec3 penumbraDsmD;
layout(location = 4) flat out uint penumbraDsmTriangleId;
layout(location = 5) flat out vec3 penumbraDsmA0;
layout(location = 6) flat out vec3 penumbraDsmA1;
layout(location = 7) flat out vec3 penumbraDsmA2;

vec3 penumbraDsmN[3];

void penumbraDsmEmitVertex(vec4 position) {
    gl_Position = position;
    penumbraDsmN0 = penumbraDsmN[0];
    penumbraDsmN1 = penumbraDsmN[1];
    penumbraDsmN2 = penumbraDsmN[2];
    penumbraDsmD = vec3(penumbraDsmVertexDepth[0], penumbraDsmVertexDepth[1], penumbraDsmVertexDepth[2]);
    penumbraDsmTriangleId = uint(gl_PrimitiveIDIn);
    penumbraDsmA0 = penumbraDsmVertexAlpha[0];
    penumbraDsmA1 = penumbraDsmVertexAlpha[1];
    penumbraDsmA2 = penumbraDsmVertexAlpha[2];
    EmitVertex();
}

#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) penumbraDsmEmitVertex(position)
#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
    vec3 h0 = gl_in[0].gl_Position.xyw, h1 = gl_in[1].gl_Position.xyw, h2 = gl_in[2].gl_Position.xyw;
    penumbraDsmN[0] = penumbraDsmCross(h1, h2);
    penumbraDsmN[1] = penumbraDsmCross(h2, h0);
    penumbraDsmN[2] = penumbraDsmCross(h0, h1);
    precise float det = (h0.x * penumbraDsmN[0].x + h0.y * penumbraDsmN[0].y) + h0.z * penumbraDsmN[0].z;
    if (!(det != 0.0) || penumbraDsmNonFinite(det)) return;
    if (det < 0.0) {
        penumbraDsmN[0] = -penumbraDsmN[0];
        penumbraDsmN[1] = -penumbraDsmN[1];
        penumbraDsmN[2] = -penumbraDsmN[2];
    }
    penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position, penumbraConservativeParams);
}
