// penumbra/reference/visibility.hpp — the exact double-precision visibility oracle.
//
// Integration summary
//   Needs:    a triangle list (positions as glm::dvec3 or glm::vec3, uint32 indices, 3 per
//             triangle), receiver points and light samples (penumbra/light_samples.hpp gives
//             deterministic sets: LightSampleSets::world, or reference/light_samples.hpp's). Header-only: GLM, the C++17 standard library, std::thread.
//             No GPU, no GL; requires IEEE-754 double arithmetic (SSE2 on x86, any 64-bit ARM);
//             not valid under -ffast-math.
//   Produces: for every (receiver, light sample) pair one "blocked" bit and one "tie" bit, packed
//             32 per word (VisibilityResult), plus closest hits for the demo renderer's primary
//             rays. Every exact GPU mode is tested against these bits on the same light samples;
//             approximate modes report their distance to them (BLOCKS.md "The oracle"). Compare
//             float modes only on pairs whose tie bit is clear.
//   Hooks:    none. Built once (binned-SAH BVH in the constructor), then const and thread-safe.
//
//   Typical use (a GPU mode's test):
//       penumbra::reference::VisibilityOracle oracle(positions, indices);
//       const auto samples = penumbra::reference::sphereLightSamples(centre, radius, 128, seed);
//       const auto expected = oracle.evaluate(receivers, samples);
//       // word w of receiver r: compare (gpu ^ expected.blocked[i]) & ~expected.ties[i] == 0,
//       // with i = r * expected.words_per_receiver + w.
//
// ---------------------------------------------------------------------------------------------
// Semantics of one pair (receiver p, light sample s)
//
// The pair is BLOCKED when the OPEN segment (p, s) crosses a triangle: ray p + t (s - p), crossing
// accepted for 0 < t < 1 (both endpoints excluded). Each non-degenerate triangle T is classified
// as follows, all in double precision:
//
//  1. Watertight test (Woop, Benthin, Wald 2013, "Watertight Ray/Triangle Intersection", JCGT
//     2(1)): translate to p, permute so the ray's dominant axis is z, shear the vertices so the ray
//     becomes the z axis, evaluate the three 2D edge functions. Their SIGNS are exact for the
//     sheared coordinates (error-free products with std::fma break the rare p1 == p2 case, the
//     paper's "fall back to higher precision"). The sheared coordinates of a vertex depend only on
//     the vertex and the ray, so two triangles sharing an edge see exactly opposite edge
//     functions: a line through a shared edge or vertex is inside at least one of them. Edges
//     never leak, whatever the compiler's contraction settings, and the bits do not depend on
//     them either: no product is fused into an FMA (detail::oracle::mul; checked by
//     tests/twin_digest.cpp under -march=native -ffp-contract=fast). Exception still open: the
//     coplanar rule's penumbra::detail::pointTriangleDistance2 (detail/geometry.hpp) contracts.
//     "The line passes through T" = all edge functions >= 0 or all <= 0, not all == 0. Then
//     t = T / det as in the paper, and hit(T) = 0 < t < 1.
//  2. Coplanar rule. Let n = (v1 - v0) x (v2 - v0) and
//         scale = max(|v0 - p|_inf, |v1 - p|_inf, |v2 - p|_inf, min(|s - p|_inf, E)),
//     E = sceneExtent() (|hi - lo|_inf of the mesh's box). Rounding scales with the triangle's
//     distance, not the segment's length: capped at E, a far light keeps the scene's tolerances up
//     to the 1e50 coordinate bound (uncapped, a light at 1e10 ignored every triangle; issue 41).
//     If the distance from p to the closed triangle T itself is <= coplanar_epsilon * scale, T is
//     IGNORED for this pair (no hit, no tie), and likewise for the distance from s. In exact
//     arithmetic a triangle containing p (or s) can only touch the segment at that endpoint, which
//     is excluded anyway, so the rule only removes rounding noise: a receiver lying on a surface
//     is never shadowed by the triangle it lies on nor by the neighbours whose edges or vertices
//     it lies on, and light samples lying on an emitter that is part of the mesh are not blocked
//     by it. The distance is to the TRIANGLE, not to its plane: near a terminator a receiver can
//     be within rounding of a neighbour's plane while the segment, at a grazing angle, meets that
//     neighbour far away; that crossing is real and counts. (The plane distance, a lower bound, is
//     checked first.) A receiver on a surface whose light is BEHIND that surface is therefore not
//     blocked by the surface itself; light-back-facing shading darkens it anyway (BLOCKS.md
//     §3.3/§4.3).
//  3. Ties. T is FRAGILE for the pair when any of:
//       a) the line passes through T and |t| <= t_eps or |t - 1| <= t_eps, where
//          t_eps = tie_epsilon * min(1, scale / |s - p|_inf) (tie_epsilon * scale along the ray);
//       b) the line passes within tie_epsilon * scale of an edge of T (end vertices included),
//          at a ray parameter in [-t_eps, 1 + t_eps]. The distance is measured in the
//          sheared frame, i.e. in the plane perpendicular to the ray's dominant axis: between 1
//          and sqrt(3) times the Euclidean distance from the edge point to the line;
//       c) the line passes through T but the plane-side test (signs of n.(v0 - p), n.(v0 - s))
//          disagrees with hit(T): the crossing is so grazing that t cannot be trusted.
//  4. Locality. T only counts (hit or fragile) when its bounding box, grown on every side by
//     (4 * tie_epsilon + 1e-12) * max(|box corner - p|_inf, min(|s - p|_inf, E)), touches the closed
//     segment [p, s] (slab test). In exact arithmetic this never removes a hit or a tie; it pins
//     down the numerically meaningless grazing cases, which is what makes the BVH and the brute-
//     force loop agree bit for bit.
//
//   blocked(p, s) = some T has hit(T).
//   tie(p, s)     = no T has (hit and not fragile), and some T is fragile.
//   A pair with one robust hit is blocked and not a tie, whatever else grazes it. On generic
//   inputs ties are rare (probability ~ tie_epsilon per triangle near the segment).
//   p == s (empty segment) is never blocked and never a tie.
//
// Closest hits (closestHit, for primary rays): the same watertight test and the same triangle
// ids, accepting t_min < t < t_max; the smallest t wins, equal t go to the smallest triangle id.
// No coplanar rule and no ties. A triangle whose plane contains the ray direction
// (|n.d| <= 1e-12 |n| |d|: edge-on) is not hit, and the hit's t must lie in the slab interval of
// the triangle's box grown by 1e-12 of its scale (rule 4's closest-hit form). u and v are the
// barycentric weights of v1 and v2.
//
// Degenerate triangles (penumbra::detail::degenerateTriangle, the rule the CPU twins and the GPU
// light pass share): a triangle with |(v1 - v0) x (v2 - v0)| <= 1e-12 * (longest edge)^2 (compared squared)
// (zero area, repeated or collinear vertices, or slivers thinner than 1e-12 of their length) is
// dropped at construction: it never blocks and is never a tie. degenerateTriangleCount() tells
// how many. Triangle ids (Hit::triangle) always refer to the caller's triangle list.
//
// Far from the origin: all tests work on coordinates relative to the receiver (ray origin), so
// translating the whole input by an offset whose sums are exactly representable (e.g. dyadic
// coordinates) gives bit-identical results. Otherwise the input rounding moves geometry by up to
// ulp(offset)/2; pairs can then flip only within that distance of a decision boundary, which is
// caught as a tie when tie_epsilon * scale >= a few ulp(offset) (e.g. 1e-9 is enough for a scene
// of size >= 1 at 1e5, use 1e-7 for size 1 at 1e7), and on-surface receivers stay unblocked when
// coplanar_epsilon * scale is above the same bound.
//
// Bad input (penumbra::Error, message naming the index/value):
//   - positions[i] not finite, or |coordinate| > 1e50 (kept away from overflow) -> throws;
//     every position is checked, even unreferenced ones;
//   - indices[k] >= positions.size() -> throws; indices.size() % 3 != 0 -> throws;
//     more than 2^32 - 1 triangles -> throws;
//   - empty mesh (no indices) is valid: nothing ever blocks;
//   - receivers[i] / light_samples[i] (evaluate), receiver / light_sample (segmentBlocked),
//     origin / direction (closestHit) not finite or beyond 1e50 -> throws;
//   - closestHit: zero direction, NaN t_min/t_max or t_min >= t_max -> throws;
//   - options: tie_epsilon or coplanar_epsilon outside [0, 0.1] or NaN -> throws;
//   - more than 2^32 - 1 light samples -> throws. Empty receiver or sample lists are valid
//     (empty result; visibleFraction() of a receiver with zero samples is 1).
//
// Threads: evaluate() splits receivers into chunks handed out dynamically to std::threads; each
// pair is computed independently and written to its own receiver's words, so the bits (and the
// work counters) do not depend on the thread count.
#ifndef PENUMBRA_REFERENCE_VISIBILITY_HPP
#define PENUMBRA_REFERENCE_VISIBILITY_HPP

