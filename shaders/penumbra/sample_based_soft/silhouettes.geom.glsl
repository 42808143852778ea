// penumbra — sample-based soft shadows, silhouette pass, geometry stage (SoftSkips::silhouettes;
// laine2005 §3.3, sintorn2008 §4.3: penumbrae come only from edges that are silhouettes from some
// point of the light). Input: the casters as GL_TRIANGLES_ADJACENCY (penumbra::triangleAdjacency:
// a, n_ab, b, n_bc, c, n_ca). Per edge xy with apex z (this triangle's third vertex) and the
// neighbour's apex n: the sheet (x, y, z) + (y, x, n) is consistently oriented whatever the mesh's
// own winding, and from a light point l the edge is a silhouette exactly when l lies in front of
// one face and behind the other. So the edge is a potential silhouette unless the whole light lies
// strictly in front of both faces or strictly behind both (penumbraSbsCasterPlane's clearance,
// rounding included); a degenerate neighbour (open or non-manifold edge: n = x) always is one.
// Each potential silhouette emits its influence region (the block-4 snippet on the triangle
// (x, y, y): the contract holds for any convex blocker, here the segment), so every view sample a
// segment to some light point through that edge could start from lands in a marked texel
// (silhouettes.frag.glsl). An edge is emitted by one of its two triangles (the one whose apex is
// lexicographically smaller; both when the apexes coincide or the edge is open).
// With PENUMBRA_SBS_NEAR_PASS = 1 the same input emits each triangle's own (uncut) influence
// region instead, its vertices flat to silhouettes.frag.glsl, which marks the texels holding a
// view sample for which the oracle's coplanar rule opens T's edges (penumbraSbsCoplanarOpen).
// Defines: the influence setup's, with PENUMBRA_INFLUENCE_CUT forced to 0 (the cut is a triangle's);
// PENUMBRA_SBS_NEAR_PASS.
// penumbra-permutation: PENUMBRA_SBS_NEAR_PASS=0
// penumbra-permutation: PENUMBRA_SBS_NEAR_PASS=1
#include "penumbra/influence_region/influence_region_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"
#include "penumbra/sample_based_soft/caster_plane.glsl"

#ifndef PENUMBRA_INFLUENCE_SIDES
#define PENUMBRA_INFLUENCE_SIDES PENUMBRA_INFLUENCE_DEFAULT_SIDES
#endif
#ifndef PENUMBRA_SBS_NEAR_PASS
#define PENUMBRA_SBS_NEAR_PASS 0
#endif

layout(triangles_adjacency) in;
#if PENUMBRA_SBS_NEAR_PASS
layout(triangle_strip, max_vertices = PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)) out;
layout(location = 0) flat out vec3 penumbraSbsNearVertex0;
layout(location = 1) flat out vec3 penumbraSbsNearVertex1;
layout(location = 2) flat out vec3 penumbraSbsNearVertex2;
#else
layout(triangle_strip, max_vertices = 3 * PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)) out;
#endif

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std140, binding = PENUMBRA_SBS_INFLUENCE_BINDING) uniform PenumbraSbsInfluenceBlock {
    PenumbraInfluenceParams penumbraSbsInfluence;
};

#include "penumbra/influence_region/influence_region.glsl"

bool penumbraSbsLess(vec3 a, vec3 b) { return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z))); }

