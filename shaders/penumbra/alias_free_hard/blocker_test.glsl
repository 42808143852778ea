// penumbra — does triangle (a, b, c) block the open segment from view sample p to light point l?
// The per-sample test of sintorn2008 §3.2/§3.3 ("4 planes: 3 edges + support", BLOCKS.md core
// pipeline), written so that its exact mode decides like the double-precision oracle
// (include/penumbra/reference/visibility.hpp) on every pair the oracle does not flag as a tie:
//
//   n  = (b - a) x (c - a);  d_p = n.(p - a),  d_l = n.(l - a)        (supporting plane)
//   coplanar rule (oracle rule 2): ignore the triangle when p (or l) lies within eps * scale of
//       the triangle itself (plane distance |d_p| <= eps * scale * |n| checked first as a bound),
//       scale = max(|a - p|inf, |b - p|inf, |c - p|inf, min(|l - p|inf, E)), E = the scene's extent
//       (the oracle's sceneExtent(); the overloads without it take E = |l - p|inf, the uncapped
//       rule, under which a light ~1e3 scene sizes away ignores every caster): a sample lying on a
//       surface is never shadowed by that surface or the neighbours it touches, with no depth
//       bias, while a grazing crossing of a neighbour near the terminator still counts;
//   p and l strictly on opposite sides (and |d_p| > offset * |n|, the optional sample offset);
//   edge planes through l: e_i = det(v_i - l, v_i+1 - l, p - l) all >= 0 or all <= 0, not all 0
//       (the line from l through p meets the closed triangle), evaluated as det(p - v_i,
//       p - v_i+1, p - l) so that a far light costs no precision.
// With both: the segment crosses the plane strictly between p and l, inside the triangle.
//
// PENUMBRA_AFH_EXACT 1 (default): double precision, `precise` so no FMA contraction changes a
// sign; the host twin (penumbra::afhBlocks<double>) runs the same operations in the same order.
// PENUMBRA_AFH_FILTERED 1 (default with EXACT 1): penumbraAfhBlocksLight decides in float where
// a proven error bound allows and calls the double test only where it does not (same bits as
// PENUMBRA_AFH_FILTERED 0, the fp64-only path; see below).
// PENUMBRA_AFH_EXACT 0: float, faster on hardware with slow fp64; its error against the oracle is
// measured by the tests and benchmarks. Callers pass positions already in the chosen type.
#ifndef PENUMBRA_AFH_BLOCKER_TEST_GLSL
#define PENUMBRA_AFH_BLOCKER_TEST_GLSL

#include "penumbra/alias_free_hard/degenerate.glsl"

#ifndef PENUMBRA_AFH_EXACT
#define PENUMBRA_AFH_EXACT 1
#endif

#if PENUMBRA_AFH_EXACT
#ifndef PENUMBRA_AFH_FILTERED
#define PENUMBRA_AFH_FILTERED 1
#endif
#define penumbraAfhReal double
#define penumbraAfhVec3 dvec3
#else
#define penumbraAfhReal float
#define penumbraAfhVec3 vec3
#endif

penumbraAfhReal penumbraAfhMaxAbs(penumbraAfhVec3 v) {
    penumbraAfhVec3 m = abs(v);
    return max(m.x, max(m.y, m.z));
}

// Triple product det(u, v, w) = (u x v) . w, evaluated term by term in a fixed order.
penumbraAfhReal penumbraAfhDet(penumbraAfhVec3 u, penumbraAfhVec3 v, penumbraAfhVec3 w) {
    precise penumbraAfhReal cx = u.y * v.z - u.z * v.y;
    precise penumbraAfhReal cy = u.z * v.x - u.x * v.z;
    precise penumbraAfhReal cz = u.x * v.y - u.y * v.x;
    precise penumbraAfhReal r = cx * w.x + cy * w.y + cz * w.z;
    return r;
}

