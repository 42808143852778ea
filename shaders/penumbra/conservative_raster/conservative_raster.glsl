// penumbra — conservative rasterization in the geometry shader (sintorn2008 §3.2, Fig. 4; the
// exact variant after Hasselgren, Akenine-Möller & Ohlsson, GPU Gems 2 ch. 42 [HAMO05]).
//
// Integration summary
//   needs:    a geometry shader with `layout(triangles) in;` and
//             `layout(triangle_strip, max_vertices = PENUMBRA_CONSERVATIVE_MAX_VERTICES) out;`
//             (PENUMBRA_CONSERVATIVE_FIXED6_MAX_VERTICES with PENUMBRA_CONSERVATIVE_DIRECT=1),
//             and a PenumbraConservativeParams value for the viewport being rendered (fill it with
//             penumbra::conservativeRasterSetup on the host; upload it however you like).
//   hook:     PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box) — called once per output vertex in
//             triangle-strip order: write gl_Position = position (clip space, w = 1), your own
//             outputs (flat ones: the hull vertices lie outside the triangle, so interpolated
//             attributes are meaningless) and the vec4 `box` (window-space xmin, ymin, xmax, ymax)
//             if the fragment stage clips with penumbraConservativeInsideBox, then EmitVertex().
//             The snippet calls EndPrimitive() itself. position.z is the triangle's NDC depth plane
//             at that hull vertex clamped to params.depth.xy (nearest vertex depth for thin ones), so
//             inside the triangle the interpolated depth is the triangle's own. The strip is always
//             counter-clockwise in window space: cull back faces yourself before calling.
//   call:     int penumbraConservativeEmit(vec4 clip0, vec4 clip1, vec4 clip2, params) — returns the
//             number of vertices emitted (0: dropped, culled, or spilled in the direct pass); at most
//             PENUMBRA_CONSERVATIVE_MAX_VERTICES (13), or 6 with PENUMBRA_CONSERVATIVE_DIRECT=1.
//   defines:  PENUMBRA_CONSERVATIVE_EXACT 0 = the seed's fixed 6 vertices / 4 triangles per triangle
//             (a case-(iii) corner over-covers by at most one pixel), 1 = the exact hull (<= 7);
//             PENUMBRA_CONSERVATIVE_DROP_DEGENERATE 1 = drop triangles thinner than the threshold
//             (zero-area ones included) instead of covering the pixels their points/edges touch;
//             PENUMBRA_CONSERVATIVE_DIRECT 1 = the Fixed-6 direct pass: the geometry shader may
//             declare max_vertices = PENUMBRA_CONSERVATIVE_FIXED6_MAX_VERTICES (6). A triangle for
//             which penumbraConservativeNeedsSpill() is true (it needs clipping: near plane,
//             w >= min_w or guard band) emits nothing here and goes to the hook
//             PENUMBRA_CONSERVATIVE_SPILL(clip0, clip1, clip2) instead — append it to a spill buffer
//             (conservative_raster_spill.glsl does that) and draw that buffer with a
//             PENUMBRA_CONSERVATIVE_DIRECT 0 geometry shader (max_vertices 13) in a second pass.
//             Both passes together emit exactly what the single pass emits. Needs EXACT 0.
//             PENUMBRA_CONSERVATIVE_BOX_ONLY 1 = any stage (compute included): no hook, nothing
//             emitted; penumbraConservativeEmit returns 1 and leaves the pixel-expanded box it
//             would hand to the hook in penumbraConservativeBoxOut, or returns 0 where the
//             triangle is dropped (the same bits as the emitting build: steps 1 to 5 below);
//             for an unclipped, not thin triangle also the triangle and the dilation
//             (penumbraConservativeBoxTriangle).
//   predicate: bool penumbraConservativeNeedsSpill(vec4 clip0, vec4 clip1, vec4 clip2, params):
//             finite, not entirely outside one clipping plane, and not every vertex inside all of
//             them (the 6-vertex hull covers only unclipped triangles). CPU twin:
//             penumbra::conservativeNeedsSpill().
//
// Coverage contract (checked against an exact predicate in tests/conservative_raster_test.cpp):
// let T be the triangle clipped to the near plane (dot(near_plane, clip) >= 0) and to w >= min_w,
// projected to viewport pixels. Every pixel of the viewport whose CLOSED square [i, i+1] x [j, j+1]
// intersects T gets at least one fragment — a pixel T touches only on its boundary counts, and so
// does every pixel a zero-area T (segment or point) touches. The far plane is not clipped. NaN or
// Inf in any input coordinate drops the triangle (no fragments).
//
// How (all hull arithmetic in viewport-relative pixels, |coordinate| <= max(W, H) + G):
//  * unclipped triangles (all vertices inside the near plane and the guard band G) are projected
//    in float; others are clipped in double precision in homogeneous clip space against the near
//    plane, w >= min_w and the guard band, so far-away or near-plane vertices never reach the
//    pixel-space arithmetic (their 1e5..1e9-pixel coordinates would swamp float precision);
//  * the polygon is dilated by the square [-h, h]^2, h = 0.5 + margin (margin = GL subpixel snap +
//    float error bound). A convex polygon dilated by a square is its edges translated by the square
//    corner that supports them, joined at each vertex by 1, 2 or 3 corners of the vertex's square
//    (Fig. 4c cases i, ii, iii). The corner an edge needs depends only on the SIGNS of its direction
//    vector, which float subtraction gets exactly right, so orientation/sliver noise never picks a
//    wrong corner;
//  * fixed variant (seed): two vertices per corner — the corners supporting the incoming and the
//    outgoing edge. In case iii those two are diagonal corners and the segment between them would
//    cut off the middle corner, so both are pushed along their edges by 2h (one pixel): the tangent
//    to the middle corner is reached after at most 2h because the edge normal is at least 45°
//    from the corner's diagonal; this is the seed's "edges are extended by the width of a pixel";
//  * exact variant and every clipped polygon: the dilated polygon itself, built from the four
//    extreme vertices (bottom, right, top, left): the boundary chain between two consecutive
//    extremes is translated by one square corner. That needs no turn signs, so the slightly
//    non-convex polygons rounding can leave after clipping are still handled;
//  * triangles whose height (2 area / diameter) is below tau = tau0 + tau_rel * diameter — slivers,
//    collinear and coincident points — are replaced by the segment between their two farthest
//    points dilated by h + thickness (a hexagon; a square for a point): the sliver lies within
//    that distance of the segment, and no edge direction has to be normalised.
#ifndef PENUMBRA_CONSERVATIVE_RASTER_GLSL
#define PENUMBRA_CONSERVATIVE_RASTER_GLSL