#include <penumbra/detail/geometry.hpp>
#include <penumbra/error.hpp>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <thread>
#include <utility>
#include <vector>

namespace penumbra {
namespace reference {

/// Closest intersection of a ray. The hit point is (1 - u - v) * v0 + u * v1 + v * v2 of the
/// caller's triangle `triangle` (its index in the index list / 3), at origin + t * direction.
struct Hit {
    bool hit = false;
    double t = 0;
    uint32_t triangle = 0;
    double u = 0, v = 0;
};

/// Value-initialised = defaults.
struct VisibilityOptions {
    unsigned threads = 0;            ///< 0 = std::thread::hardware_concurrency(); capped by the work.
    double tie_epsilon = 1e-9;       ///< relative tie tolerance (see the header comment, rule 3); [0, 0.1].
    double coplanar_epsilon = 1e-9;  ///< relative plane distance of the coplanar rule (rule 2); [0, 0.1].
};

/// Bits of evaluate(): bit (s % 32) of word [r * words_per_receiver + s / 32] is pair (r, s).
/// Unused high bits of each receiver's last word are zero.
struct VisibilityResult {
    size_t receivers = 0, samples = 0;
    uint32_t words_per_receiver = 0;  ///< ceil(samples / 32)
    std::vector<uint32_t> blocked;    ///< receivers * words_per_receiver words
    std::vector<uint32_t> ties;       ///< same layout: the pair's decision is numerically fragile
    uint64_t tie_count = 0;           ///< number of set tie bits
    // Device-independent work counters (deterministic, independent of the thread count).
    uint64_t nodes_visited = 0;   ///< BVH node bounds tested (0 for brute force)
    uint64_t triangle_tests = 0;  ///< triangle classifications (early exit on the first robust hit)