// Squared distance from p to the closed triangle (a, b, c): closest point by Voronoi regions
// (Ericson, Real-Time Collision Detection, 5.1.5); the host twin is
// penumbra::detail::pointTriangleDistance2 (include/penumbra/detail/geometry.hpp), which the
// oracle uses too.
penumbraAfhReal penumbraAfhPointTriangleDistance2(penumbraAfhVec3 p, penumbraAfhVec3 a, penumbraAfhVec3 b, penumbraAfhVec3 c) {
    precise penumbraAfhVec3 ab = b - a, ac = c - a, ap = p - a;
    precise penumbraAfhReal d1 = dot(ab, ap), d2 = dot(ac, ap);
    penumbraAfhVec3 d;
    if (d1 <= 0.0 && d2 <= 0.0) {
        d = ap;
    } else {
        precise penumbraAfhVec3 bp = p - b, cp = p - c;
        precise penumbraAfhReal d3 = dot(ab, bp), d4 = dot(ac, bp), d5 = dot(ab, cp), d6 = dot(ac, cp);
        precise penumbraAfhReal vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0.0 && d4 <= d3) {
            d = bp;
        } else if (d6 >= 0.0 && d5 <= d6) {
            d = cp;
        } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
            d = ap - ab * (d1 / (d1 - d3));
        } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
            d = ap - ac * (d2 / (d2 - d6));
        } else if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
            d = bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        } else {
            precise penumbraAfhReal denom = va + vb + vc;
            if (!(denom > 0.0)) return dot(ap, ap);
            d = ap - ab * (vb / denom) - ac * (vc / denom);
        }
    }
    return dot(d, d);
}

// `scene_extent` = E of the coplanar rule's scale (> 0; +inf = uncapped).
bool penumbraAfhBlocks(penumbraAfhVec3 a, penumbraAfhVec3 b, penumbraAfhVec3 c, penumbraAfhVec3 p,
                       penumbraAfhVec3 l, penumbraAfhReal coplanar_epsilon, penumbraAfhReal offset,
                       penumbraAfhReal scene_extent) {
    precise penumbraAfhVec3 ab = b - a;
    precise penumbraAfhVec3 ac = c - a;
    precise penumbraAfhReal nx = ab.y * ac.z - ab.z * ac.y;
    precise penumbraAfhReal ny = ab.z * ac.x - ab.x * ac.z;
    precise penumbraAfhReal nz = ab.x * ac.y - ab.y * ac.x;
    precise penumbraAfhVec3 ap = p - a;
    precise penumbraAfhVec3 al = l - a;
    precise penumbraAfhReal dp = nx * ap.x + ny * ap.y + nz * ap.z;
    precise penumbraAfhReal dl = nx * al.x + ny * al.y + nz * al.z;
    // Opposite sides first: the cheapest rejection (most casters lie beside or behind a sample).
    if (!((dp < 0.0 && dl > 0.0) || (dp > 0.0 && dl < 0.0))) return false;
    precise penumbraAfhReal nn = nx * nx + ny * ny + nz * nz;
    precise penumbraAfhReal scale = max(max(penumbraAfhMaxAbs(a - p), penumbraAfhMaxAbs(b - p)),
                                        max(penumbraAfhMaxAbs(c - p), min(penumbraAfhMaxAbs(l - p), scene_extent)));
    precise penumbraAfhReal tol = coplanar_epsilon * scale;
    precise penumbraAfhReal threshold = tol * tol * nn;
    // Plane distance first (cheap lower bound), then the distance to the triangle itself.
    if (dp * dp <= threshold && penumbraAfhPointTriangleDistance2(p, a, b, c) <= tol * tol) return false;
    if (dl * dl <= threshold && penumbraAfhPointTriangleDistance2(l, a, b, c) <= tol * tol) return false;
    if (offset > 0.0 && dp * dp <= offset * offset * nn) return false;
    // e_0 = det(a - l, b - l, p - l) = det(p - a, p - b, p - l), taken at p: relative to a far
    // light the cross products cancel ~|l|^2 (wrong signs a scene away from an edge at 1e7);
    // relative to p the error is ~u |l| |v - p|^2, a rounding of the value's own terms.
    precise penumbraAfhVec3 bp = p - b;
    precise penumbraAfhVec3 cp = p - c;
    precise penumbraAfhVec3 lp = p - l;
    penumbraAfhReal e0 = penumbraAfhDet(ap, bp, lp);
    penumbraAfhReal e1 = penumbraAfhDet(bp, cp, lp);
    penumbraAfhReal e2 = penumbraAfhDet(cp, ap, lp);
    bool all_nonnegative = e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0;
    bool all_nonpositive = e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0;
    bool all_zero = e0 == 0.0 && e1 == 0.0 && e2 == 0.0;
    return (all_nonnegative || all_nonpositive) && !all_zero;
}

