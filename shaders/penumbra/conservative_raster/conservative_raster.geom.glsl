#version 450
// penumbra — geometry stage emitting each triangle's conservative coverage (sintorn2008 §3.2),
// a ready entry for tests and a template for integrators.
//
// Inputs: triangles in clip space (gl_in[i].gl_Position). Uniform block at binding
// PENUMBRA_CONSERVATIVE_PARAMS_BINDING holds the PenumbraConservativeParams from
// penumbra::conservativeRasterSetup (std140). Uniform location 8 = id of the draw's first triangle.
// Outputs per vertex: gl_Position, flat location 0 = the window-space box for the fragment clip,
// flat location 1 = triangle id (first + gl_PrimitiveIDIn).
// PENUMBRA_CONSERVATIVE_RECORD=1 also stores the clip coordinates this stage received (3 vec4 per
// triangle at binding PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING): tests compare coverage against
// exactly the triangle the emitter saw, whatever the vertex stage did to the precision.
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_RECORD=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
#include "penumbra/conservative_raster/conservative_raster_shared.h"

#ifndef PENUMBRA_CONSERVATIVE_RECORD
#define PENUMBRA_CONSERVATIVE_RECORD 0
#endif

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};
layout(location = 8) uniform uint penumbraConservativeFirstTriangle;

layout(location = 0) flat out vec4 penumbraConservativeBox;
layout(location = 1) flat out uint penumbraConservativeTriangle;

#if PENUMBRA_CONSERVATIVE_RECORD
layout(std430, binding = PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING) writeonly buffer PenumbraConservativeRecordClip {
    vec4 penumbraConservativeRecordClip[];
};
#endif

uint penumbraConservativeEntryTriangle = 0u;

void penumbraConservativeEntryEmit(vec4 position, vec4 box) {
    gl_Position = position;
    penumbraConservativeBox = box;
    penumbraConservativeTriangle = penumbraConservativeEntryTriangle;
    EmitVertex();
}

#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) penumbraConservativeEntryEmit(position, box)
#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
    penumbraConservativeEntryTriangle = penumbraConservativeFirstTriangle + uint(gl_PrimitiveIDIn);
#if PENUMBRA_CONSERVATIVE_RECORD
    for (int i = 0; i < 3; ++i) {
        penumbraConservativeRecordClip[3u * penumbraConservativeEntryTriangle + uint(i)] = gl_in[i].gl_Position;
    }
#endif
    penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position,
                             penumbraConservativeParams);
}