#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/conservative_raster/conservative_raster_polygon.glsl"

#ifndef PENUMBRA_CONSERVATIVE_BOX_ONLY
#define PENUMBRA_CONSERVATIVE_BOX_ONLY 0
#endif
#if !PENUMBRA_CONSERVATIVE_BOX_ONLY && !defined(PENUMBRA_CONSERVATIVE_EMIT_VERTEX)
#error penumbra/conservative_raster/conservative_raster.glsl needs the hook PENUMBRA_CONSERVATIVE_EMIT_VERTEX(position, box)
#endif
#if PENUMBRA_CONSERVATIVE_BOX_ONLY && PENUMBRA_CONSERVATIVE_DIRECT
#error PENUMBRA_CONSERVATIVE_BOX_ONLY=1 clips every triangle itself: it is not the Fixed-6 direct pass
#endif
#ifndef PENUMBRA_CONSERVATIVE_EXACT
#define PENUMBRA_CONSERVATIVE_EXACT 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_DROP_DEGENERATE
#define PENUMBRA_CONSERVATIVE_DROP_DEGENERATE 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_DIRECT
#define PENUMBRA_CONSERVATIVE_DIRECT 0
#endif
#if PENUMBRA_CONSERVATIVE_DIRECT && PENUMBRA_CONSERVATIVE_EXACT
#error PENUMBRA_CONSERVATIVE_DIRECT=1 is the Fixed-6 pass; the exact hull of a triangle needs 7 vertices (use the single pass)
#endif
#if PENUMBRA_CONSERVATIVE_DIRECT && !defined(PENUMBRA_CONSERVATIVE_SPILL)
#error penumbra/conservative_raster/conservative_raster.glsl with PENUMBRA_CONSERVATIVE_DIRECT=1 needs the hook PENUMBRA_CONSERVATIVE_SPILL(clip0, clip1, clip2)
#endif