// The uncapped rule (E = |l - p|inf: the same bits as before E existed).
bool penumbraAfhBlocks(penumbraAfhVec3 a, penumbraAfhVec3 b, penumbraAfhVec3 c, penumbraAfhVec3 p,
                       penumbraAfhVec3 l, penumbraAfhReal coplanar_epsilon, penumbraAfhReal offset) {
    return penumbraAfhBlocks(a, b, c, p, l, coplanar_epsilon, offset, penumbraAfhMaxAbs(l - p));
}

// ---------------------------------------------------------------------------------------------
// Filtered exact test (PENUMBRA_AFH_EXACT 1, PENUMBRA_AFH_FILTERED 1, the default): the same
// decision as penumbraAfhBlocks in double on every input, computed in float whenever a forward
// error bound proves that float and double agree (a semi-static filter in the manner of
// Shewchuk's robust predicates), and by penumbraAfhBlocks itself otherwise. fp64 runs at 1/32 to
// 1/64 rate on consumer GPUs (emulated on some). The fallback is taken for samples lying on the
// caster's plane (within float noise: the coplanar rule's epsilon, 1e-7, is below what float
// resolves, so it is decided in double) and for lines within float noise of an edge. Measured:
// 0.45-34 % of realistic (sample, triangle) pairs, 13-44 % of the light pass's tests on the
// built-in scenes at 256x256 (mostly ground samples against the ground triangle they lie on). Design and proof: include/penumbra/detail/blocker_filter.hpp,
// whose CPU model runs these float operations in this order (tests/blocker_filter_test.cpp).
//
// The double verdict is a conjunction: opposite sides AND not coplanar (p) AND not coplanar (l)
// AND not offset-rejected AND the line meets the triangle (all early returns return false). So
// one conjunct certainly false decides false, all certainly true decide true, anything else
// falls back. A sign is certain when |x_float| > B, B bounding |x_float - X| + |x_double - X|
// (X: the exact value on the same float inputs), so X, x_float and x_double share one nonzero
// sign. Assumptions (GLSL 4.50 §4.7.1 "Range and Precision"): float +, -, * correctly rounded
// in an undefined rounding mode (unit u = 2^-23, any mode), denormals possibly flushed (an
// absolute 2^-124 per operation, the term A below), double +, -, * at least as accurate as float
// (the spec's floor: the bound does not rely on fp64 being better), float<->double conversions
// correctly rounded, finite inputs. `precise` everywhere: no contraction (an FMA would only
// remove roundings, the bound would still hold, but the CPU model would no longer match bits).
// The light point of a sample: the point light itself, or `reach` along a directional light's
// unit vector `light` from p. The fp64-only path and the filter's fallback both use this one
// function (precise: no FMA), so both see the same double l.
penumbraAfhVec3 penumbraAfhLightPoint(penumbraAfhVec3 p, penumbraAfhVec3 light, penumbraAfhReal reach, bool point_light) {
    precise penumbraAfhVec3 t = light * reach;
    precise penumbraAfhVec3 l = p + t;
    return point_light ? light : l;
}

#if PENUMBRA_AFH_EXACT

#define PENUMBRA_AFH_FILTER_FALSE 0
#define PENUMBRA_AFH_FILTER_TRUE 1
#define PENUMBRA_AFH_FILTER_UNCERTAIN 2

