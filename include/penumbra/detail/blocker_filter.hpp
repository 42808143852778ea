// penumbra — CPU model of the float filter in front of the exact blocker test
// (shaders/penumbra/alias_free_hard/blocker_test.glsl, penumbraAfhBlocksFilter). GL-free.
//
// Integration summary
//   needs:    GLM, IEEE-754 float arithmetic (SSE on x86-64, any AArch64); not valid under
//             -ffast-math. Every product that feeds an add is rounded on its own
//             (blockerFilterMul), so -ffp-contract=fast -march=native cannot fuse it.
//   produces: blockerFilter(): BlockerFilterState::False / True when the double test
//             (penumbraAfhBlocks / afhBlocks<double> on the same float inputs promoted to double)
//             certainly returns false / true, Uncertain otherwise; the same float operations in
//             the same order as the GLSL, so the GPU's state is this state bit for bit on a
//             driver with round-to-nearest float and no flushing. blockerFiltered() adds the
//             fallback; blockerLightPoint() is the one definition of the double light point.
//
// Why a filter. The exact mode runs the blocker test in double; consumer GPUs run fp64 at 1/32 to
// 1/64 of the float rate (some emulate it). Almost every (triangle, sample) pair is decided by
// signs that are far from zero, so a float evaluation with a proven forward error bound decides
// it, as robust geometric predicates do (Shewchuk 1997, "Adaptive Precision Floating-Point
// Arithmetic and Fast Robust Geometric Predicates", §4.2 static and semi-static filters).
//
// Structure of the decision. The double test returns true exactly when all of
//   (1) dp = n.(p - a) and dl = n.(l - a) have strictly opposite signs, n = (b - a) x (c - a);
//   (2) not (dp^2 <= (eps scale)^2 |n|^2 and dist(p, T)^2 <= (eps scale)^2)   (coplanar rule, p);
//   (3) the same for l;
//   (4) not (offset > 0 and dp^2 <= offset^2 |n|^2);
//   (5) e_i = det(v_i - l, v_i+1 - l, p - l) all >= 0 or all <= 0, not all 0, evaluated as
//       det(p - v_i, p - v_i+1, p - l) (relative to a far light the cross products cancel
//       ~|l|^2: wrong double signs a scene away from an edge at |l| ~ 1e7, issue 41);
// hold (its early returns all return false). The filter certifies conjuncts: one certainly false
// -> False, all certainly true -> True, otherwise Uncertain (then the double test runs).
//
// Certified sign. For a triple product x (dp, dl, e_i) let X be its exact value on the float
// inputs, x_f the float evaluation and x_d the double path's. With rounded differences, each of
// the 6 terms of the expansion passes through at most 8 roundings, so |x_f - X| <= gamma_8 P and
// |x_d - X| <= gamma_8 P, P the permanent (sum of |terms|), gamma_k = k u / (1 - k u). If
// |x_f| > B >= 2 gamma_8 P (+ terms below) then X, x_f and x_d have the same nonzero sign: the
// double comparisons (< 0, > 0, >= 0, == 0) all come out as the float ones say.
//   dp, dl: P = Q.|ap| and Q.|al|, Q_i = |ab_j||ac_k| + |ab_k||ac_j| (the permanent exactly);
//   e_i:    P <= 2 |u|inf |v|inf |w|1 (cheaper, at most 3x looser), u, v = p - v_i, w = p - l.
//   B = kRel P + A, kRel = 1.92e-6 >= 16 u (1 + 2^-8) (both paths, P's own rounding, slack).
// Coplanar rule (2)/(3): certified not to fire when |dp_f| > B + T, T >= eps scale |n|2 including
// the double path's rounding of tol, threshold and squares (|n|2 <= |n|1, |n_d|1 <= |n_f|1 +
// 2 gamma_4 sum Q); the distance to the triangle is then above eps scale too. Deciding that it
// fires needs the distance to the triangle in double: Uncertain. Samples lying on the caster's
// plane (its own triangle, coplanar neighbours) therefore always take the double path, and this
// is most of the fallback rate: the coplanar epsilon (1e-7) sits at float noise (1.2e-7).
// Offset (4): certified kept when |dp_f| > B + offset |n|1 (+ slack), rejected when
// (|dp_f| + B) < offset (|n_f|inf - error) (|n|2 >= |n|inf), Uncertain in between.
// Scene extent E (the coplanar scale caps |l - p| at E): the float scale takes
// min(|lp_f|inf + l_error, fl(min(E, 1e38)) + 1e-36), an upper bound of the double path's up to
// one rounding (inside the slack); 1e38 exceeds every difference the filter accepts.
// Directional lights: l_f = fl(p + fl(light * reach)) differs from the double path's l_d by at
// most l_error = 2.5e-7 (|t|inf + |l_f|inf) + 1e-36 per coordinate (both within 2u(1+5u) of the
// exact point); magnitudes are grown by l_error, dl moves by at most sum(Q) l_error and e_i,
// affine in l (e_0 = ((p - a) x (p - b)).(p - l)), by at most 6 m^2 l_error (24 m^2 charged).
//
// Assumptions (GLSL 4.50 §4.7.1 "Range and Precision", = ARB_shader_precision): float a + b,
// a - b, a * b correctly rounded in an undefined rounding mode -> unit u = 2^-23 (one ulp, any
// mode); denormals may be flushed on input and output -> an absolute error of 2^-124 per
// operation, propagated: A = 1.3e-35 (1 + m)^2 with m the largest difference; double operations
// only "at least as precise as single precision" -> the bound charges the double path the float
// unit too (it does not rely on fp64 being better); conversions correctly rounded; inputs finite.
// Every difference must stay below 1e12 (< 2^40, so no float overflow in degree-3 terms), else
// Uncertain. Under these assumptions the filtered verdict equals the fp64-only verdict on every
// input, on any conforming driver; the bit identity of float values between GPU and this model
// additionally needs round-to-nearest and no flushing (true on llvmpipe and desktop GPUs).
#ifndef PENUMBRA_DETAIL_BLOCKER_FILTER_HPP
#define PENUMBRA_DETAIL_BLOCKER_FILTER_HPP