    bool isBlocked(size_t r, size_t s) const { return bit(blocked, r, s); }
    bool isTie(size_t r, size_t s) const { return bit(ties, r, s); }
    uint32_t blockedCount(size_t r) const;
    /// 1 - blockedCount(r) / samples; 1 when there are no samples.
    double visibleFraction(size_t r) const;

private:
    bool bit(const std::vector<uint32_t>& words, size_t r, size_t s) const {
        PENUMBRA_ASSERT(r < receivers && s < samples);
        return (words[r * words_per_receiver + s / 32] >> (s % 32)) & 1u;
    }
};

}  // namespace reference

namespace detail {
namespace oracle {

inline constexpr double kBoxSlack = 1e-12;                // >> the ~20 ulp error of one test
inline constexpr double kParallelRay = 1e-12;             // closest hit: |n.d| <= k |n| |d| -> edge-on
inline constexpr double kMaxCoordinate = 1e50;            // squares of squares stay finite
inline constexpr double kMaxEpsilon = 0.1;
inline constexpr uint32_t kBinCount = 16;
inline constexpr uint32_t kMaxLeafSize = 8;
inline constexpr int kMaxDepth = 56;
inline constexpr int kStackSize = 64;    // one push per level: kMaxDepth + 1 suffices
inline constexpr double kTraversalCost = 1.0;  // SAH: node visit vs. one triangle test
inline constexpr size_t kReceiversPerChunkMin = 1;

struct Triangle {
    glm::dvec3 v0, v1, v2;
    uint32_t index;  // in the caller's triangle list
};

struct Node {
    glm::dvec3 lo;
    uint32_t first;  // leaf: first triangle; interior: left child (right child = first + 1)
    glm::dvec3 hi;
    uint32_t count;  // 0 = interior
};

struct Verdict {
    bool hit = false;
    bool fragile = false;
    double t = 0;  // the crossing's ray parameter when the line passes through T (reference/transmittance.hpp sorts by it)
};

struct Counters {
    uint64_t nodes = 0;
    uint64_t tests = 0;
};

inline double maxAbs(const glm::dvec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

inline bool finiteBounded(const glm::dvec3& v) {
    // NaN fails every comparison, so this also rejects NaN.
    return std::fabs(v.x) <= kMaxCoordinate && std::fabs(v.y) <= kMaxCoordinate && std::fabs(v.z) <= kMaxCoordinate;
}

inline uint32_t popcount32(uint32_t x) {
    x = x - ((x >> 1) & 0x55555555u);
    x = (x & 0x33333333u) + ((x >> 2) & 0x33333333u);
    return (((x + (x >> 4)) & 0x0f0f0f0fu) * 0x01010101u) >> 24;
}

// No FMA contraction. GCC contracts a * b + c into an FMA whenever the target has one
// (-ffp-contract=fast is its default outside strict ISO mode, e.g. with -march=native / -mfma), and
// clang does within an expression: the oracle's bits would then depend on compiler flags. Every
// product whose result feeds an addition goes through mul(), whose empty asm makes the rounded
// product opaque to the optimiser (the same device as sample_lists.hpp's mulRounded). dot3, cross3
// and length3 are glm::dot / glm::cross / glm::length with the same operation order, so the bits
// without FMA are unchanged. tests/twin_digest.cpp checks the oracle's outputs under
// -O3 -march=native -ffp-contract=fast. (The BVH's SAH costs are left alone: the tree shape may
// change with contraction, the verdicts cannot — they equal the brute-force loop's.)
inline double mul(double a, double b) {
    double r = a * b;
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    __asm__("" : "+x"(r));
#elif defined(__GNUC__) && defined(__aarch64__)
    __asm__("" : "+w"(r));
#elif defined(__GNUC__)
    __asm__("" : "+g"(r));
#endif
    return r;
}

inline double dot3(const glm::dvec3& a, const glm::dvec3& b) { return (mul(a.x, b.x) + mul(a.y, b.y)) + mul(a.z, b.z); }

inline glm::dvec3 cross3(const glm::dvec3& x, const glm::dvec3& y) {
    return {mul(x.y, y.z) - mul(y.y, x.z), mul(x.z, y.x) - mul(y.z, x.x), mul(x.x, y.y) - mul(y.x, x.y)};
}

inline double length3(const glm::dvec3& v) { return std::sqrt(dot3(v, v)); }

/// a.x * b.y - a.y * b.x with the exact sign (and exact zero) of the real value. When the two
/// rounded products differ, monotone rounding already orders the exact products; when they are
/// equal, their exact rounding errors (std::fma) decide. Antisymmetric in sign: swapping a and b
/// negates the result's sign exactly, which is the watertightness argument of Woop et al. §3.
inline double cross2(double ax, double ay, double bx, double by) {
    const double p1 = mul(ax, by);
    const double p2 = mul(ay, bx);
    if (p1 != p2) return p1 - p2;
    return std::fma(ax, by, -p1) - std::fma(ay, bx, -p2);
}

/// A ray prepared for the Woop-Benthin-Wald test and for slab tests.
struct Ray {
    glm::dvec3 origin{0.0};
    glm::dvec3 end{0.0};  // origin + dir for segments (the light sample, exactly as given)
    glm::dvec3 dir{0.0};
    glm::dvec3 inv{0.0};  // 1 / dir, 0 on zero axes
    bool zero_axis[3] = {false, false, false};
    int kx = 0, ky = 1, kz = 2;
    double sx = 0, sy = 0, sz = 0;
    double dir_scale = 0;  // |dir|_inf
};

/// `dir` must be non-zero.
inline Ray makeRay(const glm::dvec3& origin, const glm::dvec3& dir) {
    Ray ray;
    ray.origin = origin;
    ray.dir = dir;
    ray.end = origin + dir;
    int kz = 0;
    if (std::fabs(dir.y) > std::fabs(dir[kz])) kz = 1;
    if (std::fabs(dir.z) > std::fabs(dir[kz])) kz = 2;
    int kx = (kz + 1) % 3;
    int ky = (kx + 1) % 3;
    if (dir[kz] < 0.0) std::swap(kx, ky);  // Woop et al.: keep the winding
    ray.kx = kx;
    ray.ky = ky;
    ray.kz = kz;
    ray.sx = dir[kx] / dir[kz];
    ray.sy = dir[ky] / dir[kz];
    ray.sz = 1.0 / dir[kz];
    for (int k = 0; k < 3; ++k) {
        ray.zero_axis[k] = dir[k] == 0.0;
        ray.inv[k] = ray.zero_axis[k] ? 0.0 : 1.0 / dir[k];
    }
    ray.dir_scale = maxAbs(dir);
    return ray;
}

/// Slab test of [lo, hi] grown by inflation * max(dir_term, |lo - o|_inf, |hi - o|_inf), clipped
/// to [t_near, t_far] (updated). Differences are taken relative to the origin first so the growth
/// is relative to the local scale, not to the absolute coordinates. Every operation is monotone
/// in the box, so a box inside another never passes when the outer one fails (the locality rule
/// relies on this).
inline bool slabs(const glm::dvec3& lo, const glm::dvec3& hi, const Ray& ray, double inflation, double dir_term,
                  double& t_near, double& t_far) {
    const glm::dvec3 lo_rel = lo - ray.origin;
    const glm::dvec3 hi_rel = hi - ray.origin;
    double scale = dir_term;
    for (int k = 0; k < 3; ++k) scale = std::max(scale, std::max(std::fabs(lo_rel[k]), std::fabs(hi_rel[k])));
    const double grow = mul(inflation, scale);
    for (int k = 0; k < 3; ++k) {
        const double l = lo_rel[k] - grow;
        const double h = hi_rel[k] + grow;
        if (ray.zero_axis[k]) {
            if (l > 0.0 || h < 0.0) return false;
            continue;
        }
        double t0 = l * ray.inv[k];
        double t1 = h * ray.inv[k];
        if (ray.inv[k] < 0.0) std::swap(t0, t1);
        t_near = std::max(t_near, t0);
        t_far = std::min(t_far, t1);
    }
    return t_near <= t_far;
}

inline void triangleBox(const Triangle& tri, glm::dvec3& lo, glm::dvec3& hi) {
    lo = glm::min(tri.v0, glm::min(tri.v1, tri.v2));
    hi = glm::max(tri.v0, glm::max(tri.v1, tri.v2));
}

/// Rule 3b for one edge P -> Q in the sheared frame (z in ray-parameter units).
inline bool nearEdge(double px, double py, double pz, double qx, double qy, double qz, double edge_function,
                     double rho, double t_eps) {
    const double ex = qx - px;
    const double ey = qy - py;
    // |P x Q| = |E| * (distance of the origin to the edge's line) and |E|_1 >= |E|_2.
    if (std::fabs(edge_function) > rho * (std::fabs(ex) + std::fabs(ey))) return false;
    const double length2 = mul(ex, ex) + mul(ey, ey);
    double lambda = 0.0;
    if (length2 > 0.0) lambda = std::min(1.0, std::max(0.0, -(mul(px, ex) + mul(py, ey)) / length2));
    const double dx = px + mul(lambda, ex);
    const double dy = py + mul(lambda, ey);
    if (mul(dx, dx) + mul(dy, dy) > rho * rho) return false;
    const double t = pz + mul(lambda, qz - pz);
    return t >= -t_eps && t <= 1.0 + t_eps;
}

struct SegmentQuery {
    Ray ray;
    double tie_epsilon = 0;
    double coplanar_epsilon = 0;
    double inflation = 0;      // rule 4: 4 * tie_epsilon + kBoxSlack
    double segment_scale = 0;  // min(|s - p|_inf, scene extent): the segment's term in every scale
};

/// Extent of the scene for the tolerances' scale: |hi - lo|_inf of the triangles' bounding box
/// (0 when empty). The oracle uses its non-degenerate triangles; a caller of classifySegment
/// matches the oracle's bits by passing the same mesh's value to makeSegmentQuery.
inline double sceneExtent(const std::vector<Triangle>& triangles) {
    if (triangles.empty()) return 0.0;
    glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
    for (const Triangle& tri : triangles) {
        lo = glm::min(lo, glm::min(tri.v0, glm::min(tri.v1, tri.v2)));
        hi = glm::max(hi, glm::max(tri.v0, glm::max(tri.v1, tri.v2)));
    }
    return maxAbs(hi - lo);
}

/// `scene_extent` caps the segment's length in the tolerances (rules 2-4): a light far outside
/// the scene must not widen them (issue 41). +infinity (the default) = the uncapped rule, which
/// equals the capped one whenever |s - p|_inf <= the extent.
inline SegmentQuery makeSegmentQuery(const glm::dvec3& receiver, const glm::dvec3& sample,
                                     const reference::VisibilityOptions& options,
                                     double scene_extent = std::numeric_limits<double>::infinity()) {
    SegmentQuery query;
    query.ray = makeRay(receiver, sample - receiver);
    query.ray.end = sample;
    query.tie_epsilon = options.tie_epsilon;
    query.coplanar_epsilon = options.coplanar_epsilon;
    query.inflation = mul(4.0, options.tie_epsilon) + kBoxSlack;
    query.segment_scale = std::min(query.ray.dir_scale, scene_extent);
    return query;
}

/// Rules 1-4 for one triangle and one segment (see the header comment).
inline Verdict classifySegment(const Triangle& tri, const SegmentQuery& query) {
    const Ray& ray = query.ray;
    const glm::dvec3 a = tri.v0 - ray.origin;
    const glm::dvec3 b = tri.v1 - ray.origin;
    const glm::dvec3 c = tri.v2 - ray.origin;
    const int kx = ray.kx, ky = ray.ky, kz = ray.kz;
    const double ax = a[kx] - mul(ray.sx, a[kz]), ay = a[ky] - mul(ray.sy, a[kz]);
    const double bx = b[kx] - mul(ray.sx, b[kz]), by = b[ky] - mul(ray.sy, b[kz]);
    const double cx = c[kx] - mul(ray.sx, c[kz]), cy = c[ky] - mul(ray.sy, c[kz]);
    const double u = cross2(cx, cy, bx, by);  // weight of v0 (edge v1 v2)
    const double v = cross2(ax, ay, cx, cy);  // weight of v1 (edge v2 v0)
    const double w = cross2(bx, by, ax, ay);  // weight of v2 (edge v0 v1)
    const bool negative = u < 0.0 || v < 0.0 || w < 0.0;
    const bool positive = u > 0.0 || v > 0.0 || w > 0.0;
    const bool inside = negative != positive;

    const double scale = std::max(std::max(query.segment_scale, maxAbs(a)), std::max(maxAbs(b), maxAbs(c)));
    const double eps = query.tie_epsilon;
    const double rho = eps * scale;
    // Rule 3's parameter window: eps * scale in length along the ray (t's rounding is relative to
    // the triangle's scale, not to the segment's length); = eps when scale >= |s - p|_inf.
    const double t_eps = scale < ray.dir_scale ? eps * (scale / ray.dir_scale) : eps;
    const double az = ray.sz * a[kz], bz = ray.sz * b[kz], cz = ray.sz * c[kz];  // ray-parameter units

    Verdict verdict;
    if (inside) {
        const double det = u + v + w;  // same-sign terms: no cancellation, never 0
        const double t = (mul(u, az) + mul(v, bz) + mul(w, cz)) / det;
        verdict.hit = t > 0.0 && t < 1.0;
        verdict.fragile = std::fabs(t) <= t_eps || std::fabs(t - 1.0) <= t_eps;
        verdict.t = t;
    }
    if (!verdict.fragile) {
        verdict.fragile = nearEdge(bx, by, bz, cx, cy, cz, u, rho, t_eps) || nearEdge(cx, cy, cz, ax, ay, az, v, rho, t_eps) ||
                          nearEdge(ax, ay, az, bx, by, bz, w, rho, t_eps);
    }
    if (!inside && !verdict.fragile) return {};  // the common case: a clear miss

    // Rule 2 (coplanar) and rule 3c (plane sides), on the caller's absolute coordinates.
    const glm::dvec3 n = cross3(tri.v1 - tri.v0, tri.v2 - tri.v0);
    const double reach = query.coplanar_epsilon * scale;
    const double limit = reach * length3(n);
    const double side_p = dot3(n, tri.v0 - ray.origin);
    const double side_s = dot3(n, tri.v0 - ray.end);
    // The plane distance is a cheap lower bound of the distance to the triangle itself.
    if (std::fabs(side_p) <= limit && penumbra::detail::pointTriangleDistance2<double>(ray.origin, tri.v0, tri.v1, tri.v2) <= reach * reach) return {};
    if (std::fabs(side_s) <= limit && penumbra::detail::pointTriangleDistance2<double>(ray.end, tri.v0, tri.v1, tri.v2) <= reach * reach) return {};
    if (inside && ((side_p > 0.0) != (side_s > 0.0)) != verdict.hit) verdict.fragile = true;
    if (!verdict.hit && !verdict.fragile) return {};

    // Rule 4 (locality).
    glm::dvec3 lo, hi;
    triangleBox(tri, lo, hi);
    double t_near = 0.0, t_far = 1.0;
    if (!slabs(lo, hi, ray, query.inflation, query.segment_scale, t_near, t_far)) return {};
    return verdict;
}

/// Closest-hit variant: the same watertight test, accepting t_min < t < t_max, no ties and no
/// coplanar rule. Rays parallel to the triangle's plane (|n.d| <= 1e-12 |n| |d|) do not hit it,
/// and the hit's t must lie in the slab interval of the triangle's box grown by kBoxSlack (the
/// closest-hit form of rule 4, which keeps BVH pruning exact).
inline bool intersectRay(const Triangle& tri, const Ray& ray, double t_min, double t_max, double& t_out,
                         double& u_out, double& v_out) {
    const glm::dvec3 a = tri.v0 - ray.origin;
    const glm::dvec3 b = tri.v1 - ray.origin;
    const glm::dvec3 c = tri.v2 - ray.origin;
    const int kx = ray.kx, ky = ray.ky, kz = ray.kz;
    const double ax = a[kx] - mul(ray.sx, a[kz]), ay = a[ky] - mul(ray.sy, a[kz]);
    const double bx = b[kx] - mul(ray.sx, b[kz]), by = b[ky] - mul(ray.sy, b[kz]);
    const double cx = c[kx] - mul(ray.sx, c[kz]), cy = c[ky] - mul(ray.sy, c[kz]);
    const double u = cross2(cx, cy, bx, by);
    const double v = cross2(ax, ay, cx, cy);
    const double w = cross2(bx, by, ax, ay);
    const bool negative = u < 0.0 || v < 0.0 || w < 0.0;
    const bool positive = u > 0.0 || v > 0.0 || w > 0.0;
    if (negative == positive) return false;
    const double det = u + v + w;
    const double t = (mul(u, ray.sz * a[kz]) + mul(v, ray.sz * b[kz]) + mul(w, ray.sz * c[kz])) / det;
    if (!(t > t_min && t < t_max)) return false;
    // A ray lying in the triangle's plane "passes through" its zero-width projection only by
    // rounding, and its t is meaningless: edge-on triangles are invisible to closest hits.
    const glm::dvec3 n = cross3(tri.v1 - tri.v0, tri.v2 - tri.v0);
    if (std::fabs(dot3(n, ray.dir)) <= kParallelRay * length3(n) * length3(ray.dir)) return false;
    glm::dvec3 lo, hi;
    triangleBox(tri, lo, hi);
    double t_near = -std::numeric_limits<double>::infinity();
    double t_far = std::numeric_limits<double>::infinity();
    if (!slabs(lo, hi, ray, kBoxSlack, 0.0, t_near, t_far) || t < t_near || t > t_far) return false;
    t_out = t;
    u_out = v / det;
    v_out = w / det;
    return true;
}

inline double halfArea(const glm::dvec3& lo, const glm::dvec3& hi) {
    const glm::dvec3 e = hi - lo;
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

/// Binned-SAH BVH over the non-degenerate triangles (Wald 2007 "On fast construction of SAH-based
/// bounding volume hierarchies": 16 bins over the centroid bounds per axis).
class Bvh {
public:
    void build(std::vector<Triangle> triangles) {
        nodes_.clear();
        triangles_.clear();
        if (triangles.empty()) return;
        const size_t count = triangles.size();
        items_.resize(count);
        for (size_t i = 0; i < count; ++i) {
            triangleBox(triangles[i], items_[i].lo, items_[i].hi);
            items_[i].centroid = (items_[i].lo + items_[i].hi) * 0.5;
        }
        order_.resize(count);
        std::iota(order_.begin(), order_.end(), 0u);
        nodes_.reserve(2 * count);
        nodes_.push_back(Node{});
        buildNode(0, 0, static_cast<uint32_t>(count), 0);
        triangles_.reserve(count);
        for (uint32_t i : order_) triangles_.push_back(triangles[i]);
        items_.clear();
        items_.shrink_to_fit();
        order_.clear();
        order_.shrink_to_fit();
        nodes_.shrink_to_fit();
    }

    const std::vector<Node>& nodes() const { return nodes_; }
    const std::vector<Triangle>& triangles() const { return triangles_; }
    int depth() const { return depth_; }

    /// Rules 1-4 aggregated over the BVH; returns on the first robust hit.
    Verdict anyHit(const SegmentQuery& query, Counters& counters) const {
        if (nodes_.empty()) return {};
        const Ray& ray = query.ray;
        double t_near = 0.0, t_far = 1.0;
        ++counters.nodes;
        if (!slabs(nodes_[0].lo, nodes_[0].hi, ray, query.inflation, query.segment_scale, t_near, t_far)) return {};
        Verdict result;
        uint32_t stack[kStackSize];
        int top = 0;
        uint32_t index = 0;
        for (;;) {
            const Node& node = nodes_[index];
            if (node.count > 0) {
                for (uint32_t i = node.first; i < node.first + node.count; ++i) {
                    ++counters.tests;
                    const Verdict verdict = classifySegment(triangles_[i], query);
                    if (verdict.hit && !verdict.fragile) return verdict;
                    result.hit |= verdict.hit;
                    result.fragile |= verdict.fragile;
                }
            } else {
                const uint32_t left = node.first;
                double near_l = 0.0, far_l = 1.0, near_r = 0.0, far_r = 1.0;
                const bool hit_l =
                    slabs(nodes_[left].lo, nodes_[left].hi, ray, query.inflation, query.segment_scale, near_l, far_l);
                const bool hit_r =
                    slabs(nodes_[left + 1].lo, nodes_[left + 1].hi, ray, query.inflation, query.segment_scale, near_r, far_r);
                counters.nodes += 2;
                if (hit_l && hit_r) {
                    const bool right_first = near_r < near_l;
                    PENUMBRA_ASSERT(top < kStackSize);
                    stack[top++] = right_first ? left : left + 1;
                    index = right_first ? left + 1 : left;
                    continue;
                }
                if (hit_l || hit_r) {
                    index = hit_l ? left : left + 1;
                    continue;
                }
            }
            if (top == 0) break;
            index = stack[--top];
        }
        return result;
    }

    /// Smallest t, ties broken by the smallest caller triangle index.
    reference::Hit closest(const Ray& ray, double t_min, double t_max, Counters& counters) const {
        reference::Hit best;
        if (nodes_.empty()) return best;
        double t_best = t_max;
        double t_near = t_min, t_far = t_best;
        ++counters.nodes;
        if (!slabs(nodes_[0].lo, nodes_[0].hi, ray, kBoxSlack, 0.0, t_near, t_far)) return best;
        struct Entry {
            uint32_t node;
            double t_near;
        };
        Entry stack[kStackSize];
        int top = 0;
        stack[top++] = {0, t_near};
        while (top > 0) {
            const Entry entry = stack[--top];
            if (entry.t_near > t_best) continue;  // pruned by a hit found since it was pushed
            const Node& node = nodes_[entry.node];
            if (node.count > 0) {
                for (uint32_t i = node.first; i < node.first + node.count; ++i) {
                    ++counters.tests;
                    double t = 0, u = 0, v = 0;
                    const Triangle& tri = triangles_[i];
                    if (!intersectRay(tri, ray, t_min, t_max, t, u, v)) continue;
                    if (!best.hit || t < best.t || (t == best.t && tri.index < best.triangle)) {
                        best = reference::Hit{true, t, tri.index, u, v};
                        t_best = t;
                    }
                }
                continue;
            }
            const uint32_t left = node.first;
            double near_l = t_min, far_l = t_best, near_r = t_min, far_r = t_best;
            const bool hit_l = slabs(nodes_[left].lo, nodes_[left].hi, ray, kBoxSlack, 0.0, near_l, far_l);
            const bool hit_r = slabs(nodes_[left + 1].lo, nodes_[left + 1].hi, ray, kBoxSlack, 0.0, near_r, far_r);
            counters.nodes += 2;
            // Push the far child first so the near one is popped next.
            const bool right_first = hit_r && (!hit_l || near_r < near_l);
            PENUMBRA_ASSERT(top + 2 <= kStackSize);
            if (right_first) {
                if (hit_l) stack[top++] = {left, near_l};
                stack[top++] = {left + 1, near_r};
            } else {
                if (hit_r) stack[top++] = {left + 1, near_r};
                if (hit_l) stack[top++] = {left, near_l};
            }
        }
        return best;
    }

private:
    struct Item {
        glm::dvec3 lo, hi, centroid;
    };
    struct Bin {
        glm::dvec3 lo{std::numeric_limits<double>::infinity()};
        glm::dvec3 hi{-std::numeric_limits<double>::infinity()};
        uint32_t count = 0;
        void grow(const glm::dvec3& l, const glm::dvec3& h) {
            lo = glm::min(lo, l);
            hi = glm::max(hi, h);
        }
    };

    static uint32_t binOf(double centroid, double lo, double scale) {
        // Written so that NaN (0 * inf for subnormal extents) and overshoot stay in range: the
        // counting pass and the partition must agree, and the cast must stay defined.
        const double f = (centroid - lo) * scale;
        if (!(f > 0.0)) return 0u;
        if (f >= static_cast<double>(kBinCount - 1)) return kBinCount - 1;
        return static_cast<uint32_t>(f);
    }

    void buildNode(uint32_t node_index, uint32_t begin, uint32_t end, int depth) {
        depth_ = std::max(depth_, depth);
        glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        glm::dvec3 centroid_lo = lo, centroid_hi = hi;
        for (uint32_t i = begin; i < end; ++i) {
            const Item& item = items_[order_[i]];
            lo = glm::min(lo, item.lo);
            hi = glm::max(hi, item.hi);
            centroid_lo = glm::min(centroid_lo, item.centroid);
            centroid_hi = glm::max(centroid_hi, item.centroid);
        }
        nodes_[node_index].lo = lo;
        nodes_[node_index].hi = hi;
        const uint32_t count = end - begin;
        const auto makeLeaf = [&] {
            nodes_[node_index].first = begin;
            nodes_[node_index].count = count;
        };
        if (count <= 2 || depth >= kMaxDepth) return makeLeaf();

        int best_axis = -1;
        uint32_t best_split = 0;
        double best_cost = std::numeric_limits<double>::infinity();
        for (int axis = 0; axis < 3; ++axis) {
            const double extent = centroid_hi[axis] - centroid_lo[axis];
            if (!(extent > 0.0)) continue;
            const double scale = kBinCount / extent;
            Bin bins[kBinCount];
            for (uint32_t i = begin; i < end; ++i) {
                const Item& item = items_[order_[i]];
                Bin& bin = bins[binOf(item.centroid[axis], centroid_lo[axis], scale)];
                bin.grow(item.lo, item.hi);
                ++bin.count;
            }
            double right_area[kBinCount];
            uint32_t right_count[kBinCount];
            Bin right;
            for (uint32_t b = kBinCount - 1; b > 0; --b) {
                if (bins[b].count > 0) right.grow(bins[b].lo, bins[b].hi);
                right.count += bins[b].count;
                right_area[b] = right.count > 0 ? halfArea(right.lo, right.hi) : 0.0;
                right_count[b] = right.count;
            }
            Bin left;
            for (uint32_t split = 1; split < kBinCount; ++split) {  // left = bins [0, split)
                if (bins[split - 1].count > 0) left.grow(bins[split - 1].lo, bins[split - 1].hi);
                left.count += bins[split - 1].count;
                if (left.count == 0 || right_count[split] == 0) continue;
                const double cost = halfArea(left.lo, left.hi) * left.count + right_area[split] * right_count[split];
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_split = split;
                }
            }
        }
        if (best_axis < 0) return makeLeaf();  // all centroids coincide
        const double area = halfArea(lo, hi);
        const double split_cost = kTraversalCost * area + best_cost;
        const double leaf_cost = area * count;
        if (split_cost >= leaf_cost && count <= kMaxLeafSize) return makeLeaf();

        const double axis_lo = centroid_lo[best_axis];
        const double scale = kBinCount / (centroid_hi[best_axis] - axis_lo);
        const auto middle = std::partition(order_.begin() + begin, order_.begin() + end, [&](uint32_t i) {
            return binOf(items_[i].centroid[best_axis], axis_lo, scale) < best_split;
        });
        const uint32_t mid = static_cast<uint32_t>(middle - order_.begin());
        PENUMBRA_ASSERT(mid > begin && mid < end);
        const uint32_t left = static_cast<uint32_t>(nodes_.size());
        nodes_.push_back(Node{});
        nodes_.push_back(Node{});
        nodes_[node_index].first = left;
        nodes_[node_index].count = 0;
        buildNode(left, begin, mid, depth + 1);
        buildNode(left + 1, mid, end, depth + 1);
    }

    std::vector<Node> nodes_;
    std::vector<Triangle> triangles_;  // in leaf order
    std::vector<Item> items_;          // build scratch
    std::vector<uint32_t> order_;      // build scratch
    int depth_ = 0;
};

inline void checkOptions(const reference::VisibilityOptions& options, const char* function) {
    PENUMBRA_CHECK(options.tie_epsilon >= 0.0 && options.tie_epsilon <= kMaxEpsilon, function,
                   ": options.tie_epsilon must be in [0, ", kMaxEpsilon, "] (got ", options.tie_epsilon, ")");
    PENUMBRA_CHECK(options.coplanar_epsilon >= 0.0 && options.coplanar_epsilon <= kMaxEpsilon, function,
                   ": options.coplanar_epsilon must be in [0, ", kMaxEpsilon, "] (got ", options.coplanar_epsilon, ")");
}

inline void checkPoint(const glm::dvec3& p, const char* function, const char* name) {
    PENUMBRA_CHECK(finiteBounded(p), function, ": ", name, " must be finite with |coordinate| <= ", kMaxCoordinate,
                   " (got ", p.x, ", ", p.y, ", ", p.z, ")");
}

inline void checkPoints(const std::vector<glm::dvec3>& points, const char* function, const char* name) {
    for (size_t i = 0; i < points.size(); ++i) {
        const glm::dvec3& p = points[i];
        PENUMBRA_CHECK(finiteBounded(p), function, ": ", name, "[", i, "] must be finite with |coordinate| <= ",
                       kMaxCoordinate, " (got ", p.x, ", ", p.y, ", ", p.z, ")");
    }
}

/// The oracle's input rules, shared by every oracle (`who` names the caller in the messages):
/// index count a multiple of 3, at most 2^32 - 1 triangles, finite vertices with |coordinate| <=
/// kMaxCoordinate, indices in range. Returns the non-degenerate triangles in caller order
/// (Triangle::index = the caller's triangle index); degenerate ones never block (the one rule of
/// detail/geometry.hpp, shared with the twins and the GPU).
inline std::vector<Triangle> oracleTriangles(const std::vector<glm::dvec3>& positions, const std::vector<uint32_t>& indices,
                                             const char* who) {
    PENUMBRA_CHECK(indices.size() % 3 == 0, who, ": index count ", indices.size(), " is not a multiple of 3");
    PENUMBRA_CHECK(indices.size() / 3 <= 0xffffffffull, who, ": too many triangles (", indices.size() / 3, ")");
    for (size_t i = 0; i < positions.size(); ++i) {
        const glm::dvec3& p = positions[i];
        PENUMBRA_CHECK(finiteBounded(p), who, ": vertex ", i, " must be finite with |coordinate| <= ", kMaxCoordinate,
                       " (got ", p.x, ", ", p.y, ", ", p.z, ")");
    }
    for (size_t k = 0; k < indices.size(); ++k) {
        PENUMBRA_CHECK(indices[k] < positions.size(), who, ": indices[", k, "] = ", indices[k], " is out of range (",
                       positions.size(), " vertices)");
    }
    const size_t count = indices.size() / 3;
    std::vector<Triangle> triangles;
    triangles.reserve(count);
    for (size_t i = 0; i < count; ++i) {
        const Triangle tri{positions[indices[3 * i]], positions[indices[3 * i + 1]], positions[indices[3 * i + 2]],
                           static_cast<uint32_t>(i)};
        if (penumbra::detail::degenerateTriangle(tri.v0, tri.v1, tri.v2)) continue;
        triangles.push_back(tri);
    }
    return triangles;
}

}  // namespace oracle
}  // namespace detail

namespace reference {

inline uint32_t VisibilityResult::blockedCount(size_t r) const {
    PENUMBRA_ASSERT(r < receivers);
    uint32_t total = 0;
    for (uint32_t word = 0; word < words_per_receiver; ++word)
        total += detail::oracle::popcount32(blocked[r * words_per_receiver + word]);
    return total;
}

inline double VisibilityResult::visibleFraction(size_t r) const {
    PENUMBRA_ASSERT(r < receivers);
    if (samples == 0) return 1.0;
    return 1.0 - static_cast<double>(blockedCount(r)) / static_cast<double>(samples);
}

/// The oracle. Construction validates the mesh, drops degenerate triangles and builds the BVH;
/// every query is const and may run concurrently.
class VisibilityOracle {
public:
    /// Triangle list: triangle i is (indices[3i], indices[3i+1], indices[3i+2]).
    VisibilityOracle(const std::vector<glm::dvec3>& positions, const std::vector<uint32_t>& indices) {
        build(positions, indices);
    }
    /// Converts to double (exactly) first.
    VisibilityOracle(const std::vector<glm::vec3>& positions, const std::vector<uint32_t>& indices) {
        build(std::vector<glm::dvec3>(positions.begin(), positions.end()), indices);
    }