// Constants (each a decimal above the value the proof needs, so literal rounding cannot matter):
//   relative bound of one triple product: 2 gamma_8 (float and double) with slack = 16u(1+2^-8)
const float penumbraAfhFilterRel = 1.92e-6;
//   the same for the edge products, whose permanent is bounded by 2 |u|inf |v|inf |w|1
const float penumbraAfhFilterEdgeRel = 3.84e-6;
//   underflow: A = kA (1 + m)^2 >= the propagated 2^-124 per operation (m = largest difference)
const float penumbraAfhFilterAbs = 1.3e-35;
//   rounding error of the bound's own evaluation and the double path's comparisons
const float penumbraAfhFilterSlack = 1.004;
//   |n_double|1 <= |n_float|1 + 2 gamma_4 sum(Q)
const float penumbraAfhFilterNormalRel = 1.0e-6;
//   directional light: |l_float - l_double|inf <= 2u (1 + 5u) (|t|inf + |l|inf) + 8 * 2^-124
const float penumbraAfhFilterLightRel = 2.5e-7;
const float penumbraAfhFilterTiny = 1.0e-36;
//   no float overflow when every difference is below 2^40 (degree-3 terms < 2^126)
const float penumbraAfhFilterMaxDifference = 1.0e12;
//   E's float upper bound: float(min(E, 1e38)) + Tiny (1e38 >> any difference the filter accepts)
const double penumbraAfhFilterExtentClamp = 1.0e38LF;

float penumbraAfhFilterMaxAbs(vec3 v) {
    precise vec3 m = abs(v);
    return max(m.x, max(m.y, m.z));
}

// Triple product det(u, v, w) = (u x v) . w in float, same order as penumbraAfhDet.
float penumbraAfhFilterDet(vec3 u, vec3 v, vec3 w) {
    precise float cx = u.y * v.z - u.z * v.y;
    precise float cy = u.z * v.x - u.x * v.z;
    precise float cz = u.x * v.y - u.y * v.x;
    precise float r = cx * w.x + cy * w.y + cz * w.z;
    return r;
}

// -1 / +1: x certainly has that sign (so does the double value); 0: uncertain.
int penumbraAfhFilterSign(float x, float bound) {
    return x > bound ? 1 : (x < -bound ? -1 : 0);
}

