// penumbra — the degenerate-triangle rule of the hard-shadow light pass (one function, no hooks).
#ifndef PENUMBRA_AFH_DEGENERATE_GLSL
#define PENUMBRA_AFH_DEGENERATE_GLSL

// The one degenerate-triangle rule (penumbra::detail::degenerateTriangle, shared with the oracle
// and the CPU twin): |(v1 - v0) x (v2 - v0)| <= 1e-12 * (longest edge)^2, compared squared, in
// double. A degenerate triangle never blocks; the light pass culls it in the geometry stage.
bool penumbraAfhDegenerate(dvec3 v0, dvec3 v1, dvec3 v2) {
    precise dvec3 e0 = v1 - v0;
    precise dvec3 e1 = v2 - v1;
    precise dvec3 e2 = v0 - v2;
    precise dvec3 e02 = v2 - v0;
    precise double l0 = e0.x * e0.x + e0.y * e0.y;
    l0 = l0 + e0.z * e0.z;
    precise double l1 = e1.x * e1.x + e1.y * e1.y;
    l1 = l1 + e1.z * e1.z;
    precise double l2 = e2.x * e2.x + e2.y * e2.y;
    l2 = l2 + e2.z * e2.z;
    const double longest2 = max(l0, max(l1, l2));
    precise dvec3 n = dvec3(e0.y * e02.z - e02.y * e0.z, e0.z * e02.x - e02.z * e0.x, e0.x * e02.y - e02.x * e0.y);
    precise double nn = n.x * n.x + n.y * n.y;
    nn = nn + n.z * n.z;
    precise double limit = 1e-12LF * longest2;
    return nn <= limit * limit;
}

#endif
