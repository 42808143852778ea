// penumbra — small exact-geometry helpers shared by the CPU side of several blocks (the oracle and
// the CPU twins). GLSL twins live next to the shaders that use them.
#ifndef PENUMBRA_DETAIL_GEOMETRY_HPP
#define PENUMBRA_DETAIL_GEOMETRY_HPP

#include "penumbra/detail/float_ops.hpp"

#include <glm/geometric.hpp>
#include <algorithm>
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
    // Products are opaque (detail/float_ops.hpp): no FMA contraction on any compiler flags.
    using V = glm::tvec3<Real>;
    const V ab = b - a, ac = c - a, ap = p - a;
    const Real d1 = dotRounded(ab, ap), d2 = dotRounded(ac, ap);
    V d;
    if (d1 <= 0 && d2 <= 0) {
        d = ap;
    } else {
        const V bp = p - b, cp = p - c;
        const Real d3 = dotRounded(ab, bp), d4 = dotRounded(ac, bp), d5 = dotRounded(ab, cp), d6 = dotRounded(ac, cp);
        const Real vc = mulRounded(d1, d4) - mulRounded(d3, d2), vb = mulRounded(d5, d2) - mulRounded(d1, d6),
                   va = mulRounded(d3, d6) - mulRounded(d5, d4);
        if (d3 >= 0 && d4 <= d3) {
            d = bp;
        } else if (d6 >= 0 && d5 <= d6) {
            d = cp;
        } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
            d = ap - mulRounded(ab, d1 / (d1 - d3));
        } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
            d = ap - mulRounded(ac, d2 / (d2 - d6));
        } else if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
            d = bp - mulRounded(V(c - b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
        } else {
            const Real denom = va + vb + vc;
            if (!(denom > 0)) return dotRounded(ap, ap);
            d = ap - mulRounded(ab, vb / denom) - mulRounded(ac, vc / denom);
        }
    }
    return dotRounded(d, d);
}

/// The one degenerate-triangle rule of the oracle, the CPU twins and the GPU
/// (penumbraAfhDegenerate in blocker_test.glsl): |(v1 - v0) x (v2 - v0)| <= 1e-12 * (longest
/// edge)^2, compared squared, in double, products opaque. A degenerate triangle never blocks and is
/// never a tie (the oracle drops it at construction; the light pass culls it in its geometry stage).
inline constexpr double kDegenerateRelativeArea = 1e-12;

inline bool degenerateTriangle(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2) {
    const glm::dvec3 e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2, e02 = v2 - v0;
    const double longest2 = std::max(dotRounded(e0, e0), std::max(dotRounded(e1, e1), dotRounded(e2, e2)));
    const glm::dvec3 n(mulRounded(e0.y, e02.z) - mulRounded(e02.y, e0.z), mulRounded(e0.z, e02.x) - mulRounded(e02.z, e0.x),
                       mulRounded(e0.x, e02.y) - mulRounded(e02.x, e0.y));
    const double limit = mulRounded(kDegenerateRelativeArea, longest2);
    return dotRounded(n, n) <= mulRounded(limit, limit);
}

}  // namespace penumbra::detail

#endif
