// penumbra — sample-based soft shadows, SoftSkips::wedges: GLSL twin of detail::soft::wedgePlanes,
// wedgeProven and wedgeRejects (include/penumbra/pipelines/sample_based_soft.hpp), step for step.
// Per caster T up to four planes F(x) = n . x + d with float n, d, each proven (in double, with the
// float coefficients and bounded rounding) to hold T's vertices on its closed positive side and the
// light's bounding sphere strictly on its negative side: the three planes through T's edges
// tangent to the sphere grown by 4 delta, shifted delta towards the light, and T's own plane.
// Every point of a blocked segment lies on T's side of each, so a view sample beyond one by the
// margin has nothing to do with T (nor does any rule of the oracle reach it). (0, 0, 0, 1) where
// no plane is proven: it never rejects. The geometry stage builds them (fp64; real GPUs' sqrt and
// division may round worse than IEEE: the proof allows 64 eps for the norm), the fragment stage
// and the compute passes test view samples in float (its error is at most 4 ulp of the terms'
// magnitude on any driver, FMA or not; the test allows 1e-6 of it).
// Needs caster_plane.glsl's fp64 helpers.
#ifndef PENUMBRA_SBS_WEDGES_GLSL
#define PENUMBRA_SBS_WEDGES_GLSL

struct PenumbraSbsWedges {
    vec4 planes[4];
    vec2 margin;  // x: 2 mu S (rounded up), y: S (T's vertices and the light lie in [-S, S]^3)
};

// 4 max(tie, coplanar epsilon) + 2^-21 (detail::soft::wedgeMu).
double penumbraSbsWedgeMu(double eps) { return 4.0LF * eps + 4.76837158203125e-7LF; }

bool penumbraSbsWedgeProven(vec4 plane, dvec3 v[3], dvec3 centre, double reach) {
    const dvec3 n = dvec3(plane.xyz);
    const double d = double(plane.w);
    for (int i = 0; i < 3; ++i) {
        const dvec3 x = v[i];
        precise double f = ((n.x * x.x + n.y * x.y) + n.z * x.z) + d;
        precise double size = abs(n.x * x.x) + abs(n.y * x.y) + abs(n.z * x.z) + abs(d);
        if (!(f - 4.0LF * kPenumbraSbsEpsilon * size >= 0.0LF)) return false;
    }
    precise double f = ((n.x * centre.x + n.y * centre.y) + n.z * centre.z) + d;
    precise double size = abs(n.x * centre.x) + abs(n.y * centre.y) + abs(n.z * centre.z) + abs(d);
    precise double len = sqrt(n.x * n.x + n.y * n.y + n.z * n.z) * (1.0LF + 64.0LF * kPenumbraSbsEpsilon);
    precise double top = f + reach * len * (1.0LF + 8.0LF * kPenumbraSbsEpsilon) + 8.0LF * kPenumbraSbsEpsilon * size;
    return top < 0.0LF;
}

PenumbraSbsWedges penumbraSbsWedgePlanes(dvec3 v0, dvec3 v1, dvec3 v2, dvec3 centre, double reach, double eps) {
    dvec3 v[3] = dvec3[3](v0, v1, v2);
    const double scene = max(max(penumbraSbsMaxAbs(v0), penumbraSbsMaxAbs(v1)), max(penumbraSbsMaxAbs(v2), penumbraSbsMaxAbs(centre) + reach));
    const double mu = penumbraSbsWedgeMu(eps);
    precise double delta = 2.0LF * mu * scene;
    precise double grown = reach + 4.0LF * delta;
    PenumbraSbsWedges w;
    for (int i = 0; i < 4; ++i) w.planes[i] = vec4(0.0, 0.0, 0.0, 1.0);
    w.margin = vec2(float(2.0LF * mu * scene * 1.001LF), float(scene));
    for (int e = 0; e < 3; ++e) {
        const dvec3 a = v[e], b = v[(e + 1) % 3], o = v[(e + 2) % 3];
        const double len = penumbraSbsLength(b - a);
        if (!(len > 0.0LF)) continue;
        precise dvec3 u = (b - a) / len;
        // In the plane across the edge: the sphere's centre at distance D, the opposite vertex.
        const dvec3 ca = centre - a, oa = o - a;
        precise dvec3 w_c = ca - penumbraSbsDot(ca, u) * u;
        precise dvec3 w_o = oa - penumbraSbsDot(oa, u) * u;
        const double distance = penumbraSbsLength(w_c);
        if (!(distance > grown * (1.0LF + 1e-6LF))) continue;  // the edge's line meets the grown sphere
        precise dvec3 across = w_c / distance;
        const dvec3 side = penumbraSbsCross(u, across);
        precise double alpha = -grown / distance;
        const double beta = sqrt(max(0.0LF, 1.0LF - alpha * alpha));
        precise dvec3 m = alpha * across + (penumbraSbsDot(side, w_o) < 0.0LF ? -beta : beta) * side;
        precise double d = delta - penumbraSbsDot(m, a);
        const vec4 plane = vec4(vec3(m), float(d));
        if (penumbraSbsWedgeProven(plane, v, centre, reach)) w.planes[e] = plane;
    }
    const dvec3 normal = penumbraSbsCross(v1 - v0, v2 - v0);
    const double len = penumbraSbsLength(normal);
    if (len > 0.0LF) {
        precise dvec3 unit = normal / len;
        if (penumbraSbsDot(unit, centre - v0) > 0.0LF) unit = -unit;
        precise double d = delta - penumbraSbsDot(unit, v0);
        const vec4 plane = vec4(vec3(unit), float(d));
        if (penumbraSbsWedgeProven(plane, v, centre, reach)) w.planes[3] = plane;
    }
    return w;
}

// View sample p beyond one of the planes by more than the margin (receivers beyond 4 S are kept).
// mu2 = float(2 mu * 1.001) (detail::soft::wedgeMu2, set up on the host: params reserved.z).
bool penumbraSbsWedgeRejects(PenumbraSbsWedges w, vec3 p, float mu2) {
    const vec3 ap = abs(p);
    const float size = max(ap.x, max(ap.y, ap.z));
    if (!(size <= 4.0 * w.margin.y)) return false;
    const float margin = max(w.margin.x, mu2 * size);
    bool rejects = false;
    for (int i = 0; i < 4; ++i) {
        const vec4 q = w.planes[i];
        const float f = ((q.x * p.x + q.y * p.y) + q.z * p.z) + q.w;
        const float e = ((abs(q.x * p.x) + abs(q.y * p.y)) + abs(q.z * p.z)) + abs(q.w);
        rejects = rejects || f < -(margin + 1e-6 * e);
    }
    return rejects;
}

#endif
