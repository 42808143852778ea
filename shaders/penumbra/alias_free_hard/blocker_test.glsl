// penumbra — does triangle (a, b, c) block the open segment from view sample p to light point l?
// The per-sample test of sintorn2008 §3.2/§3.3 ("4 planes: 3 edges + support", BLOCKS.md core
// pipeline), written so that its exact mode decides like the double-precision oracle
// (include/penumbra/reference/visibility.hpp) on every pair the oracle does not flag as a tie:
//
//   n  = (b - a) x (c - a);  d_p = n.(p - a),  d_l = n.(l - a)        (supporting plane)
//   coplanar rule (oracle rule 2): ignore the triangle when p (or l) lies within eps * scale of
//       the triangle itself (plane distance |d_p| <= eps * scale * |n| checked first as a bound),
//       scale = max(|a - p|inf, |b - p|inf, |c - p|inf, |l - p|inf): a sample lying on a surface
//       is never shadowed by that surface or the neighbours it touches, with no depth bias, while
//       a grazing crossing of a neighbour near the terminator still counts;
//   p and l strictly on opposite sides (and |d_p| > offset * |n|, the optional sample offset);
//   edge planes through l: e_i = det(v_i - l, v_i+1 - l, p - l) all >= 0 or all <= 0, not all 0
//       (the line from l through p meets the closed triangle).
// With both: the segment crosses the plane strictly between p and l, inside the triangle.
//
// PENUMBRA_AFH_EXACT 1 (default): double precision, `precise` so no FMA contraction changes a
// sign; the host twin (penumbra::afhBlocks<double>) runs the same operations in the same order.
// PENUMBRA_AFH_EXACT 0: float, faster on hardware with slow fp64; its error against the oracle is
// measured by the tests and benchmarks. Callers pass positions already in the chosen type.
#ifndef PENUMBRA_AFH_BLOCKER_TEST_GLSL
#define PENUMBRA_AFH_BLOCKER_TEST_GLSL

#ifndef PENUMBRA_AFH_EXACT
#define PENUMBRA_AFH_EXACT 1
#endif

#if PENUMBRA_AFH_EXACT
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

bool penumbraAfhBlocks(penumbraAfhVec3 a, penumbraAfhVec3 b, penumbraAfhVec3 c, penumbraAfhVec3 p,
                       penumbraAfhVec3 l, penumbraAfhReal coplanar_epsilon, penumbraAfhReal offset) {
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
    precise penumbraAfhReal scale =
        max(max(penumbraAfhMaxAbs(a - p), penumbraAfhMaxAbs(b - p)), max(penumbraAfhMaxAbs(c - p), penumbraAfhMaxAbs(l - p)));
    precise penumbraAfhReal tol = coplanar_epsilon * scale;
    precise penumbraAfhReal threshold = tol * tol * nn;
    // Plane distance first (cheap lower bound), then the distance to the triangle itself.
    if (dp * dp <= threshold && penumbraAfhPointTriangleDistance2(p, a, b, c) <= tol * tol) return false;
    if (dl * dl <= threshold && penumbraAfhPointTriangleDistance2(l, a, b, c) <= tol * tol) return false;
    if (offset > 0.0 && dp * dp <= offset * offset * nn) return false;
    precise penumbraAfhVec3 la = a - l;
    precise penumbraAfhVec3 lb = b - l;
    precise penumbraAfhVec3 lc = c - l;
    precise penumbraAfhVec3 lp = p - l;
    penumbraAfhReal e0 = penumbraAfhDet(la, lb, lp);
    penumbraAfhReal e1 = penumbraAfhDet(lb, lc, lp);
    penumbraAfhReal e2 = penumbraAfhDet(lc, la, lp);
    bool all_nonnegative = e0 >= 0.0 && e1 >= 0.0 && e2 >= 0.0;
    bool all_nonpositive = e0 <= 0.0 && e1 <= 0.0 && e2 <= 0.0;
    bool all_zero = e0 == 0.0 && e1 == 0.0 && e2 == 0.0;
    return (all_nonnegative || all_nonpositive) && !all_zero;
}

#endif