// The filter alone: PENUMBRA_AFH_FILTER_FALSE / _TRUE when penumbraAfhBlocks(dvec3(a), dvec3(b),
// dvec3(c), dvec3(p), l_double, coplanar_epsilon, offset) certainly returns false / true,
// PENUMBRA_AFH_FILTER_UNCERTAIN otherwise. `l` is the light point in float; `l_error` bounds
// |l - l_double| per coordinate (0 when l_double == dvec3(l), e.g. a point light).
int penumbraAfhBlocksFilter(vec3 a, vec3 b, vec3 c, vec3 p, vec3 l, float l_error, double coplanar_epsilon,
                            double offset, double scene_extent) {
    // Supporting plane: n = ab x ac, dp = n.(p - a), dl = n.(l - a).
    precise vec3 ab = b - a;
    precise vec3 ac = c - a;
    precise vec3 ap = p - a;
    precise vec3 al = l - a;
    precise float nx = ab.y * ac.z - ab.z * ac.y;
    precise float ny = ab.z * ac.x - ab.x * ac.z;
    precise float nz = ab.x * ac.y - ab.y * ac.x;
    precise float dp = nx * ap.x + ny * ap.y + nz * ap.z;
    precise float dl = nx * al.x + ny * al.y + nz * al.z;
    // Permanent of n: Q_i >= |N_i| term by term; P(dp) = Q.|ap|, P(dl) = Q.(|al| + l_error).
    precise vec3 mab = abs(ab);
    precise vec3 mac = abs(ac);
    precise vec3 mal = abs(al) + vec3(l_error);
    precise vec3 q = vec3(mab.y * mac.z + mab.z * mac.y, mab.z * mac.x + mab.x * mac.z, mab.x * mac.y + mab.y * mac.x);
    precise float q_sum = q.x + q.y + q.z;
    precise float m_plane = max(max(max(mab.x, max(mab.y, mab.z)), max(mac.x, max(mac.y, mac.z))),
                                max(penumbraAfhFilterMaxAbs(ap), max(mal.x, max(mal.y, mal.z))));
    precise float abs_plane = penumbraAfhFilterAbs * ((1.0 + m_plane) * (1.0 + m_plane));
    precise vec3 map = abs(ap);
    precise float b_dp = penumbraAfhFilterRel * (q.x * map.x + q.y * map.y + q.z * map.z) + abs_plane;
    precise float b_dl = penumbraAfhFilterRel * (q.x * mal.x + q.y * mal.y + q.z * mal.z) +
                         (penumbraAfhFilterSlack * q_sum) * l_error + abs_plane;
    if (!(m_plane <= penumbraAfhFilterMaxDifference)) return PENUMBRA_AFH_FILTER_UNCERTAIN;
    const int sp = penumbraAfhFilterSign(dp, b_dp);
    const int sl = penumbraAfhFilterSign(dl, b_dl);
    // Same side, certainly: the cheapest and by far the most common decision.
    if (sp * sl > 0) return PENUMBRA_AFH_FILTER_FALSE;

    // Edge planes through the light, taken at p as the double test does: e_i = det(p - v_i,
    // p - v_i+1, p - l); only p - l carries l_error.
    precise vec3 bp = p - b;
    precise vec3 cp = p - c;
    precise vec3 lp = p - l;
    precise float e0 = penumbraAfhFilterDet(ap, bp, lp);
    precise float e1 = penumbraAfhFilterDet(bp, cp, lp);
    precise float e2 = penumbraAfhFilterDet(cp, ap, lp);
    precise float ma = penumbraAfhFilterMaxAbs(ap);
    precise float mb = penumbraAfhFilterMaxAbs(bp);
    precise float mc = penumbraAfhFilterMaxAbs(cp);
    precise vec3 mlp = abs(lp);
    precise float lp1 = (mlp.x + mlp.y + mlp.z) + 3.0 * l_error;
    precise float m_edge = max(max(ma, mb), max(mc, max(mlp.x, max(mlp.y, mlp.z)) + l_error));
    if (!(m_edge <= penumbraAfhFilterMaxDifference)) return PENUMBRA_AFH_FILTER_UNCERTAIN;
    // A moved light point moves e_i by at most |(p - v_i) x (p - v_i+1)|1 l_error <= 6 m^2 l_error
    // (e_i is affine in l); 24 m^2 kept.
    precise float abs_edge = penumbraAfhFilterAbs * ((1.0 + m_edge) * (1.0 + m_edge)) +
                             (24.2 * (m_edge * m_edge)) * l_error;
    precise float be0 = penumbraAfhFilterEdgeRel * ((ma * mb) * lp1) + abs_edge;
    precise float be1 = penumbraAfhFilterEdgeRel * ((mb * mc) * lp1) + abs_edge;
    precise float be2 = penumbraAfhFilterEdgeRel * ((mc * ma) * lp1) + abs_edge;
    const int s0 = penumbraAfhFilterSign(e0, be0);
    const int s1 = penumbraAfhFilterSign(e1, be1);
    const int s2 = penumbraAfhFilterSign(e2, be2);
    // One certainly positive and one certainly negative edge: the line misses the triangle.
    if (min(s0, min(s1, s2)) < 0 && max(s0, max(s1, s2)) > 0) return PENUMBRA_AFH_FILTER_FALSE;
    if (sp == 0 || sl == 0 || s0 == 0 || s1 == 0 || s2 == 0) return PENUMBRA_AFH_FILTER_UNCERTAIN;

    // Opposite sides and inside, certainly. The coplanar rule cannot fire when |dp| (and |dl|)
    // certainly exceed eps * scale * |n|2 (|n|2 <= |n|1): the distance to the triangle is at
    // least the distance to its plane. E is converted here, where few pairs arrive (one fp64 op).
    precise float extent_up = float(min(scene_extent, penumbraAfhFilterExtentClamp)) + penumbraAfhFilterTiny;
    precise float segment = min(max(mlp.x, max(mlp.y, mlp.z)) + l_error, extent_up);
    precise float scale = max(max(penumbraAfhFilterMaxAbs(ap), penumbraAfhFilterMaxAbs(bp)),
                              max(penumbraAfhFilterMaxAbs(cp), segment));
    precise float n1 = (abs(nx) + abs(ny) + abs(nz)) + penumbraAfhFilterNormalRel * q_sum + abs_plane;
    precise float eps_up = float(coplanar_epsilon) + penumbraAfhFilterTiny;
    precise float tol_n = penumbraAfhFilterSlack * ((eps_up * scale) * n1) + abs_plane;
    if (!(abs(dp) > b_dp + tol_n && abs(dl) > b_dl + tol_n)) return PENUMBRA_AFH_FILTER_UNCERTAIN;

    // Optional offset (offset > 0: the sample must lie farther than offset behind the plane).
    if (offset > 0.0) {
        const float offset_f = float(offset);
        if (!(offset_f <= penumbraAfhFilterMaxDifference)) return PENUMBRA_AFH_FILTER_UNCERTAIN;
        precise float keep = penumbraAfhFilterSlack * ((offset_f + penumbraAfhFilterTiny) * n1) + abs_plane;
        if (abs(dp) > b_dp + keep) return PENUMBRA_AFH_FILTER_TRUE;
        // |n|2 >= |n|inf: rejected when |dp| + b_dp certainly stays below offset * |n|inf.
        precise float n_inf = max(abs(nx), max(abs(ny), abs(nz))) - (penumbraAfhFilterNormalRel * q_sum + abs_plane);
        precise float reject = (0.98 * offset_f) * n_inf;
        if (penumbraAfhFilterSlack * (abs(dp) + b_dp) < reject) return PENUMBRA_AFH_FILTER_FALSE;
        return PENUMBRA_AFH_FILTER_UNCERTAIN;
    }
    return PENUMBRA_AFH_FILTER_TRUE;
}