    /// Number of triangles in the caller's list (degenerate ones included).
    size_t triangleCount() const { return triangle_count_; }
    /// Triangles dropped as degenerate (they never block).
    size_t degenerateTriangleCount() const { return triangle_count_ - bvh_.triangles().size(); }
    size_t bvhNodeCount() const { return bvh_.nodes().size(); }
    int bvhDepth() const { return bvh_.depth(); }
    /// E of the tolerances' scale (header comment, rule 2): |hi - lo|_inf of the non-degenerate
    /// triangles' bounding box; 0 for an empty mesh.
    double sceneExtent() const { return scene_extent_; }

    /// Is the open segment (receiver, light_sample) blocked? *tie (optional) receives the tie bit.
    /// Default options. Throws penumbra::Error for non-finite input.
    bool segmentBlocked(const glm::dvec3& receiver, const glm::dvec3& light_sample, bool* tie = nullptr) const {
        return segmentBlocked(receiver, light_sample, VisibilityOptions{}, tie);
    }
    /// Same with explicit tolerances (options.threads is ignored).
    bool segmentBlocked(const glm::dvec3& receiver, const glm::dvec3& light_sample, const VisibilityOptions& options,
                        bool* tie = nullptr) const {
        detail::oracle::checkOptions(options, "segmentBlocked");
        detail::oracle::checkPoint(receiver, "segmentBlocked", "receiver");
        detail::oracle::checkPoint(light_sample, "segmentBlocked", "light_sample");
        detail::oracle::Counters counters;
        const detail::oracle::Verdict verdict = query(receiver, light_sample, options, false, counters);
        if (tie) *tie = verdict.fragile;
        return verdict.hit;
    }

