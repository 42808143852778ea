// penumbra — alias-free hard shadows, light pass, geometry stage (sintorn2008 §3.2, §3.3).
// Culls per the caster class (closed meshes: only light-back-facing triangles cast, §3.3, which
// removes self-shadowing without any bias), then emits the triangle's conservative coverage of
// the light grid (penumbra/conservative_raster) with the world-space vertices as flat outputs: the
// fragment stage tests each listed view sample against the triangle itself.
// Three programs from one file (the defines come from penumbra::afhConservativeSetup):
//   * single pass (default): every triangle, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES (13);
//     ConservativeVariant::Exact always (its unclipped hull has up to 7 vertices), Fixed6 with
//     AliasFreeHardOptions::fixed6_two_pass = false;
//   * PENUMBRA_CONSERVATIVE_DIRECT=1 — the Fixed-6 direct pass at the seed's max_vertices = 6: culls,
//     emits every unclipped triangle, and hands each triangle that needs clipping (it crosses the
//     light's eye plane w = min_w or the guard band) to the spill buffers: its clip coordinates to
//     the conservative spill array (PENUMBRA_AFH_SPILL_BINDING; payload x = spill-world entry,
//     y = the draw's flags), its world-space vertices to the spill-world array
//     (PENUMBRA_AFH_SPILL_WORLD_BINDING, alias_free_hard_shared.h);
//   * PENUMBRA_CONSERVATIVE_SPILL_DRAW=1 — the spill pass, max_vertices = 13, drawn with one
//     glDrawArraysIndirect from the spill header (no vertex attributes): primitive i clips and emits
//     spilled triangle i with the world vertices of its spill-world entry — the same clip and world
//     bits the direct pass received, hence the same hull and fragments as the single pass.
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_EXACT=0
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_EXACT=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=0 PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_AFH_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DIRECT=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=0 PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_DIRECT=1 PENUMBRA_AFH_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_SPILL_DRAW=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=0 PENUMBRA_CONSERVATIVE_EXACT=0 PENUMBRA_CONSERVATIVE_SPILL_DRAW=1 PENUMBRA_AFH_COUNT_WORK=1
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"
#include "penumbra/alias_free_hard/cull.glsl"

#ifndef PENUMBRA_AFH_EXACT
#define PENUMBRA_AFH_EXACT 1
#endif
#ifndef PENUMBRA_AFH_COUNT_WORK
#define PENUMBRA_AFH_COUNT_WORK 0
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
layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};
#if PENUMBRA_AFH_COUNT_WORK
layout(std430, binding = PENUMBRA_AFH_WORK_BINDING) buffer PenumbraAfhWork { uint penumbraAfhWork[]; };
#endif

#if PENUMBRA_CONSERVATIVE_DIRECT || PENUMBRA_CONSERVATIVE_SPILL_DRAW
layout(std430, binding = PENUMBRA_AFH_SPILL_BINDING) buffer PenumbraAfhSpillBlock {
    PenumbraConservativeSpillHeader penumbraAfhSpillHeader;
    PenumbraConservativeSpillTriangle penumbraAfhSpillTriangles[];
};
layout(std430, binding = PENUMBRA_AFH_SPILL_WORLD_BINDING) buffer PenumbraAfhSpillWorldBlock {
    PenumbraAfhSpillWorldHeader penumbraAfhSpillWorldHeader;
    PenumbraAfhSpillWorld penumbraAfhSpillWorld[];
};
#endif

#if !PENUMBRA_CONSERVATIVE_SPILL_DRAW
layout(location = 0) in vec3 penumbraAfhWorld[];
#endif
layout(location = 0) flat out vec3 penumbraAfhVertex0;
layout(location = 1) flat out vec3 penumbraAfhVertex1;
layout(location = 2) flat out vec3 penumbraAfhVertex2;
layout(location = 3) flat out vec4 penumbraAfhBox;

// The current triangle's world-space vertices (from the vertex stage, or from the spill-world entry).
vec3 penumbraAfhTriangle[3];

void penumbraAfhEmitVertex(vec4 position, vec4 box) {
    gl_Position = position;
    penumbraAfhVertex0 = penumbraAfhTriangle[0];
    penumbraAfhVertex1 = penumbraAfhTriangle[1];
    penumbraAfhVertex2 = penumbraAfhTriangle[2];
    penumbraAfhBox = box;
    EmitVertex();
}