#include "penumbra/detail/float_ops.hpp"

#include <glm/common.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace penumbra::detail {

/// PENUMBRA_AFH_FILTER_FALSE / _TRUE / _UNCERTAIN of blocker_test.glsl.
enum class BlockerFilterState : uint32_t { False = 0, True = 1, Uncertain = 2 };

// The GLSL constants (blocker_test.glsl, penumbraAfhFilter*), same float values.
inline constexpr float kBlockerFilterRel = 1.92e-6f;
inline constexpr float kBlockerFilterEdgeRel = 3.84e-6f;
inline constexpr float kBlockerFilterAbs = 1.3e-35f;
inline constexpr float kBlockerFilterSlack = 1.004f;
inline constexpr float kBlockerFilterNormalRel = 1.0e-6f;
inline constexpr float kBlockerFilterLightRel = 2.5e-7f;
inline constexpr float kBlockerFilterTiny = 1.0e-36f;
inline constexpr float kBlockerFilterMaxDifference = 1.0e12f;
inline constexpr double kBlockerFilterExtentClamp = 1.0e38;  // penumbraAfhFilterExtentClamp

/// a * b rounded on its own: opaque to the optimiser, so it cannot be contracted with a following
/// add into an FMA (GCC contracts across statements with -mfma / -march=native). The GLSL side
/// writes `precise` for the same reason.
template <typename Real>
inline Real blockerFilterMul(Real a, Real b) {
    return mulRounded(a, b);  // detail/float_ops.hpp
}

inline float blockerFilterMaxAbs(const glm::vec3& v) {
    return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
}

/// penumbraAfhFilterDet: (u x v) . w in float, same order as the double test's determinant.
inline float blockerFilterDet(const glm::vec3& u, const glm::vec3& v, const glm::vec3& w) {
    using detail::blockerFilterMul;
    const float cx = blockerFilterMul(u.y, v.z) - blockerFilterMul(u.z, v.y);
    const float cy = blockerFilterMul(u.z, v.x) - blockerFilterMul(u.x, v.z);
    const float cz = blockerFilterMul(u.x, v.y) - blockerFilterMul(u.y, v.x);
    return (blockerFilterMul(cx, w.x) + blockerFilterMul(cy, w.y)) + blockerFilterMul(cz, w.z);
}

inline int blockerFilterSign(float x, float bound) { return x > bound ? 1 : (x < -bound ? -1 : 0); }

/// What the filter computed (for tests: each certificate can be checked on its own).
struct BlockerFilterTrace {
    float dp = 0, dl = 0, b_dp = 0, b_dl = 0;
    int sp = 0, sl = 0;                     ///< certified signs of dp, dl (0 = uncertain / not reached)
    float e[3] = {0, 0, 0}, be[3] = {0, 0, 0};
    int se[3] = {0, 0, 0};                  ///< certified signs of e_i (0 = uncertain / not reached)
    bool edges_reached = false;
    bool coplanar_certified = false;        ///< rule (2) and (3) certainly do not fire
    int offset_certified = 0;               ///< +1 kept, -1 rejected, 0 uncertain / not reached
};

