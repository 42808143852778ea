// penumbra — small exact-geometry helpers shared by the CPU side of several blocks (the oracle and
// the CPU twins). GLSL twins live next to the shaders that use them.
#ifndef PENUMBRA_DETAIL_GEOMETRY_HPP
#define PENUMBRA_DETAIL_GEOMETRY_HPP

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

namespace penumbra::detail {

/// Squared distance from p to the closed triangle (a, b, c): closest point by Voronoi regions
/// (Ericson, Real-Time Collision Detection, 5.1.5). Zero-area triangles return |p - a|^2 when no
/// vertex or edge region applies. The GLSL twin is penumbraAfhPointTriangleDistance2
/// (shaders/penumbra/alias_free_hard/blocker_test.glsl): same operations, same order.
template <typename Real>
Real pointTriangleDistance2(const glm::tvec3<Real>& p, const glm::tvec3<Real>& a, const glm::tvec3<Real>& b,
                            const glm::tvec3<Real>& c) {
    // Everything relative to the vertices (p - a, p - b, ...): exact translations of the input
    // then give bit-identical distances, as the oracle's far-from-origin rule requires.
    using V = glm::tvec3<Real>;
    const V ab = b - a, ac = c - a, ap = p - a;
    const Real d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    V d;
    if (d1 <= 0 && d2 <= 0) {
        d = ap;
    } else {
        const V bp = p - b, cp = p - c;
        const Real d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp), d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
        const Real vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
        if (d3 >= 0 && d4 <= d3) {
            d = bp;
        } else if (d6 >= 0 && d5 <= d6) {
            d = cp;
        } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
            d = ap - ab * (d1 / (d1 - d3));
        } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
            d = ap - ac * (d2 / (d2 - d6));
        } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
            d = bp - (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
        } else {
            const Real denom = va + vb + vc;
            if (!(denom > 0)) return glm::dot(ap, ap);
            d = ap - ab * (vb / denom) - ac * (vc / denom);
        }
    }
    return glm::dot(d, d);
}

}  // namespace penumbra::detail

#endif
