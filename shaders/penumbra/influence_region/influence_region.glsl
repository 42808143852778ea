// penumbra — a shadow-casting triangle's influence region in the light grid (sintorn2008 §4.1,
// Fig. 5; the optional supporting-plane cut of §4.3 / [LLA06]), conservatively dilated with the
// §4.1 corner rules. GLSL twin of penumbra::influenceRegion (include/penumbra/influence_region.hpp,
// where the construction and its contract are described): the same float operations in the same
// order, `precise` wherever the twin keeps a product opaque, so the polygon is bit for bit the
// CPU's on drivers with correctly rounded float add/mul/div/sqrt (llvmpipe).
//
// Integration summary
//   needs:    a PenumbraInfluenceParams value (penumbra::influenceRegionSetup on the host);
//             PENUMBRA_INFLUENCE_SIDES (k: 4, 6, 8, 12) and PENUMBRA_INFLUENCE_CUT (0/1) from the
//             setup's defines.
//   call:     int penumbraInfluenceRegion(vec3 v0, vec3 v1, vec3 v2, PenumbraInfluenceParams p):
//             world-space (float) vertices -> the polygon to rasterize in penumbraInfluenceOut[0, n),
//             grid pixels ([0, W] x [0, H] is the grid), counter-clockwise; returns n (0: dropped or
//             culled). penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_*, penumbraInfluenceFallback =
//             PENUMBRA_INFLUENCE_FALLBACK_* bits. Rasterize it into a W x H viewport with GL's
//             ordinary rule (gl_Position = vec4(pixel / (0.5 * grid) - 1, z, 1)); every texel the
//             region touches then gets a fragment. At most PENUMBRA_INFLUENCE_MAX_VERTICES(k) = 3k + 5.
//   hooks:    none.
#ifndef PENUMBRA_INFLUENCE_REGION_GLSL
#define PENUMBRA_INFLUENCE_REGION_GLSL

#include "penumbra/influence_region/influence_region_shared.h"
#include "penumbra/conservative_raster/conservative_raster_polygon.glsl"

#ifndef PENUMBRA_INFLUENCE_SIDES
#error penumbra/influence_region/influence_region.glsl needs PENUMBRA_INFLUENCE_SIDES (4, 6, 8 or 12; from influenceRegionSetup's defines)
#endif
#if PENUMBRA_INFLUENCE_SIDES != 4 && PENUMBRA_INFLUENCE_SIDES != 6 && PENUMBRA_INFLUENCE_SIDES != 8 && PENUMBRA_INFLUENCE_SIDES != 12
#error PENUMBRA_INFLUENCE_SIDES must be 4, 6, 8 or 12
#endif
#ifndef PENUMBRA_INFLUENCE_CUT
#define PENUMBRA_INFLUENCE_CUT 0
#endif

#define PENUMBRA_INFLUENCE_K PENUMBRA_INFLUENCE_SIDES
#define PENUMBRA_INFLUENCE_N (3 * PENUMBRA_INFLUENCE_SIDES)

vec2 penumbraInfluenceOut[PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)];
int penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_DROPPED;
uint penumbraInfluenceFallback = 0u;

vec2 penumbraInfluenceGroups[PENUMBRA_INFLUENCE_N];        // group i at [i k, i k + k)
vec2 penumbraInfluenceSortedGroups[PENUMBRA_INFLUENCE_N];  // each group sorted
vec2 penumbraInfluenceMerged[2 * PENUMBRA_INFLUENCE_K];
vec2 penumbraInfluencePoints[PENUMBRA_INFLUENCE_N];        // all, sorted
vec2 penumbraInfluenceHull[2 * PENUMBRA_INFLUENCE_N + 1];
vec2 penumbraInfluenceChainF[PENUMBRA_INFLUENCE_K];
vec2 penumbraInfluenceChainB[PENUMBRA_INFLUENCE_K];

float penumbraInfluenceDot3(vec3 a, vec3 b) {
    precise float r = (a.x * b.x + a.y * b.y) + a.z * b.z;
    return r;
}

float penumbraInfluenceCross2(vec2 a, vec2 b) {
    precise float r = a.x * b.y - a.y * b.x;
    return r;
}