/// penumbraAfhBlocksFilter: see the header comment. `l` is the light point in float and l_error
/// bounds |l - l_double| per coordinate (0 for a point light: l_double = double(l)).
/// `scene_extent`: the double test's E (+inf = uncapped).
inline BlockerFilterState blockerFilter(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& p,
                                        const glm::vec3& l, float l_error, double coplanar_epsilon, double offset,
                                        double scene_extent = std::numeric_limits<double>::infinity(),
                                        BlockerFilterTrace* trace = nullptr) {
    using detail::blockerFilterMul;
    BlockerFilterTrace local;
    BlockerFilterTrace& t = trace ? *trace : local;
    t = BlockerFilterTrace{};
    const auto mul = [](float x, float y) { return blockerFilterMul(x, y); };
    const glm::vec3 ab = b - a, ac = c - a, ap = p - a, al = l - a;
    const float nx = mul(ab.y, ac.z) - mul(ab.z, ac.y);
    const float ny = mul(ab.z, ac.x) - mul(ab.x, ac.z);
    const float nz = mul(ab.x, ac.y) - mul(ab.y, ac.x);
    const float dp = (mul(nx, ap.x) + mul(ny, ap.y)) + mul(nz, ap.z);
    const float dl = (mul(nx, al.x) + mul(ny, al.y)) + mul(nz, al.z);
    const glm::vec3 mab = glm::abs(ab), mac = glm::abs(ac);
    const glm::vec3 mal = glm::abs(al) + glm::vec3(l_error);
    const glm::vec3 q(mul(mab.y, mac.z) + mul(mab.z, mac.y), mul(mab.z, mac.x) + mul(mab.x, mac.z),
                      mul(mab.x, mac.y) + mul(mab.y, mac.x));
    const float q_sum = (q.x + q.y) + q.z;
    const float m_plane = std::max(std::max(std::max(mab.x, std::max(mab.y, mab.z)), std::max(mac.x, std::max(mac.y, mac.z))),
                                   std::max(blockerFilterMaxAbs(ap), std::max(mal.x, std::max(mal.y, mal.z))));
    const float abs_plane = kBlockerFilterAbs * mul(1.0f + m_plane, 1.0f + m_plane);
    const glm::vec3 map = glm::abs(ap);
    const float b_dp = mul(kBlockerFilterRel, (mul(q.x, map.x) + mul(q.y, map.y)) + mul(q.z, map.z)) + abs_plane;
    const float b_dl = (mul(kBlockerFilterRel, (mul(q.x, mal.x) + mul(q.y, mal.y)) + mul(q.z, mal.z)) +
                        mul(mul(kBlockerFilterSlack, q_sum), l_error)) +
                       abs_plane;
    t.dp = dp;
    t.dl = dl;
    t.b_dp = b_dp;
    t.b_dl = b_dl;
    if (!(m_plane <= kBlockerFilterMaxDifference)) return BlockerFilterState::Uncertain;
    const int sp = blockerFilterSign(dp, b_dp), sl = blockerFilterSign(dl, b_dl);
    t.sp = sp;
    t.sl = sl;
    if (sp * sl > 0) return BlockerFilterState::False;

    const glm::vec3 bp = p - b, cp = p - c, lp = p - l;  // e_i taken at p, as the double test
    const float e0 = blockerFilterDet(ap, bp, lp), e1 = blockerFilterDet(bp, cp, lp), e2 = blockerFilterDet(cp, ap, lp);
    const float ma = blockerFilterMaxAbs(ap);
    const float mb = blockerFilterMaxAbs(bp);
    const float mc = blockerFilterMaxAbs(cp);
    const glm::vec3 mlp = glm::abs(lp);
    const float lp1 = ((mlp.x + mlp.y) + mlp.z) + mul(3.0f, l_error);
    const float m_edge = std::max(std::max(ma, mb), std::max(mc, std::max(mlp.x, std::max(mlp.y, mlp.z)) + l_error));
    t.edges_reached = true;
    if (!(m_edge <= kBlockerFilterMaxDifference)) return BlockerFilterState::Uncertain;
    const float abs_edge = mul(kBlockerFilterAbs, mul(1.0f + m_edge, 1.0f + m_edge)) + mul(mul(24.2f, mul(m_edge, m_edge)), l_error);
    const float be0 = mul(kBlockerFilterEdgeRel, mul(mul(ma, mb), lp1)) + abs_edge;
    const float be1 = mul(kBlockerFilterEdgeRel, mul(mul(mb, mc), lp1)) + abs_edge;
    const float be2 = mul(kBlockerFilterEdgeRel, mul(mul(mc, ma), lp1)) + abs_edge;
    const int s0 = blockerFilterSign(e0, be0), s1 = blockerFilterSign(e1, be1), s2 = blockerFilterSign(e2, be2);
    t.e[0] = e0, t.e[1] = e1, t.e[2] = e2;
    t.be[0] = be0, t.be[1] = be1, t.be[2] = be2;
    t.se[0] = s0, t.se[1] = s1, t.se[2] = s2;
    if (std::min(s0, std::min(s1, s2)) < 0 && std::max(s0, std::max(s1, s2)) > 0) return BlockerFilterState::False;
    if (sp == 0 || sl == 0 || s0 == 0 || s1 == 0 || s2 == 0) return BlockerFilterState::Uncertain;

    const float extent_up = static_cast<float>(std::min(scene_extent, kBlockerFilterExtentClamp)) + kBlockerFilterTiny;
    const float segment = std::min(std::max(mlp.x, std::max(mlp.y, mlp.z)) + l_error, extent_up);
    const float scale = std::max(std::max(blockerFilterMaxAbs(ap), blockerFilterMaxAbs(bp)),
                                 std::max(blockerFilterMaxAbs(cp), segment));
    const float n1 = (((std::abs(nx) + std::abs(ny)) + std::abs(nz)) + mul(kBlockerFilterNormalRel, q_sum)) + abs_plane;
    const float eps_up = static_cast<float>(coplanar_epsilon) + kBlockerFilterTiny;
    const float tol_n = mul(kBlockerFilterSlack, mul(mul(eps_up, scale), n1)) + abs_plane;
    if (!(std::abs(dp) > b_dp + tol_n && std::abs(dl) > b_dl + tol_n)) return BlockerFilterState::Uncertain;
    t.coplanar_certified = true;

    if (offset > 0.0) {
        const float offset_f = static_cast<float>(offset);
        if (!(offset_f <= kBlockerFilterMaxDifference)) return BlockerFilterState::Uncertain;
        const float keep = mul(kBlockerFilterSlack, mul(offset_f + kBlockerFilterTiny, n1)) + abs_plane;
        if (std::abs(dp) > b_dp + keep) {
            t.offset_certified = 1;
            return BlockerFilterState::True;
        }
        const float n_inf = std::max(std::abs(nx), std::max(std::abs(ny), std::abs(nz))) -
                            (mul(kBlockerFilterNormalRel, q_sum) + abs_plane);
        const float reject = mul(mul(0.98f, offset_f), n_inf);
        if (mul(kBlockerFilterSlack, std::abs(dp) + b_dp) < reject) {
            t.offset_certified = -1;
            return BlockerFilterState::False;
        }
        return BlockerFilterState::Uncertain;
    }
    return BlockerFilterState::True;
}