    /// Closest hit of origin + t * direction with t_min < t < t_max (t_max may be +infinity,
    /// t_min -infinity), using the watertight test; equal t resolve to the smallest triangle
    /// index. No coplanar rule and no ties; a triangle whose plane contains the ray direction
    /// (|n.d| <= 1e-12 |n| |d|: edge-on) is not hit, and a hit must pass the closest-hit form of
    /// the locality rule (t inside the triangle's box grown by 1e-12 of its scale). Throws for
    /// non-finite origin/direction, zero direction, NaN bounds or t_min >= t_max.
    Hit closestHit(const glm::dvec3& origin, const glm::dvec3& direction, double t_min, double t_max) const {
        detail::oracle::Counters counters;
        return closestHit(origin, direction, t_min, t_max, false, counters);
    }
    /// Same result from a loop over all triangles (for tests).
    Hit closestHitBruteForce(const glm::dvec3& origin, const glm::dvec3& direction, double t_min, double t_max) const {
        detail::oracle::Counters counters;
        return closestHit(origin, direction, t_min, t_max, true, counters);
    }

    /// All receivers x all light samples through the BVH, on options.threads threads.
    VisibilityResult evaluate(const std::vector<glm::dvec3>& receivers, const std::vector<glm::dvec3>& light_samples,
                              const VisibilityOptions& options = {}) const {
        return evaluateImpl(receivers, light_samples, options, false, "evaluate");
    }
    /// The same predicate over every triangle, without the BVH: bit-identical to evaluate().
    VisibilityResult evaluateBruteForce(const std::vector<glm::dvec3>& receivers,
                                        const std::vector<glm::dvec3>& light_samples,
                                        const VisibilityOptions& options = {}) const {
        return evaluateImpl(receivers, light_samples, options, true, "evaluateBruteForce");
    }

private:
    void build(const std::vector<glm::dvec3>& positions, const std::vector<uint32_t>& indices) {
        std::vector<detail::oracle::Triangle> triangles = detail::oracle::oracleTriangles(positions, indices, "VisibilityOracle");
        triangle_count_ = indices.size() / 3;
        scene_extent_ = detail::oracle::sceneExtent(triangles);
        linear_ = triangles;  // caller order, for the brute-force paths
        bvh_.build(std::move(triangles));
    }

