// penumbra — alias-free hard shadows, light pass, geometry stage (sintorn2008 §3.2, §3.3).
// Culls per the caster class (closed meshes: only light-back-facing triangles cast, §3.3, which
// removes self-shadowing without any bias), then emits the triangle's conservative coverage of
// the light grid (penumbra/conservative_raster) with the world-space vertices as flat outputs: the
// fragment stage tests each listed view sample against the triangle itself.
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_EXACT=0
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_EXACT=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=0 PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_AFH_COUNT_WORK=1
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

#ifndef PENUMBRA_AFH_EXACT
#define PENUMBRA_AFH_EXACT 1
#endif
#ifndef PENUMBRA_AFH_COUNT_WORK
#define PENUMBRA_AFH_COUNT_WORK 0
#endif

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};
layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};
#if PENUMBRA_AFH_COUNT_WORK
layout(std430, binding = PENUMBRA_AFH_WORK_BINDING) buffer PenumbraAfhWork { uint penumbraAfhWork[]; };
#endif

layout(location = 0) in vec3 penumbraAfhWorld[];
layout(location = 0) flat out vec3 penumbraAfhVertex0;
layout(location = 1) flat out vec3 penumbraAfhVertex1;
layout(location = 2) flat out vec3 penumbraAfhVertex2;
layout(location = 3) flat out vec4 penumbraAfhBox;

void penumbraAfhEmitVertex(vec4 position, vec4 box) {
    gl_Position = position;
    penumbraAfhVertex0 = penumbraAfhWorld[0];
    penumbraAfhVertex1 = penumbraAfhWorld[1];
    penumbraAfhVertex2 = penumbraAfhWorld[2];
    penumbraAfhBox = box;
    EmitVertex();
}

#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) penumbraAfhEmitVertex(position, box)
#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
    if ((penumbraAfhParams.grid.w & PENUMBRA_AFH_FLAG_CLOSED) != 0u) {
        // §3.3: of a closed caster only the light-back-facing triangles cast. Decided in double:
        // a triangle wrongly culled here would be a missing blocker. Edge-on triangles (facing
        // exactly 0) block nothing: the oracle's coplanar rule ignores them.
        dvec3 a = dvec3(penumbraAfhWorld[0]), b = dvec3(penumbraAfhWorld[1]), c = dvec3(penumbraAfhWorld[2]);
        dvec3 to_light = penumbraAfhParams.light.w != 0.0 ? dvec3(penumbraAfhParams.light.xyz) - a
                                                           : dvec3(penumbraAfhParams.light.xyz);
        precise double facing = dot(cross(b - a, c - a), to_light);
        if (facing >= 0.0) return;
    }
    int emitted = penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position,
                                           penumbraConservativeParams);
#if PENUMBRA_AFH_COUNT_WORK
    if (emitted > 0) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TRIANGLES], 1u);
#endif
}