#define PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) penumbraAfhEmitVertex(position, box)

#if PENUMBRA_CONSERVATIVE_DIRECT
#define PENUMBRA_CONSERVATIVE_SPILL_HEADER penumbraAfhSpillHeader
#define PENUMBRA_CONSERVATIVE_SPILL_TRIANGLES penumbraAfhSpillTriangles
#include "penumbra/conservative_raster/conservative_raster_spill.glsl"

// The spill hook: a spill-world entry first, then the append. Only triangles that got an entry are
// appended, so both arrays hold the same triangles and the append itself never finds the array full;
// a triangle that finds no entry is lost and counted where the plan counts losses (header.overflow).
void penumbraAfhSpill(vec4 clip0, vec4 clip1, vec4 clip2) {
    uint entry = atomicAdd(penumbraAfhSpillWorldHeader.count, 1u);
    if (entry >= penumbraAfhSpillHeader.capacity) {
        atomicAdd(penumbraAfhSpillHeader.overflow, 1u);
        return;
    }
    penumbraAfhSpillWorld[entry].v0 = vec4(penumbraAfhTriangle[0], 0.0);
    penumbraAfhSpillWorld[entry].v1 = vec4(penumbraAfhTriangle[1], 0.0);
    penumbraAfhSpillWorld[entry].v2 = vec4(penumbraAfhTriangle[2], 0.0);
    penumbraConservativeSpillAppend(clip0, clip1, clip2, uvec4(entry, penumbraAfhParams.grid.w, 0u, 0u));
}
#define PENUMBRA_CONSERVATIVE_SPILL(clip0, clip1, clip2) penumbraAfhSpill(clip0, clip1, clip2)
#endif

#include "penumbra/conservative_raster/conservative_raster.glsl"

void main() {
#if PENUMBRA_CONSERVATIVE_SPILL_DRAW
    // Culling happened in the direct pass, before the triangle was spilled.
    uint index = uint(gl_PrimitiveIDIn);
    if (index >= penumbraAfhSpillHeader.capacity) return;  // never: count <= 3 * capacity
    uint entry = penumbraAfhSpillTriangles[index].payload.x;
    if (entry >= penumbraAfhSpillHeader.capacity) return;  // never: only entries taken are appended
    penumbraAfhTriangle[0] = penumbraAfhSpillWorld[entry].v0.xyz;
    penumbraAfhTriangle[1] = penumbraAfhSpillWorld[entry].v1.xyz;
    penumbraAfhTriangle[2] = penumbraAfhSpillWorld[entry].v2.xyz;
    int emitted = penumbraConservativeEmit(penumbraAfhSpillTriangles[index].clip0, penumbraAfhSpillTriangles[index].clip1,
                                           penumbraAfhSpillTriangles[index].clip2, penumbraConservativeParams);
#else
    penumbraAfhTriangle[0] = penumbraAfhWorld[0];
    penumbraAfhTriangle[1] = penumbraAfhWorld[1];
    penumbraAfhTriangle[2] = penumbraAfhWorld[2];
    // The culls (cull.glsl): degenerate triangles, and a closed caster's per `flags`; once per
    // triangle here, before any spill, rather than per fragment.
    const int cull = penumbraAfhCull(penumbraAfhWorld[0], penumbraAfhWorld[1], penumbraAfhWorld[2], penumbraAfhParams.light,
                                     penumbraAfhParams.grid.w);
    if (cull != PENUMBRA_AFH_CULL_NONE) {
#if PENUMBRA_AFH_COUNT_WORK
        if (cull == PENUMBRA_AFH_CULL_CLOSED && penumbraAfhParams.pass.x == 0u)
            atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TRIANGLES_CULLED], 1u);
#endif
        return;
    }
    // Direct pass: a triangle that needs clipping goes to penumbraAfhSpill and returns 0 here.
    int emitted = penumbraConservativeEmit(gl_in[0].gl_Position, gl_in[1].gl_Position, gl_in[2].gl_Position,
                                           penumbraConservativeParams);
#endif
#if PENUMBRA_AFH_COUNT_WORK
    if (emitted > 0) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TRIANGLES], 1u);
#endif
}
