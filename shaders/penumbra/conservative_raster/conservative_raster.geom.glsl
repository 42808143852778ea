#version 450
// penumbra — geometry stage emitting each triangle's conservative coverage (sintorn2008 §3.2),
// a ready entry for tests and a template for integrators. Three programs from one file:
//   * single pass (default): every triangle, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES (13);
//     the Exact variant always runs this way (its unclipped hull has up to 7 vertices);
//   * PENUMBRA_CONSERVATIVE_DIRECT=1 — the Fixed-6 direct pass, max_vertices = 6: unclipped
//     triangles are emitted, triangles that need clipping are appended to the spill buffer at
//     binding PENUMBRA_CONSERVATIVE_SPILL_BINDING (payload x = triangle id);
//   * PENUMBRA_CONSERVATIVE_SPILL_DRAW=1 — the spill pass, max_vertices = 13, drawn with
//     glDrawArraysIndirect from the spill header (no vertex attributes): primitive i emits spilled
//     triangle i, whose id comes from its payload.
//
// Inputs: triangles in clip space (gl_in[i].gl_Position). Uniform block at binding
// PENUMBRA_CONSERVATIVE_PARAMS_BINDING holds the PenumbraConservativeParams from
// penumbra::conservativeRasterSetup (std140). Uniform location 8 = id of the draw's first triangle.
// Outputs per vertex: gl_Position, flat location 0 = the window-space box for the fragment clip,
// flat location 1 = triangle id (first + gl_PrimitiveIDIn).
// PENUMBRA_CONSERVATIVE_RECORD=1 also stores the clip coordinates this stage received (3 vec4 per
// triangle at binding PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING): tests compare coverage against
// exactly the triangle the emitter saw, whatever the vertex stage did to the precision (the spill
// pass records nothing: the direct pass recorded every triangle).
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=1 PENUMBRA_CONSERVATIVE_RECORD=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DIRECT=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DIRECT=1 PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DIRECT=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1 PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_SPILL_DRAW=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_SPILL_DRAW=1 PENUMBRA_CONSERVATIVE_DROP_DEGENERATE=1
#include "penumbra/conservative_raster/conservative_raster_shared.h"

#ifndef PENUMBRA_CONSERVATIVE_RECORD
#define PENUMBRA_CONSERVATIVE_RECORD 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_DIRECT
#define PENUMBRA_CONSERVATIVE_DIRECT 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_SPILL_DRAW
#define PENUMBRA_CONSERVATIVE_SPILL_DRAW 0
#endif
#if PENUMBRA_CONSERVATIVE_DIRECT && PENUMBRA_CONSERVATIVE_SPILL_DRAW
#error PENUMBRA_CONSERVATIVE_DIRECT and PENUMBRA_CONSERVATIVE_SPILL_DRAW are the two passes of one plan: pick one
#endif

layout(triangles) in;
#if PENUMBRA_CONSERVATIVE_DIRECT
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_FIXED6_MAX_VERTICES) out;
#else
layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;
#endif

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};
layout(location = 8) uniform uint penumbraConservativeFirstTriangle;

layout(location = 0) flat out vec4 penumbraConservativeBox;
layout(location = 1) flat out uint penumbraConservativeTriangle;

#if PENUMBRA_CONSERVATIVE_RECORD && !PENUMBRA_CONSERVATIVE_SPILL_DRAW
layout(std430, binding = PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING) writeonly buffer PenumbraConservativeRecordClip {
    vec4 penumbraConservativeRecordClip[];
};
#endif

#if PENUMBRA_CONSERVATIVE_DIRECT || PENUMBRA_CONSERVATIVE_SPILL_DRAW
layout(std430, binding = PENUMBRA_CONSERVATIVE_SPILL_BINDING) buffer PenumbraConservativeSpillBlock {
    PenumbraConservativeSpillHeader penumbraConservativeSpillHeader;
    PenumbraConservativeSpillTriangle penumbraConservativeSpillTriangles[];
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
#if PENUMBRA_CONSERVATIVE_DIRECT
#define PENUMBRA_CONSERVATIVE_SPILL_HEADER penumbraConservativeSpillHeader
#define PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES penumbraConservativeSpillTriangles
#include "penumbra/conservative_raster/conservative_raster_spill.glsl"
#define PENUMBRA_CONSERVATIVE_SPILL(clip0, clip1, clip2) \
    penumbraConservativeSpillAppend(clip0, clip1, clip2, uvec4(penumbraConservativeEntryTriangle, 0u, 0u, 0u))
#endif
#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
#if PENUMBRA_CONSERVATIVE_SPILL_DRAW
    uint index = uint(gl_PrimitiveIDIn);
    if (index >= penumbraConservativeSpillHeader.capacity) return;  // never: count <= 3 * capacity
    penumbraConservativeEntryTriangle = penumbraConservativeSpillTriangles[index].payload.x;
    penumbraConservativeEmit(penumbraConservativeSpillTriangles[index].clip0, penumbraConservativeSpillTriangles[index].clip1,
                             penumbraConservativeSpillTriangles[index].clip2, penumbraConservativeParams);
#else
    penumbraConservativeEntryTriangle = penumbraConservativeFirstTriangle + uint(gl_PrimitiveIDIn);
#if PENUMBRA_CONSERVATIVE_RECORD
    for (int i = 0; i < 3; ++i) {
        penumbraConservativeRecordClip[3u * penumbraConservativeEntryTriangle + uint(i)] = gl_in[i].gl_Position;
    }
#endif
    penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position,
                             penumbraConservativeParams);
#endif
}