// The polygon being dilated (viewport-relative pixels, NDC depth) and the hull being emitted.
vec2 penumbraConservativePolygon[PENUMBRA_CONSERVATIVE_MAX_POLYGON];
float penumbraConservativeDepth[PENUMBRA_CONSERVATIVE_MAX_POLYGON];
vec2 penumbraConservativeHull[PENUMBRA_CONSERVATIVE_MAX_VERTICES];
#if PENUMBRA_CONSERVATIVE_BOX_ONLY
vec4 penumbraConservativeBoxOut;  // the last penumbraConservativeEmit's box (when it returned 1)
// ... and when true, its unclipped triangle, counter-clockwise in viewport-relative pixels, in
// penumbraConservativePolygon[0 .. 2], which the hull dilates by penumbraConservativeBoxDilation
// (penumbraConservativeInsideDilatedTriangle); false: clipped or thin, the box alone.
bool penumbraConservativeBoxTriangle;
float penumbraConservativeBoxDilation;
#endif

// dot(near_plane, c) in float, left to right, no FMA (the twin computes the same bits).
float penumbraConservativeNearDistance(vec4 plane, vec4 c) {
    precise float d = ((plane.x * c.x + plane.y * c.y) + plane.z * c.z) + plane.w * c.w;
    return d;
}

// The unclipped fast path's test: the vertex lies inside the near plane, w >= min_w and the guard
// band (float; the guard products are single roundings, so FMA cannot change them).
bool penumbraConservativeVertexInside(vec4 c, PenumbraConservativeParams params) {
    return penumbraConservativeNearDistance(params.near_plane, c) >= 0.0 && c.w >= params.clipping.w &&
           abs(c.x) <= params.clipping.y * c.w && abs(c.y) <= params.clipping.z * c.w;
}

// Signed distance-like value of clip-space point c to clipping plane i (kept where >= 0):
// 0 near plane, 1 w >= min_w, 2..5 guard band x >= -gx w, x <= gx w, y >= -gy w, y <= gy w.
// precise, left to right: the twin computes the same bits.
double penumbraConservativePlane(int i, dvec4 c, PenumbraConservativeParams params) {
    if (i == 0) {
        dvec4 n = dvec4(params.near_plane);
        precise double d = ((n.x * c.x + n.y * c.y) + n.z * c.z) + n.w * c.w;
        return d;
    }
    if (i == 1) return c.w - double(params.clipping.w);
    double g = double(i < 4 ? params.clipping.y : params.clipping.z);
    double coordinate = i < 4 ? c.x : c.y;
    precise double d = ((i & 1) == 0 ? coordinate : -coordinate) + g * c.w;
    return d;
}

// True when all three vertices lie strictly outside one clipping plane (evaluated in double as the
// clipper does): nothing of the triangle can reach the viewport, so it is culled without clipping
// (and never spilled).
bool penumbraConservativeOutsideOnePlane(vec4 c0, vec4 c1, vec4 c2, PenumbraConservativeParams params) {
    dvec4 a = dvec4(c0), b = dvec4(c1), c = dvec4(c2);
    for (int plane = 0; plane < 6; ++plane) {
        if (penumbraConservativePlane(plane, a, params) < 0.0 && penumbraConservativePlane(plane, b, params) < 0.0 &&
            penumbraConservativePlane(plane, c, params) < 0.0) {
            return true;
        }
    }
    return false;
}

// The spill predicate (see the summary): the triangles the Fixed-6 direct pass hands to the hook.
bool penumbraConservativeNeedsSpill(vec4 clip0, vec4 clip1, vec4 clip2, PenumbraConservativeParams params) {
    if (!(penumbraConservativeFinite(clip0) && penumbraConservativeFinite(clip1) && penumbraConservativeFinite(clip2))) {
        return false;
    }
    if (penumbraConservativeVertexInside(clip0, params) && penumbraConservativeVertexInside(clip1, params) &&
        penumbraConservativeVertexInside(clip2, params)) {
        return false;
    }
    return !penumbraConservativeOutsideOnePlane(clip0, clip1, clip2, params);
}