vec3 penumbraInfluenceCross(vec3 a, vec3 b) {
    precise vec3 r = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return r;
}

bool penumbraInfluenceLess(vec2 a, vec2 b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }

// Sorts group g (k points in angular order) into penumbraInfluenceSortedGroups: two x-monotone
// chains from the leftmost to the rightmost point, merged.
void penumbraInfluenceSortGroup(int g) {
    int base = g * PENUMBRA_INFLUENCE_K;
    int left = 0, right = 0;
    for (int i = 1; i < PENUMBRA_INFLUENCE_K; ++i) {
        if (penumbraInfluenceLess(penumbraInfluenceGroups[base + i], penumbraInfluenceGroups[base + left])) left = i;
        if (penumbraInfluenceLess(penumbraInfluenceGroups[base + right], penumbraInfluenceGroups[base + i])) right = i;
    }
    int nf = 0, nb = 0;
    for (int i = left, guard = 0; guard < PENUMBRA_INFLUENCE_K; i = (i + 1) % PENUMBRA_INFLUENCE_K, ++guard) {
        penumbraInfluenceChainF[nf++] = penumbraInfluenceGroups[base + i];
        if (i == right) break;
    }
    for (int i = (left + PENUMBRA_INFLUENCE_K - 1) % PENUMBRA_INFLUENCE_K; i != right && nb < PENUMBRA_INFLUENCE_K;
         i = (i + PENUMBRA_INFLUENCE_K - 1) % PENUMBRA_INFLUENCE_K) {
        penumbraInfluenceChainB[nb++] = penumbraInfluenceGroups[base + i];
    }
    int i = 0, j = 0;
    for (int m = 0; m < PENUMBRA_INFLUENCE_K; ++m) {
        bool take_b = i >= nf || (j < nb && penumbraInfluenceLess(penumbraInfluenceChainB[j], penumbraInfluenceChainF[i]));
        penumbraInfluenceSortedGroups[base + m] = take_b ? penumbraInfluenceChainB[j++] : penumbraInfluenceChainF[i++];
    }
}

// The §4.1 dilation of penumbraInfluenceHull[0, n) (counter-clockwise) by [-h, h]^2 into
// penumbraInfluenceOut; -1 when the turn sequence is inconsistent.
int penumbraInfluenceDilate(int n, float h) {
    int count = 0, turns = 0;
    for (int i = 0; i < n; ++i) {
        vec2 q = penumbraInfluenceHull[i];
        vec2 d_in = q - penumbraInfluenceHull[(i + n - 1) % n];
        vec2 d_out = penumbraInfluenceHull[(i + 1) % n] - q;
        int k_in = penumbraConservativeEdgeCorner(d_in);
        int k_out = penumbraConservativeEdgeCorner(d_out);
        int steps = (k_out - k_in) & 3;
        turns += steps;
        if (steps == 3) return -1;
        vec2 c_in = h * penumbraConservativeCorner(k_in);
        vec2 c_out = h * penumbraConservativeCorner(k_out);
        vec2 a = q + c_in;
        if (steps == 0) {  // case i: one vertex
            penumbraInfluenceOut[count++] = a;
            continue;
        }
        vec2 b = q + c_out;
        if (steps == 1) {  // case ii: the offset edges' intersection when the turn is below 90°
            precise float dot_io = d_in.x * d_out.x + d_in.y * d_out.y;
            float cross_io = penumbraInfluenceCross2(d_in, d_out);
            precise float len2 = (d_in.x * d_in.x + d_in.y * d_in.y) * (d_out.x * d_out.x + d_out.y * d_out.y);
            precise float cross2 = cross_io * cross_io;
            precise float limit = len2 * (1.0 / 4096.0);
            if (dot_io > 0.0 && cross_io > 0.0 && cross2 >= limit) {
                float t = penumbraInfluenceCross2(c_out - c_in, d_out) / cross_io;
                precise vec2 x = vec2(a.x + t * d_in.x, a.y + t * d_in.y);
                penumbraInfluenceOut[count++] = x;
            } else {
                penumbraInfluenceOut[count++] = a;
                penumbraInfluenceOut[count++] = b;
            }
            continue;
        }
        penumbraInfluenceOut[count++] = a;  // case iii: three corners
        penumbraInfluenceOut[count++] = q + h * penumbraConservativeCorner((k_in + 1) & 3);
        penumbraInfluenceOut[count++] = b;
    }
    if (turns != 4) return -1;
    return count;
}

