// penumbra — shadow-edge stencil, Chebyshev moment map, geometry stage: the triangle in the map's
// texel space (penumbraAaDepthTriangle: clipped to w >= 1e-4 w_max, its depth plane, range and
// winding; the twin detail::aaDepthTriangle) handed flat to the fragment stage, and its
// conservative coverage of the grid (penumbra/conservative_raster, near plane w >= min_w only).
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"
#include "penumbra/alias_free_hard/degenerate.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };

layout(location = 0) in vec3 penumbraAaWorld[];
layout(location = 0) flat out dvec2 penumbraAaS0;
layout(location = 1) flat out dvec2 penumbraAaS1;
layout(location = 2) flat out dvec2 penumbraAaS2;
layout(location = 3) flat out dvec2 penumbraAaS3;
layout(location = 4) flat out dvec4 penumbraAaPlane;  // ga, gb, g0, dmin
layout(location = 6) flat out dvec4 penumbraAaRange;  // dmax, orientation, count, 0
layout(location = 8) flat out dvec4 penumbraAaBox;    // lo.x, lo.y, hi.x, hi.y

PenumbraAaDepthTriangle penumbraAaTriangle;

void penumbraAaEmitVertex(vec4 position) {
    gl_Position = position;
    penumbraAaS0 = penumbraAaTriangle.s[0].xy;
    penumbraAaS1 = penumbraAaTriangle.s[1].xy;
    penumbraAaS2 = penumbraAaTriangle.s[2].xy;
    penumbraAaS3 = penumbraAaTriangle.s[3].xy;
    penumbraAaPlane = dvec4(penumbraAaTriangle.ga, penumbraAaTriangle.gb, penumbraAaTriangle.g0, penumbraAaTriangle.dmin);
    penumbraAaRange = dvec4(penumbraAaTriangle.dmax, penumbraAaTriangle.orientation, double(penumbraAaTriangle.count), 0.0lf);
    penumbraAaBox = dvec4(penumbraAaTriangle.lo, penumbraAaTriangle.hi);
    EmitVertex();
}

#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) penumbraAaEmitVertex(position)
#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
    dvec3 p0 = dvec3(penumbraAaWorld[0]), p1 = dvec3(penumbraAaWorld[1]), p2 = dvec3(penumbraAaWorld[2]);
    if (penumbraAfhDegenerate(p0, p1, p2)) return;
    if (!penumbraAaDepthTriangle(penumbraAaParams.light_view_projection[0], penumbraAaParams.light_view_projection[1],
                                 penumbraAaParams.light_view_projection[2], penumbraAaParams.light_view_projection[3], p0, p1, p2,
                                 penumbraAaParams.grid.x, penumbraAaParams.grid.y, penumbraAaParams.moments.z != 0u,
                                 penumbraAaTriangle))
        return;
    penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position, penumbraConservativeParams);
}