#if !PENUMBRA_CONSERVATIVE_DIRECT  // the direct pass never clips: it spills
// Sutherland-Hodgman in double precision, homogeneous clip space; every intersection is computed
// from the kept endpoint, so its error scales with the kept (small) coordinates. Writes the
// projected polygon to penumbraConservativePolygon/Depth and returns its size (0: nothing left).
int penumbraConservativeClip(vec4 c0, vec4 c1, vec4 c2, PenumbraConservativeParams params) {
    dvec4 poly[PENUMBRA_CONSERVATIVE_MAX_POLYGON];
    dvec4 next[PENUMBRA_CONSERVATIVE_MAX_POLYGON];
    poly[0] = dvec4(c0);
    poly[1] = dvec4(c1);
    poly[2] = dvec4(c2);
    int n = 3;
    for (int plane = 0; plane < 6 && n > 0; ++plane) {
        int m = 0;
        dvec4 prev = poly[n - 1];
        double d_prev = penumbraConservativePlane(plane, prev, params);
        for (int i = 0; i < n; ++i) {
            dvec4 cur = poly[i];
            double d_cur = penumbraConservativePlane(plane, cur, params);
            if (d_cur >= 0.0) {
                if (d_prev < 0.0) {
                    precise dvec4 x = cur + (d_cur / (d_cur - d_prev)) * (prev - cur);
                    next[m++] = x;
                }
                next[m++] = cur;
            } else if (d_prev >= 0.0) {
                precise dvec4 x = prev + (d_prev / (d_prev - d_cur)) * (cur - prev);
                next[m++] = x;
            }
            prev = cur;
            d_prev = d_cur;
        }
        n = m;
        for (int i = 0; i < n; ++i) poly[i] = next[i];
    }
    dvec2 half_size = dvec2(params.viewport.zw) * 0.5;
    for (int i = 0; i < n; ++i) {
        precise dvec2 q = poly[i].xy / poly[i].w * half_size + half_size;
        penumbraConservativePolygon[i] = vec2(q);
        penumbraConservativeDepth[i] = float(poly[i].z / poly[i].w);
    }
    return n;
}
#endif

// The exact dilation of the counter-clockwise polygon [0, n) by [-h, h]^2 into
// penumbraConservativeHull (counter-clockwise). Returns the vertex count, or -1 when the extreme
// vertices are not in counter-clockwise order (the caller then falls back to the box).
int penumbraConservativeChainHull(int n, float h) {
    int extreme[4] = int[4](0, 0, 0, 0);  // bottom, right, top, left; ties as in the edge rule
    for (int i = 1; i < n; ++i) {
        vec2 p = penumbraConservativePolygon[i];
        vec2 b = penumbraConservativePolygon[extreme[0]];
        vec2 r = penumbraConservativePolygon[extreme[1]];
        vec2 t = penumbraConservativePolygon[extreme[2]];
        vec2 l = penumbraConservativePolygon[extreme[3]];
        if (p.y < b.y || (p.y == b.y && p.x > b.x)) extreme[0] = i;
        if (p.x > r.x || (p.x == r.x && p.y > r.y)) extreme[1] = i;
        if (p.y > t.y || (p.y == t.y && p.x < t.x)) extreme[2] = i;
        if (p.x < l.x || (p.x == l.x && p.y < l.y)) extreme[3] = i;
    }
    int turns = 0;
    for (int k = 0; k < 4; ++k) turns += (extreme[(k + 1) & 3] - extreme[k] + n) % n;
    if (turns != n && turns != 0) return -1;
    int count = 0;
    for (int k = 0; k < 4; ++k) {
        int length = (extreme[(k + 1) & 3] - extreme[k] + n) % n + 1;
        vec2 corner = h * penumbraConservativeCorner(k);
        for (int j = 0; j < length; ++j) {
            penumbraConservativeHull[count++] = penumbraConservativePolygon[(extreme[k] + j) % n] + corner;
        }
    }
    return count;
}