// The uncapped rule (+inf's float bound: min(|l - p| + l_error, 1e38) = |l - p| + l_error).
int penumbraAfhBlocksFilter(vec3 a, vec3 b, vec3 c, vec3 p, vec3 l, float l_error, double coplanar_epsilon,
                            double offset) {
    return penumbraAfhBlocksFilter(a, b, c, p, l, l_error, coplanar_epsilon, offset, penumbraAfhFilterExtentClamp);
}

// The float light point and its l_error (host: detail::blockerFilterLightPoint).
void penumbraAfhFilterLightPoint(vec3 p, vec4 light, float reach, out vec3 l, out float l_error) {
    l = light.xyz;
    l_error = 0.0;
    if (light.w == 0.0) {
        precise vec3 t = light.xyz * reach;
        precise vec3 ld = p + t;
        precise float e = penumbraAfhFilterLightRel * (penumbraAfhFilterMaxAbs(t) + penumbraAfhFilterMaxAbs(ld));
        l = ld;
        l_error = e + penumbraAfhFilterTiny;
    }
}

// Filter, then the double test where the filter is uncertain. light.w != 0: point light at
// light.xyz; light.w == 0: directional, unit vector light.xyz, light point `reach` away.
// `fallbacks` counts the pairs that took the double test.
bool penumbraAfhBlocksFilteredCounted(vec3 a, vec3 b, vec3 c, vec3 p, vec4 light, float reach, double coplanar_epsilon,
                                      double offset, double scene_extent, inout uint fallbacks) {
    const bool point_light = light.w != 0.0;
    vec3 l;
    float l_error;
    penumbraAfhFilterLightPoint(p, light, reach, l, l_error);
    const int verdict = penumbraAfhBlocksFilter(a, b, c, p, l, l_error, coplanar_epsilon, offset, scene_extent);
    if (verdict != PENUMBRA_AFH_FILTER_UNCERTAIN) return verdict == PENUMBRA_AFH_FILTER_TRUE;
    ++fallbacks;
    return penumbraAfhBlocks(dvec3(a), dvec3(b), dvec3(c), dvec3(p),
                             penumbraAfhLightPoint(dvec3(p), dvec3(light.xyz), double(reach), point_light),
                             coplanar_epsilon, offset, scene_extent);
}

bool penumbraAfhBlocksFiltered(vec3 a, vec3 b, vec3 c, vec3 p, vec4 light, float reach, double coplanar_epsilon,
                               double offset, double scene_extent) {
    uint fallbacks = 0u;
    return penumbraAfhBlocksFilteredCounted(a, b, c, p, light, reach, coplanar_epsilon, offset, scene_extent, fallbacks);
}