/// penumbraAfhLightPoint in double: the point light itself, or p + light * reach (no FMA).
inline glm::dvec3 blockerLightPoint(const glm::dvec3& p, const glm::dvec3& light, double reach, bool point_light) {
    if (point_light) return light;
    return glm::dvec3(p.x + blockerFilterMul(light.x, reach), p.y + blockerFilterMul(light.y, reach),
                      p.z + blockerFilterMul(light.z, reach));
}

/// The float light point and its l_error of penumbraAfhBlocksFiltered (light.w != 0: point).
inline void blockerFilterLightPoint(const glm::vec3& p, const glm::vec4& light, float reach, glm::vec3& l, float& l_error) {
    if (light.w != 0.0f) {
        l = glm::vec3(light);
        l_error = 0.0f;
        return;
    }
    const glm::vec3 t(blockerFilterMul(light.x, reach), blockerFilterMul(light.y, reach), blockerFilterMul(light.z, reach));
    l = p + t;
    l_error = blockerFilterMul(kBlockerFilterLightRel, blockerFilterMaxAbs(t) + blockerFilterMaxAbs(l)) + kBlockerFilterTiny;
}

/// penumbraAfhBlocksFiltered: the filter, then `exact(a, b, c, p, l_double, eps, offset,
/// scene_extent)` (the double test, e.g. penumbra::afhBlocks<double>) where it is uncertain.
/// `state` (optional) receives the filter's state.
template <typename ExactTest>
bool blockerFiltered(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c, const glm::vec3& p, const glm::vec4& light,
                     float reach, double coplanar_epsilon, double offset, double scene_extent, ExactTest&& exact,
                     BlockerFilterState* state = nullptr) {
    glm::vec3 l;
    float l_error;
    blockerFilterLightPoint(p, light, reach, l, l_error);
    const BlockerFilterState s = blockerFilter(a, b, c, p, l, l_error, coplanar_epsilon, offset, scene_extent);
    if (state) *state = s;
    if (s != BlockerFilterState::Uncertain) return s == BlockerFilterState::True;
    const bool point_light = light.w != 0.0f;
    return exact(glm::dvec3(a), glm::dvec3(b), glm::dvec3(c), glm::dvec3(p),
                 blockerLightPoint(glm::dvec3(p), glm::dvec3(glm::vec3(light)), double(reach), point_light),
                 coplanar_epsilon, offset, scene_extent);
}

}  // namespace penumbra::detail

#endif