// The seed's fixed six vertices for a counter-clockwise, non-thin triangle in polygon[0..2].
// Returns 6, or -1 if a corner turned by 270° (impossible for such a triangle; box fallback).
int penumbraConservativeFixedHull(float h) {
    for (int i = 0; i < 3; ++i) {
        vec2 p = penumbraConservativePolygon[i];
        vec2 d_in = p - penumbraConservativePolygon[(i + 2) % 3];
        vec2 d_out = penumbraConservativePolygon[(i + 1) % 3] - p;
        int k_in = penumbraConservativeEdgeCorner(d_in);
        int k_out = penumbraConservativeEdgeCorner(d_out);
        int steps = (k_out - k_in) & 3;
        if (steps == 3) return -1;
        precise vec2 a = p + h * penumbraConservativeCorner(k_in);
        precise vec2 b = p + h * penumbraConservativeCorner(k_out);
        if (steps == 2) {  // case iii: extend both edges by one pixel (2h) past the corner
            precise vec2 n_in = d_in / sqrt(d_in.x * d_in.x + d_in.y * d_in.y);
            precise vec2 n_out = d_out / sqrt(d_out.x * d_out.x + d_out.y * d_out.y);
            a += (2.0 * h) * n_in;
            b -= (2.0 * h) * n_out;
        }
        penumbraConservativeHull[2 * i] = a;
        penumbraConservativeHull[2 * i + 1] = b;
    }
    return 6;
}