    detail::oracle::Verdict query(const glm::dvec3& receiver, const glm::dvec3& sample,
                                  const VisibilityOptions& options, bool brute_force,
                                  detail::oracle::Counters& counters) const {
        namespace oracle = detail::oracle;
        if (receiver == sample) return {};  // empty open segment
        const oracle::SegmentQuery segment = oracle::makeSegmentQuery(receiver, sample, options, scene_extent_);
        if (!brute_force) return bvh_.anyHit(segment, counters);
        oracle::Verdict result;
        for (const oracle::Triangle& tri : linear_) {
            ++counters.tests;
            const oracle::Verdict verdict = oracle::classifySegment(tri, segment);
            if (verdict.hit && !verdict.fragile) return verdict;
            result.hit |= verdict.hit;
            result.fragile |= verdict.fragile;
        }
        return result;
    }

    Hit closestHit(const glm::dvec3& origin, const glm::dvec3& direction, double t_min, double t_max, bool brute_force,
                   detail::oracle::Counters& counters) const {
        namespace oracle = detail::oracle;
        oracle::checkPoint(origin, "closestHit", "origin");
        oracle::checkPoint(direction, "closestHit", "direction");
        PENUMBRA_CHECK(direction != glm::dvec3(0.0), "closestHit: direction must be non-zero");
        PENUMBRA_CHECK(!std::isnan(t_min) && !std::isnan(t_max) && t_min < t_max,
                       "closestHit: need t_min < t_max (got ", t_min, ", ", t_max, ")");
        const oracle::Ray ray = oracle::makeRay(origin, direction);
        if (!brute_force) return bvh_.closest(ray, t_min, t_max, counters);
        Hit best;
        for (const oracle::Triangle& tri : linear_) {
            ++counters.tests;
            double t = 0, u = 0, v = 0;
            if (!oracle::intersectRay(tri, ray, t_min, t_max, t, u, v)) continue;
            if (!best.hit || t < best.t || (t == best.t && tri.index < best.triangle)) best = Hit{true, t, tri.index, u, v};
        }
        return best;
    }

