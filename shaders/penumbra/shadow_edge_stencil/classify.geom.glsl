// penumbra — shadow-edge stencil, pass 5, geometry stage: the triangle's conservative coverage of
// the light grid (penumbra/conservative_raster, single pass, near plane w >= min_w only) with its
// world-space vertices as flat outputs. Degenerate triangles (the oracle's rule) emit nothing.
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"
#include "penumbra/alias_free_hard/degenerate.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};

layout(location = 0) in vec3 penumbraAaWorld[];
layout(location = 0) flat out vec3 penumbraAaVertex0;
layout(location = 1) flat out vec3 penumbraAaVertex1;
layout(location = 2) flat out vec3 penumbraAaVertex2;

void penumbraAaEmitVertex(vec4 position) {
    gl_Position = position;
    penumbraAaVertex0 = penumbraAaWorld[0];
    penumbraAaVertex1 = penumbraAaWorld[1];
    penumbraAaVertex2 = penumbraAaWorld[2];
    EmitVertex();
}

#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) penumbraAaEmitVertex(position)
#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
    if (penumbraAfhDegenerate(dvec3(penumbraAaWorld[0]), dvec3(penumbraAaWorld[1]), dvec3(penumbraAaWorld[2]))) return;
    penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position, penumbraConservativeParams);
}