int penumbraConservativeEmit(vec4 clip0, vec4 clip1, vec4 clip2, PenumbraConservativeParams params) {
    if (!(penumbraConservativeFinite(clip0) && penumbraConservativeFinite(clip1) &&
          penumbraConservativeFinite(clip2))) {
        return 0;  // contract: NaN/Inf drops the triangle
    }
    vec2 size = params.viewport.zw;
    vec2 half_size = 0.5 * size;
    float h = params.expansion.x;

    // 1. The polygon in viewport-relative pixels: fast path or clipped in double precision.
    vec4 c[3] = vec4[3](clip0, clip1, clip2);
    bool inside = penumbraConservativeVertexInside(clip0, params) && penumbraConservativeVertexInside(clip1, params) &&
                  penumbraConservativeVertexInside(clip2, params);
    int n = 3;
    if (inside) {
        for (int i = 0; i < 3; ++i) {
            precise vec2 q = c[i].xy / c[i].w * half_size + half_size;  // the twin rounds the product
            penumbraConservativePolygon[i] = q;
            penumbraConservativeDepth[i] = c[i].z / c[i].w;
        }
    } else {
        if (penumbraConservativeOutsideOnePlane(clip0, clip1, clip2, params)) return 0;
#if PENUMBRA_CONSERVATIVE_DIRECT
        PENUMBRA_CONSERVATIVE_SPILL(clip0, clip1, clip2);  // the spill pass clips and emits it
        return 0;
#else
        n = penumbraConservativeClip(clip0, clip1, clip2, params);
        if (n == 0) return 0;
#endif
    }

    // 2. Orientation, diameter and thinness (relative to a local origin: vertex 0).
    vec2 origin = penumbraConservativePolygon[0];
    float area2 = 0.0;
    for (int i = 1; i + 1 < n; ++i) {
        area2 += penumbraConservativeCross(penumbraConservativePolygon[i] - origin,
                                           penumbraConservativePolygon[i + 1] - origin);
    }
    float diameter2 = 0.0;
    int far_a = 0, far_b = 0;
    for (int i = 0; i < n; ++i) {
        for (int j = i + 1; j < n; ++j) {
            vec2 d = penumbraConservativePolygon[j] - penumbraConservativePolygon[i];
            precise float d2 = d.x * d.x + d.y * d.y;
            if (d2 > diameter2) {
                diameter2 = d2;
                far_a = i;
                far_b = j;
            }
        }
    }
    float diameter = sqrt(diameter2);
    precise float thin_bound = (params.expansion.z + params.expansion.w * diameter) * diameter;
    bool thin = abs(area2) <= thin_bound;
#if PENUMBRA_CONSERVATIVE_DROP_DEGENERATE
    if (thin) return 0;
#endif

    // 3. Depth plane z(p) = z0 + dot(gradient, p - origin) from Newell's normal; thin: nearest z.
    precise float z0 = penumbraConservativeDepth[0];
    precise vec2 gradient = vec2(0.0);
    if (thin) {
        for (int i = 1; i < n; ++i) z0 = min(z0, penumbraConservativeDepth[i]);
    } else {
        precise vec3 normal = vec3(0.0);
        precise vec3 mean = vec3(0.0);
        for (int i = 0; i < n; ++i) {
            vec3 a = vec3(penumbraConservativePolygon[i] - origin, penumbraConservativeDepth[i]);
            int j = i + 1 < n ? i + 1 : 0;
            vec3 b = vec3(penumbraConservativePolygon[j] - origin, penumbraConservativeDepth[j]);
            normal += vec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
            mean += a;
        }
        mean /= float(n);
        gradient = -normal.xy / normal.z;
        z0 = mean.z - (gradient.x * mean.x + gradient.y * mean.y);
    }

    // 4. Thin polygons become the segment between their farthest points, dilated by h + thickness.
    if (thin) {
        vec2 a = penumbraConservativePolygon[far_a];
        vec2 b = penumbraConservativePolygon[far_b];
        float thickness = 0.0;
        if (diameter > 0.0) {
            for (int i = 0; i < n; ++i) {
                thickness = max(thickness, abs(penumbraConservativeCross(penumbraConservativePolygon[i] - a, b - a)));
            }
            thickness /= diameter;
        }
        h += thickness;
        penumbraConservativePolygon[0] = a;
        penumbraConservativePolygon[1] = b;
        n = 2;
    } else if (area2 < 0.0) {  // clockwise (back-facing) input: walk it the other way
        for (int i = 0; i < n / 2; ++i) {
            vec2 t = penumbraConservativePolygon[i];
            penumbraConservativePolygon[i] = penumbraConservativePolygon[n - 1 - i];
            penumbraConservativePolygon[n - 1 - i] = t;
        }
    }

    // 5. Pixel-expanded bounding box (handed to the fragment stage) and viewport culling.
    vec2 lo = penumbraConservativePolygon[0];
    vec2 hi = lo;
    for (int i = 1; i < n; ++i) {
        lo = min(lo, penumbraConservativePolygon[i]);
        hi = max(hi, penumbraConservativePolygon[i]);
    }
    lo -= vec2(h);
    hi += vec2(h);
    if (any(greaterThan(lo, size)) || any(lessThan(hi, vec2(0.0)))) return 0;
    vec4 box = vec4(lo + params.viewport.xy, hi + params.viewport.xy);
#if PENUMBRA_CONSERVATIVE_BOX_ONLY
    penumbraConservativeBoxOut = box;
    penumbraConservativeBoxTriangle = inside && !thin;
    penumbraConservativeBoxDilation = h;
    return 1;
#else

    // 6. The hull.
    int count = -1;
#if !PENUMBRA_CONSERVATIVE_EXACT
    if (inside && !thin) count = penumbraConservativeFixedHull(h);
    else
#endif
        count = penumbraConservativeChainHull(n, h);
    if (count < 0) {  // never expected; the box is always conservative
        penumbraConservativeHull[0] = lo;
        penumbraConservativeHull[1] = vec2(hi.x, lo.y);
        penumbraConservativeHull[2] = hi;
        penumbraConservativeHull[3] = vec2(lo.x, hi.y);
        count = 4;
    }

    // 7. Emit the convex polygon as a zig-zag strip: 0, 1, n-1, 2, n-2, ... (all counter-clockwise).
    for (int j = 0; j < count; ++j) {
        int index = (j & 1) != 0 ? (j + 1) >> 1 : (count - (j >> 1)) % count;
        vec2 p = penumbraConservativeHull[index];
        vec2 dq = p - origin;
        precise float z = clamp(z0 + (gradient.x * dq.x + gradient.y * dq.y), params.depth.x, params.depth.y);
        PENUMBRA_CONSERVATIVE_EMIT_VERTEX(vec4(p / half_size - 1.0, z, 1.0), box);
    }
    EndPrimitive();
    return count;
#endif
}

#endif