// The uncapped rule: the filter's and the double test's overloads without E, as before E existed.
bool penumbraAfhBlocksFiltered(vec3 a, vec3 b, vec3 c, vec3 p, vec4 light, float reach, double coplanar_epsilon,
                               double offset) {
    const bool point_light = light.w != 0.0;
    vec3 l;
    float l_error;
    penumbraAfhFilterLightPoint(p, light, reach, l, l_error);
    const int verdict = penumbraAfhBlocksFilter(a, b, c, p, l, l_error, coplanar_epsilon, offset);
    if (verdict != PENUMBRA_AFH_FILTER_UNCERTAIN) return verdict == PENUMBRA_AFH_FILTER_TRUE;
    return penumbraAfhBlocks(dvec3(a), dvec3(b), dvec3(c), dvec3(p),
                             penumbraAfhLightPoint(dvec3(p), dvec3(light.xyz), double(reach), point_light),
                             coplanar_epsilon, offset);
}

#endif  // PENUMBRA_AFH_EXACT

// E as the float test takes it (PENUMBRA_AFH_EXACT 0): float(min(E, 1e38)), no overflow in the
// conversion (the host twin: detail::afhFloatExtent).
float penumbraAfhFloatExtent(double scene_extent) { return float(min(scene_extent, 1.0e38LF)); }

// The light pass's call: float inputs as stored, the variant the defines select (exact filtered,
// exact fp64-only with PENUMBRA_AFH_FILTERED 0, or float with PENUMBRA_AFH_EXACT 0). `fallbacks`
// counts the filtered mode's double tests (unchanged otherwise). `scene_extent`: E, in double.
bool penumbraAfhBlocksLightCounted(vec3 a, vec3 b, vec3 c, vec3 p, vec4 light, float reach, penumbraAfhReal coplanar_epsilon,
                                   penumbraAfhReal offset, double scene_extent, inout uint fallbacks) {
#if PENUMBRA_AFH_EXACT && PENUMBRA_AFH_FILTERED
    return penumbraAfhBlocksFilteredCounted(a, b, c, p, light, reach, coplanar_epsilon, offset, scene_extent, fallbacks);
#else
    const penumbraAfhVec3 l = penumbraAfhLightPoint(penumbraAfhVec3(p), penumbraAfhVec3(light.xyz), penumbraAfhReal(reach),
                                                    light.w != 0.0);
#if PENUMBRA_AFH_EXACT
    const penumbraAfhReal extent = scene_extent;
#else
    const penumbraAfhReal extent = penumbraAfhFloatExtent(scene_extent);
#endif
    return penumbraAfhBlocks(penumbraAfhVec3(a), penumbraAfhVec3(b), penumbraAfhVec3(c), penumbraAfhVec3(p), l,
                             coplanar_epsilon, offset, extent);
#endif
}

bool penumbraAfhBlocksLight(vec3 a, vec3 b, vec3 c, vec3 p, vec4 light, float reach, penumbraAfhReal coplanar_epsilon,
                            penumbraAfhReal offset, double scene_extent) {
    uint fallbacks = 0u;
    return penumbraAfhBlocksLightCounted(a, b, c, p, light, reach, coplanar_epsilon, offset, scene_extent, fallbacks);
}

// The uncapped rule (the overloads without E; same bits as before E existed).
bool penumbraAfhBlocksLight(vec3 a, vec3 b, vec3 c, vec3 p, vec4 light, float reach, penumbraAfhReal coplanar_epsilon,
                            penumbraAfhReal offset) {
#if PENUMBRA_AFH_EXACT && PENUMBRA_AFH_FILTERED
    return penumbraAfhBlocksFiltered(a, b, c, p, light, reach, coplanar_epsilon, offset);
#else
    const penumbraAfhVec3 l = penumbraAfhLightPoint(penumbraAfhVec3(p), penumbraAfhVec3(light.xyz), penumbraAfhReal(reach),
                                                    light.w != 0.0);
    return penumbraAfhBlocks(penumbraAfhVec3(a), penumbraAfhVec3(b), penumbraAfhVec3(c), penumbraAfhVec3(p), l,
                             coplanar_epsilon, offset);
#endif
}

#endif