void penumbraSbsEdge(vec3 x, vec3 y, vec3 z, vec3 n) {
    const bool open = n == x || n == y;
    if (!open && penumbraSbsLess(n, z)) return;  // the neighbour emits it
    if (!open) {
        const dvec3 centre = penumbraSbsParams.center.xyz;
        const double reach = penumbraSbsParams.bounds.x;
        const PenumbraSbsCasterPlane f = penumbraSbsCasterPlane(dvec3(x), dvec3(y), dvec3(z), centre, reach);
        const PenumbraSbsCasterPlane g = penumbraSbsCasterPlane(dvec3(y), dvec3(x), dvec3(n), centre, reach);
        if (f.light_clearance > 0.0LF && g.light_clearance > 0.0LF && (f.light_side > 0.0LF) == (g.light_side > 0.0LF))
            return;  // the whole light on one side of both faces: never a silhouette
    }
    // Clip the edge to where a blocker can matter (instead of the block's whole-grid fallbacks for
    // points beyond F or far outside the grid). A receiver p lies in the grid's frustum (between the
    // light's eye plane and F) and a blocking point x on the segment from a light point y to p, so x
    // lies in the convex hull of the light and that frustum: inside each side plane of the frustum
    // (through the light centre) moved out by the light's radius, and in front of F. In the light's
    // normalised space (the light is the unit ball; R below inflates it for float error):
    //   - side planes: the grid's pixel rows of penumbraSbsInfluence.to_pixel, x >= 0, x <= W w,
    //     y >= 0, y <= H w, each moved out by R |normal|; the kept part is widened by 2^-12 of the
    //     edge's length at each clipped end (conservative);
    //   - F: the part beyond F cannot be met by a segment from a receiver in front of F to the light
    //     (every point of such a segment lies on the light's side of the receiver); the kept part
    //     ends short of F by 2^-12 of the front endpoint's distance, so the skip needs receivers that
    //     much in front of F (SoftSkips::silhouettes' requirement).
    const PenumbraInfluenceParams P = penumbraSbsInfluence;
    const vec3 qx = vec3(penumbraInfluenceDot3(P.to_local[0].xyz, x - P.center.xyz),
                         penumbraInfluenceDot3(P.to_local[1].xyz, x - P.center.xyz),
                         penumbraInfluenceDot3(P.to_local[2].xyz, x - P.center.xyz));
    const vec3 qy = vec3(penumbraInfluenceDot3(P.to_local[0].xyz, y - P.center.xyz),
                         penumbraInfluenceDot3(P.to_local[1].xyz, y - P.center.xyz),
                         penumbraInfluenceDot3(P.to_local[2].xyz, y - P.center.xyz));
    float t0 = 0.0, t1 = 1.0;  // the kept part x + t (y - x), t in [t0, t1]
    const float radius = 1.0625 + max(length(qx), length(qy)) / 4096.0;
    const vec4 rows[4] = vec4[4](P.to_pixel[0], P.grid.x * P.to_pixel[2] - P.to_pixel[0], P.to_pixel[1],
                                 P.grid.y * P.to_pixel[2] - P.to_pixel[1]);
    for (int i = 0; i < 4; ++i) {
        const float shift = radius * length(rows[i].xyz);
        const float dx = dot(rows[i].xyz, qx) + rows[i].w + shift, dy = dot(rows[i].xyz, qy) + rows[i].w + shift;
        if (dx < 0.0 && dy < 0.0) return;  // wholly outside: no receiver's segment meets it
        if (dx < 0.0) t0 = max(t0, max(0.0, dx / (dx - dy) - 1.0 / 4096.0));
        if (dy < 0.0) t1 = min(t1, min(1.0, dx / (dx - dy) + 1.0 / 4096.0));
    }
    precise float sx = penumbraInfluenceDot3(P.far_plane.xyz, qx) + P.far_plane.w;
    precise float sy = penumbraInfluenceDot3(P.far_plane.xyz, qy) + P.far_plane.w;
    if (!(sx < 0.0) && !(sy < 0.0)) return;  // wholly beyond F
    // The kept end lies at s = 2^-12 s_front (s_front < 0: the front endpoint's), in front of F.
    if (!(sx < 0.0)) t0 = max(t0, (sx - sy / 4096.0) / (sx - sy));        // y in front
    if (!(sy < 0.0)) t1 = min(t1, sx * (1.0 - 1.0 / 4096.0) / (sx - sy));  // x in front
    if (!(t0 <= t1)) return;
    const vec3 a = t0 > 0.0 ? x + t0 * (y - x) : x, b = t1 < 1.0 ? x + t1 * (y - x) : y;
    const int count = penumbraInfluenceRegion(a, b, b, penumbraSbsInfluence);
    const vec2 half_grid = 0.5 * penumbraSbsInfluence.grid.xy;
    for (int j = 0; j < count; ++j) {
        const int index = (j & 1) != 0 ? (j + 1) >> 1 : (count - (j >> 1)) % count;
        gl_Position = vec4(penumbraInfluenceOut[index] / half_grid - 1.0, 0.0, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}

void main() {
    const vec3 v[6] = vec3[6](gl_in[0].gl_Position.xyz, gl_in[1].gl_Position.xyz, gl_in[2].gl_Position.xyz,
                              gl_in[3].gl_Position.xyz, gl_in[4].gl_Position.xyz, gl_in[5].gl_Position.xyz);
#if PENUMBRA_SBS_NEAR_PASS
    // The triangle's region holds every view sample a segment to the light meets it from: the
    // only ones for which ignoring it can matter.
    const int count = penumbraInfluenceRegion(v[0], v[2], v[4], penumbraSbsInfluence);
    const vec2 half_grid = 0.5 * penumbraSbsInfluence.grid.xy;
    for (int j = 0; j < count; ++j) {
        const int index = (j & 1) != 0 ? (j + 1) >> 1 : (count - (j >> 1)) % count;
        gl_Position = vec4(penumbraInfluenceOut[index] / half_grid - 1.0, 0.0, 1.0);
        penumbraSbsNearVertex0 = v[0];
        penumbraSbsNearVertex1 = v[2];
        penumbraSbsNearVertex2 = v[4];
        EmitVertex();
    }
    EndPrimitive();
#else
    penumbraSbsEdge(v[0], v[2], v[4], v[1]);
    penumbraSbsEdge(v[2], v[4], v[0], v[3]);
    penumbraSbsEdge(v[4], v[0], v[2], v[5]);
#endif
}