int penumbraInfluenceWholeGrid(uint flags, PenumbraInfluenceParams p) {
    penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_WHOLE_GRID;
    penumbraInfluenceFallback = flags;
    penumbraInfluenceOut[0] = vec2(0.0, 0.0);
    penumbraInfluenceOut[1] = vec2(p.grid.x, 0.0);
    penumbraInfluenceOut[2] = vec2(p.grid.x, p.grid.y);
    penumbraInfluenceOut[3] = vec2(0.0, p.grid.y);
    return 4;
}

int penumbraInfluenceRegion(vec3 v0, vec3 v1, vec3 v2, PenumbraInfluenceParams p) {
    penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_DROPPED;
    penumbraInfluenceFallback = 0u;
    if (!(penumbraConservativeFinite(vec4(v0, 0.0)) && penumbraConservativeFinite(vec4(v1, 0.0)) &&
          penumbraConservativeFinite(vec4(v2, 0.0)))) {
        return 0;
    }
    float W = p.grid.x, H = p.grid.y, B = p.grid.z, h = p.expansion.x;
    vec3 n_far = p.far_plane.xyz;
    vec3 v[3] = vec3[3](v0, v1, v2);
    vec3 q[3];
    float s[3];
    int beyond = 0;
    for (int i = 0; i < 3; ++i) {
        vec3 d = v[i] - p.center.xyz;
        q[i] = vec3(penumbraInfluenceDot3(p.to_local[0].xyz, d), penumbraInfluenceDot3(p.to_local[1].xyz, d),
                    penumbraInfluenceDot3(p.to_local[2].xyz, d));
        precise float si = penumbraInfluenceDot3(n_far, q[i]) + p.far_plane.w;
        s[i] = si;
        if (!(s[i] < 0.0)) ++beyond;
    }
    if (beyond == 3) {
        penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_CULLED;
        return 0;
    }
    if (beyond > 0) return penumbraInfluenceWholeGrid(PENUMBRA_INFLUENCE_FALLBACK_BEYOND_FAR, p);

    uint flags = 0u;
    for (int i = 0; i < 3 && flags == 0u; ++i) {
        vec3 qi = q[i];
        float r2 = penumbraInfluenceDot3(qi, qi);
        if (!(r2 > p.expansion.w)) {
            flags |= PENUMBRA_INFLUENCE_FALLBACK_INSIDE_LIGHT;
            break;
        }
        float len = sqrt(r2);
        precise float R = p.expansion.y + p.expansion.z * len;
        precise float R2 = R * R;
        if (!(r2 > R2)) {
            flags |= PENUMBRA_INFLUENCE_FALLBACK_INSIDE_LIGHT;
            break;
        }
        precise vec3 C = vec3(penumbraInfluenceDot3(p.to_pixel[0].xyz, qi) + p.to_pixel[0].w,
                              penumbraInfluenceDot3(p.to_pixel[1].xyz, qi) + p.to_pixel[1].w,
                              penumbraInfluenceDot3(p.to_pixel[2].xyz, qi) + p.to_pixel[2].w);
        precise float bound_c = B * C.z;
        if (!(C.z > 0.0) || !(abs(C.x) <= bound_c) || !(abs(C.y) <= bound_c)) {
            flags |= PENUMBRA_INFLUENCE_FALLBACK_VERTEX;
            break;
        }
        precise vec3 m = qi * (R2 / r2);
        precise float rho = (R * sqrt(r2 - R2)) / len;
        precise float radius = rho * p.polygon.x;
        vec3 u = qi / len;
        vec3 au = abs(u);
        vec3 a = au.x <= au.y && au.x <= au.z ? vec3(0.0, u.z, -u.y)
                 : au.y <= au.z              ? vec3(-u.z, 0.0, u.x)
                                             : vec3(u.y, -u.x, 0.0);
        a = a / sqrt(penumbraInfluenceDot3(a, a));
        vec3 b = penumbraInfluenceCross(u, a);
        for (int j = 0; j < PENUMBRA_INFLUENCE_K; ++j) {
            vec4 dir4 = p.directions[j / 2];
            float cj = (j & 1) != 0 ? dir4.z : dir4.x;
            float sj = (j & 1) != 0 ? dir4.w : dir4.y;
            precise float rc = radius * cj;
            precise float rs = radius * sj;
            precise vec3 g = m + (a * rc + b * rs);
            vec3 dj = qi - g;
            float aj = penumbraInfluenceDot3(n_far, dj);
            vec3 D = vec3(penumbraInfluenceDot3(p.to_pixel[0].xyz, dj), penumbraInfluenceDot3(p.to_pixel[1].xyz, dj),
                          penumbraInfluenceDot3(p.to_pixel[2].xyz, dj));
            precise float bound_d = B * D.z;
            if (!(aj > 0.0) || !(D.z > 0.0) || !(abs(D.x) <= bound_d) || !(abs(D.y) <= bound_d)) {
                flags |= PENUMBRA_INFLUENCE_FALLBACK_RAY;
                break;
            }
            precise vec3 P = aj * C - s[i] * D;
            penumbraInfluenceGroups[i * PENUMBRA_INFLUENCE_K + j] = vec2(P.x / P.z, P.y / P.z);
        }
    }
    if (flags != 0u) return penumbraInfluenceWholeGrid(flags, p);

    // Hull of the 3k points: sorted groups, two merges, insertion repair, monotone chain (O(k)).
    for (int g = 0; g < 3; ++g) penumbraInfluenceSortGroup(g);
    {
        int i = 0, j = 0;
        for (int m = 0; m < 2 * PENUMBRA_INFLUENCE_K; ++m) {
            bool take_b = i >= PENUMBRA_INFLUENCE_K ||
                          (j < PENUMBRA_INFLUENCE_K && penumbraInfluenceLess(penumbraInfluenceSortedGroups[PENUMBRA_INFLUENCE_K + j],
                                                                             penumbraInfluenceSortedGroups[i]));
            penumbraInfluenceMerged[m] = take_b ? penumbraInfluenceSortedGroups[PENUMBRA_INFLUENCE_K + j++]
                                                : penumbraInfluenceSortedGroups[i++];
        }
        i = 0;
        j = 0;
        for (int m = 0; m < PENUMBRA_INFLUENCE_N; ++m) {
            bool take_b = i >= 2 * PENUMBRA_INFLUENCE_K ||
                          (j < PENUMBRA_INFLUENCE_K &&
                           penumbraInfluenceLess(penumbraInfluenceSortedGroups[2 * PENUMBRA_INFLUENCE_K + j], penumbraInfluenceMerged[i]));
            penumbraInfluencePoints[m] = take_b ? penumbraInfluenceSortedGroups[2 * PENUMBRA_INFLUENCE_K + j++]
                                                : penumbraInfluenceMerged[i++];
        }
    }
    for (int i = 1; i < PENUMBRA_INFLUENCE_N; ++i) {
        vec2 x = penumbraInfluencePoints[i];
        int j = i - 1;
        while (j >= 0 && penumbraInfluenceLess(x, penumbraInfluencePoints[j])) {
            penumbraInfluencePoints[j + 1] = penumbraInfluencePoints[j];
            --j;
        }
        penumbraInfluencePoints[j + 1] = x;
    }
    int n = 0;
    for (int i = 0; i < PENUMBRA_INFLUENCE_N; ++i) {
        vec2 x = penumbraInfluencePoints[i];
        while (n >= 2 && penumbraInfluenceCross2(penumbraInfluenceHull[n - 1] - penumbraInfluenceHull[n - 2],
                                                 x - penumbraInfluenceHull[n - 2]) <= 0.0) {
            --n;
        }
        penumbraInfluenceHull[n++] = x;
    }
    int lower = n + 1;
    for (int i = PENUMBRA_INFLUENCE_N - 2; i >= 0; --i) {
        vec2 x = penumbraInfluencePoints[i];
        while (n >= lower && penumbraInfluenceCross2(penumbraInfluenceHull[n - 1] - penumbraInfluenceHull[n - 2],
                                                     x - penumbraInfluenceHull[n - 2]) <= 0.0) {
            --n;
        }
        penumbraInfluenceHull[n++] = x;
    }
    if (n > 1) --n;

#if PENUMBRA_INFLUENCE_CUT
    if ((p.config.y & PENUMBRA_INFLUENCE_CONFIG_CUT) != 0u && n >= 3) {
        vec3 e0 = q[1] - q[0];
        vec3 e1 = q[2] - q[0];
        vec3 nt = penumbraInfluenceCross(e0, e1);
        float nn = penumbraInfluenceDot3(nt, nt);
        precise float sliver = (penumbraInfluenceDot3(e0, e0) * penumbraInfluenceDot3(e1, e1)) * (1.0 / 256.0);
        float dist = -penumbraInfluenceDot3(nt, q[0]);
        float len0 = sqrt(penumbraInfluenceDot3(q[0], q[0]));
        precise float clearance = p.polygon.y + p.polygon.z * len0;
        precise float dist2 = dist * dist;
        precise float need = (clearance * clearance) * nn;
        if (nn > 0.0 && nn >= sliver && dist2 > need) {
            vec3 nk = dist > 0.0 ? -nt : nt;
            vec3 line = vec3(penumbraInfluenceDot3(p.cut_lines[0].xyz, nk), penumbraInfluenceDot3(p.cut_lines[1].xyz, nk),
                             penumbraInfluenceDot3(p.cut_lines[2].xyz, nk));
            precise float slack = p.grid.w * (abs(line.x) + abs(line.y));
            // Clip in place through penumbraInfluencePoints (free now) as the output buffer.
            int m = 0;
            vec2 prev = penumbraInfluenceHull[n - 1];
            precise float d_prev = ((line.x * prev.x + line.y * prev.y) + line.z) + slack;
            for (int i = 0; i < n; ++i) {
                vec2 cur = penumbraInfluenceHull[i];
                precise float d_cur = ((line.x * cur.x + line.y * cur.y) + line.z) + slack;
                if (d_cur >= 0.0) {
                    if (d_prev < 0.0) {
                        float t = d_cur / (d_cur - d_prev);
                        precise vec2 x = vec2(cur.x + t * (prev.x - cur.x), cur.y + t * (prev.y - cur.y));
                        penumbraInfluencePoints[m++] = x;
                    }
                    penumbraInfluencePoints[m++] = cur;
                } else if (d_prev >= 0.0) {
                    float t = d_prev / (d_prev - d_cur);
                    precise vec2 x = vec2(prev.x + t * (cur.x - prev.x), prev.y + t * (cur.y - prev.y));
                    penumbraInfluencePoints[m++] = x;
                }
                prev = cur;
                d_prev = d_cur;
            }
            if (m == 0) {
                penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_CULLED;
                return 0;
            }
            n = m;
            for (int i = 0; i < n; ++i) penumbraInfluenceHull[i] = penumbraInfluencePoints[i];
        }
    }
#endif

    vec2 lo = penumbraInfluenceHull[0];
    vec2 hi = lo;
    for (int i = 1; i < n; ++i) {
        lo = min(lo, penumbraInfluenceHull[i]);
        hi = max(hi, penumbraInfluenceHull[i]);
    }
    lo -= vec2(h);
    hi += vec2(h);
    if (lo.x > W || lo.y > H || hi.x < 0.0 || hi.y < 0.0) {
        penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_CULLED;
        return 0;
    }
    int count = n >= 3 ? penumbraInfluenceDilate(n, h) : -1;
    penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_HULL;
    if (count < 0) {
        penumbraInfluenceOut[0] = lo;
        penumbraInfluenceOut[1] = vec2(hi.x, lo.y);
        penumbraInfluenceOut[2] = hi;
        penumbraInfluenceOut[3] = vec2(lo.x, hi.y);
        count = 4;
        penumbraInfluenceKind = PENUMBRA_INFLUENCE_KIND_BOX;
    }
    return count;
}

#endif