    VisibilityResult evaluateImpl(const std::vector<glm::dvec3>& receivers, const std::vector<glm::dvec3>& samples,
                                  const VisibilityOptions& options, bool brute_force, const char* function) const {
        namespace oracle = detail::oracle;
        oracle::checkOptions(options, function);
        PENUMBRA_CHECK(samples.size() <= 0xffffffffull, function, ": too many light samples (", samples.size(), ")");
        oracle::checkPoints(receivers, function, "receivers");
        oracle::checkPoints(samples, function, "light_samples");

        VisibilityResult result;
        result.receivers = receivers.size();
        result.samples = samples.size();
        result.words_per_receiver = static_cast<uint32_t>((samples.size() + 31) / 32);
        const size_t words = result.receivers * result.words_per_receiver;
        result.blocked.assign(words, 0u);
        result.ties.assign(words, 0u);
        if (words == 0) return result;

        unsigned threads = options.threads != 0 ? options.threads : std::thread::hardware_concurrency();
        threads = std::max(threads, 1u);
        // Small chunks balance uneven receivers; a few per thread keep the atomic cheap.
        const size_t chunk = std::max<size_t>(oracle::kReceiversPerChunkMin, receivers.size() / (size_t(threads) * 16));
        const size_t chunks = (receivers.size() + chunk - 1) / chunk;
        threads = static_cast<unsigned>(std::min<size_t>(threads, chunks));

        std::atomic<size_t> next_chunk{0};
        std::vector<oracle::Counters> counters(threads);
        const auto work = [&](unsigned worker) {
            oracle::Counters local;
            for (size_t c = next_chunk.fetch_add(1); c < chunks; c = next_chunk.fetch_add(1)) {
                const size_t r_end = std::min(receivers.size(), (c + 1) * chunk);
                for (size_t r = c * chunk; r < r_end; ++r) {
                    uint32_t* blocked = result.blocked.data() + r * result.words_per_receiver;
                    uint32_t* ties = result.ties.data() + r * result.words_per_receiver;
                    for (size_t s = 0; s < samples.size(); ++s) {
                        const oracle::Verdict verdict = query(receivers[r], samples[s], options, brute_force, local);
                        if (verdict.hit) blocked[s / 32] |= 1u << (s % 32);
                        if (verdict.fragile) ties[s / 32] |= 1u << (s % 32);
                    }
                }
            }
            counters[worker] = local;
        };
        std::vector<std::thread> pool;
        pool.reserve(threads - 1);
        for (unsigned i = 1; i < threads; ++i) {
            try {
                pool.emplace_back(work, i);
            } catch (...) {
                break;  // fewer threads: the remaining chunks are picked up by the others
            }
        }
        work(0);
        for (std::thread& thread : pool) thread.join();

        for (const oracle::Counters& c : counters) {
            result.nodes_visited += c.nodes;
            result.triangle_tests += c.tests;
        }
        for (uint32_t word : result.ties) result.tie_count += oracle::popcount32(word);
        return result;
    }

    size_t triangle_count_ = 0;
    double scene_extent_ = 0;  // detail::oracle::sceneExtent of linear_
    std::vector<detail::oracle::Triangle> linear_;  // non-degenerate, caller order
    detail::oracle::Bvh bvh_;
};

}  // namespace reference
}  // namespace penumbra

#endif
