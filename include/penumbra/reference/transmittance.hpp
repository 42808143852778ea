// penumbra/reference/transmittance.hpp — the exact transmittance oracle for deep shadow maps.
//
// Integration summary
//   Needs:    reference/visibility.hpp (its segment predicate ::penumbra::detail::oracle::classifySegment and
//             its BVH, reused as they are); a triangle list (positions as glm::dvec3 or glm::vec3,
//             uint32 indices, 3 per triangle) with an opacity per triangle: one value for all, a
//             std::vector<float> / std::vector<double> with one per triangle (TransmittanceOracle),
//             or RGB opacities as glm::dvec3 (ColourTransmittanceOracle); optionally a homogeneous
//             participating medium (HomogeneousMedium: an axis-aligned box and sigma_t).
//             Header-only: GLM, the C++17 standard library, std::thread. No GPU, no GL; IEEE-754
//             double arithmetic; not valid under -ffast-math.
//   Produces: per segment (p, q) the transmittance prod (1 - opacity) over the triangles the OPEN
//             segment crosses, times the medium's exp(-sigma_t L), with the hit count, the number
//             of fragile triangles and a tie flag (TransmittanceResult); batches on all cores
//             (evaluate), weighted filters of segments (filteredTransmittance: what a filtered
//             deep-shadow-map lookup estimates, lokovic2000 §4), and the exact visibility function
//             of a ray from the light (transmittanceAlongRay: every crossing sorted by t, the step
//             function a deep shadow map's compressed function approximates, lokovic2000 §3).
//   Hooks:    none. Built once (the oracle's binned-SAH BVH in the constructor), then const and
//             thread-safe.
//
//   Typical use (a deep-shadow-map mode's test):
//       penumbra::reference::TransmittanceOracle oracle(positions, indices, opacities);
//       const auto exact = oracle.transmittanceAlongRay(light, direction, t_far);
//       // exact.steps[i].t / .transmittance: V(t) just after the i-th crossing; compare a DSM
//       // texel's function to it where exact.tie is clear.
//       const auto r = oracle.transmittance(receiver, light);  // r.transmittance, r.tie
//
// ---------------------------------------------------------------------------------------------
// Semantics of one segment (p, q)
//
//   transmittance(p, q) = surfaces * medium, where
//     surfaces = prod over every triangle T with hit(T) of (1 - opacity(T)), multiplied in the
//                caller's triangle order (ascending index), so the bits do not depend on the BVH;
//     medium   = exp(-sigma_t * L), L = length of the part of the segment inside the medium's box.
//   hit(T) is EXACTLY reference/visibility.hpp's per-triangle predicate (::penumbra::detail::oracle::
//   classifySegment with the options' tie_epsilon / coplanar_epsilon and the mesh's sceneExtent()
//   capping the segment's length in the tolerances, as VisibilityOracle): the watertight test on the
//   open segment, 0 < t < 1 (both endpoints excluded), the coplanar rule (a receiver lying on a
//   surface is not attenuated by it, nor by the neighbours whose edges it lies on), and rule 4's
//   locality. Degenerate triangles are dropped (never hit, never fragile) as there. Each triangle
//   counts at most once: a surface made of several triangles attenuates once per triangle crossed.
//
//   Ties. fragile(T) is visibility.hpp's rule 3 for T alone (crossing within tie_epsilon of an
//   endpoint, line within tie_epsilon * scale of an edge or vertex of T, or a crossing so grazing
//   that its plane-side test disagrees). Unlike visibility's tie bit, one robust hit does NOT hide
//   the fragile ones: every factor matters here.
//     fragile_triangles = number of fragile triangles (hit or not), tie = fragile_triangles > 0.
//   With tie clear, every decision is robust: an implementation of the same predicate with
//   another rounding (float, another compiler, a GPU) finds the same crossed set, hence the same
//   hit count and, multiplying in index order, the same bits. With tie set, its result may differ
//   from this one by factors (1 - opacity) of the fragile triangles (some included here and not
//   there, or the reverse). In particular a line through an edge shared by two triangles (a
//   quad's diagonal, a vertex of a fan) is inside BOTH under the watertight test — no crack, but
//   the surface then attenuates twice, (1 - a)^2 instead of (1 - a): exactly such a case is
//   fragile, so it is flagged as a tie (fragile_triangles = 2 for a quad's diagonal).
//   The medium factor is never a tie: it is continuous in p and q except for segments lying in
//   the plane of a box face (see below), and only its rounding (a few ulp, plus std::exp's) varies.
//   p == q (empty segment): surfaces = 1, L = 0, no hits, no tie.
//
// Colour: ColourTransmittanceOracle takes RGB opacities (glm::dvec3) and multiplies per channel:
// the same crossed set, three products. A grey opacity (a, a, a) gives three times the bits of
// TransmittanceOracle with opacity a. sigma_t is grey.
//
// Medium (HomogeneousMedium; value-initialised = none: sigma_t = 0 gives exactly 1): the CLOSED
// box [lo, hi] (lo <= hi per axis; a flat box is allowed), clipped analytically against the
// segment p + t (q - p), 0 <= t <= 1, per axis in double (Kay-Kajiya slabs, divisions, no
// inflation): L = (t_exit - t_entry) * |q - p|. A segment lying in a face's plane (its axis
// component of q - p exactly 0) is inside when that coordinate is in [lo, hi]: grazing a face
// counts the full overlap, 1 ulp outside counts nothing. A segment touching the box at one point
// has L = 0.
//
// Along a ray (transmittanceAlongRay(origin, direction, t_max)): the crossings of the open
// segment (origin, end), end = origin + t_max * direction evaluated in double, i.e. exactly the
// hits of transmittance(origin, end): for each, t = t_max * (segment parameter) in ray units
// (0 < t <= t_max after rounding), the opacity, the caller's triangle index and its fragile flag,
// sorted by t then by triangle index; step i's `transmittance` is the product of (1 - opacity)
// over steps 0..i in that order (so the last one equals transmittance(origin, end).surfaces up to
// the rounding of the product order). The visibility function of lokovic2000 §3 is then
//   V(t) = (product over steps with step.t < t) * mediumTransmittance(origin, origin + t * direction);
// the steps exclude the medium. Steps with equal t (a shared edge) are adjacent and fragile.
//
// Filtered (filteredTransmittance(taps)): sum_i w_i T_i / sum_i w_i over taps {p, q, weight},
// summed in tap order (deterministic); tie = some tap is a tie, tie_weight_fraction = sum of the
// tie taps' weights / sum of all weights.
//
// Bad input (penumbra::Error, message naming the index/value):
//   - everything VisibilityOracle rejects (non-finite vertex or |coordinate| > 1e50, index out of
//     range, index count not a multiple of 3, too many triangles), with the same messages but
//     "TransmittanceOracle:" in front;
//   - an opacity not finite or outside [0, 1] (NaN, 1.5, -0.1, inf) -> throws, naming the triangle
//     (and channel) and the value; per-triangle lists must hold exactly one per triangle;
//   - medium: sigma_t negative, NaN or infinite, lo/hi not finite (or beyond 1e50), lo > hi on
//     some axis -> throws;
//   - queries: points not finite or beyond 1e50, options.tie_epsilon / coplanar_epsilon outside
//     [0, 0.1] -> throws;
//   - filteredTransmittance: no taps, a weight not finite or <= 0, a weight sum that overflows ->
//     throws; transmittanceAlongRay: zero direction, t_max not finite or <= 0, an end point
//     beyond 1e50 -> throws.
//   An empty mesh is valid: only the medium attenuates.
//
// Threads: evaluate() (and filteredTransmittance) split the segments into chunks handed out
// dynamically to std::threads; each segment is computed alone and written to its own slot, so the
// results (and the work counters) do not depend on the thread count.
#ifndef PENUMBRA_REFERENCE_TRANSMITTANCE_HPP
#define PENUMBRA_REFERENCE_TRANSMITTANCE_HPP

#include <penumbra/error.hpp>
#include <penumbra/reference/visibility.hpp>

#include <glm/vec3.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <thread>
#include <type_traits>
#include <utility>
#include <vector>

namespace penumbra {
namespace reference {

/// A homogeneous participating medium filling the closed box [lo, hi]. Value-initialised = none.
struct HomogeneousMedium {
    glm::dvec3 lo{0.0};
    glm::dvec3 hi{0.0};
    double sigma_t = 0.0;  ///< extinction coefficient (per unit length), finite and >= 0
};

/// The same tolerances and thread count as the visibility oracle (rules 2 and 3 of visibility.hpp).
using TransmittanceOptions = VisibilityOptions;

/// One segment of a batch: the open segment (p, q).
struct TransmittanceSegment {
    glm::dvec3 p{0.0};
    glm::dvec3 q{0.0};
};

/// One tap of filteredTransmittance: the open segment (p, q) with weight > 0.
struct FilterTap {
    glm::dvec3 p{0.0};
    glm::dvec3 q{0.0};
    double weight = 1.0;
};

/// Value is double (TransmittanceOracle) or glm::dvec3 (ColourTransmittanceOracle).
template <typename Value>
struct TransmittanceResult {
    Value transmittance = Value(1.0);  ///< surfaces * medium
    Value surfaces = Value(1.0);       ///< prod (1 - opacity) over the crossed triangles, ascending index
    double medium = 1.0;               ///< exp(-sigma_t * medium_length)
    double medium_length = 0.0;        ///< length of the segment inside the medium's box
    uint32_t hits = 0;                 ///< triangles crossed (fragile ones included)
    uint32_t fragile_triangles = 0;    ///< triangles whose decision is fragile (crossed or not)
    bool tie = false;                  ///< fragile_triangles > 0
};

template <typename Value>
struct TransmittanceBatch {
    std::vector<TransmittanceResult<Value>> results;  ///< one per segment, in input order
    uint64_t tie_count = 0;                           ///< segments with tie set
    // Device-independent work counters (deterministic, independent of the thread count).
    uint64_t nodes_visited = 0;   ///< BVH node bounds tested (0 for brute force)
    uint64_t triangle_tests = 0;  ///< triangle classifications (no early exit: all hits are needed)
};

template <typename Value>
struct FilteredTransmittance {
    Value transmittance = Value(1.0);  ///< sum w_i T_i / sum w_i
    bool tie = false;                  ///< some tap is a tie
    uint32_t tie_taps = 0;
    double tie_weight_fraction = 0.0;  ///< sum of the tie taps' weights / sum of all weights
};

/// One crossing of transmittanceAlongRay.
template <typename Value>
struct RayStep {
    double t = 0.0;                    ///< ray parameter (units of `direction`), 0 < t <= t_max
    Value opacity = Value(0.0);
    uint32_t triangle = 0;             ///< caller's triangle index
    bool fragile = false;
    Value transmittance = Value(1.0);  ///< prod (1 - opacity) over this step and all before it
};

template <typename Value>
struct RayTransmittance {
    std::vector<RayStep<Value>> steps;  ///< sorted by t, then triangle
    uint32_t fragile_triangles = 0;     ///< fragile triangles, crossed (steps) or not
    bool tie = false;                   ///< fragile_triangles > 0
    glm::dvec3 end{0.0};                ///< origin + t_max * direction as evaluated
};

}  // namespace reference

namespace detail {
namespace transmittance {

namespace oracle = ::penumbra::detail::oracle;

/// A triangle the segment crosses or nearly crosses (hit or fragile).
struct Crossing {
    uint32_t triangle;  // caller's index
    bool hit;
    bool fragile;
    double t;  // segment parameter, meaningful when hit
};

inline void classify(const oracle::Triangle& tri, const oracle::SegmentQuery& query, std::vector<Crossing>& out) {
    const oracle::Verdict verdict = oracle::classifySegment(tri, query);
    if (verdict.hit || verdict.fragile) out.push_back(Crossing{tri.index, verdict.hit, verdict.fragile, verdict.t});
}

/// Bvh::anyHit without the early exit: every triangle that is hit or fragile, in traversal order.
/// The node test is anyHit's (same inflation), so by rule 4's monotonicity no triangle whose
/// verdict is non-empty is pruned: the set equals the brute-force loop's.
inline void allHits(const oracle::Bvh& bvh, const oracle::SegmentQuery& query, std::vector<Crossing>& out,
                    oracle::Counters& counters) {
    const std::vector<oracle::Node>& nodes = bvh.nodes();
    const std::vector<oracle::Triangle>& triangles = bvh.triangles();
    if (nodes.empty()) return;
    const oracle::Ray& ray = query.ray;
    double t_near = 0.0, t_far = 1.0;
    ++counters.nodes;
    if (!oracle::slabs(nodes[0].lo, nodes[0].hi, ray, query.inflation, query.segment_scale, t_near, t_far)) return;
    uint32_t stack[oracle::kStackSize];
    int top = 0;
    uint32_t index = 0;
    for (;;) {
        const oracle::Node& node = nodes[index];
        if (node.count > 0) {
            for (uint32_t i = node.first; i < node.first + node.count; ++i) {
                ++counters.tests;
                classify(triangles[i], query, out);
            }
        } else {
            const uint32_t left = node.first;
            double near_l = 0.0, far_l = 1.0, near_r = 0.0, far_r = 1.0;
            const bool hit_l =
                oracle::slabs(nodes[left].lo, nodes[left].hi, ray, query.inflation, query.segment_scale, near_l, far_l);
            const bool hit_r =
                oracle::slabs(nodes[left + 1].lo, nodes[left + 1].hi, ray, query.inflation, query.segment_scale, near_r, far_r);
            counters.nodes += 2;
            if (hit_l && hit_r) {
                PENUMBRA_ASSERT(top < oracle::kStackSize);
                stack[top++] = left + 1;
                index = left;
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
}

/// Length of p + t (q - p), 0 <= t <= 1, inside the closed box [lo, hi] (slabs, no inflation).
inline double boxLength(const glm::dvec3& lo, const glm::dvec3& hi, const glm::dvec3& p, const glm::dvec3& q) {
    const glm::dvec3 d = q - p;
    if (d == glm::dvec3(0.0)) return 0.0;
    double t_entry = 0.0, t_exit = 1.0;
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0.0) {
            if (p[k] < lo[k] || p[k] > hi[k]) return 0.0;
            continue;
        }
        double t0 = (lo[k] - p[k]) / d[k];
        double t1 = (hi[k] - p[k]) / d[k];
        if (d[k] < 0.0) std::swap(t0, t1);
        t_entry = std::max(t_entry, t0);
        t_exit = std::min(t_exit, t1);
    }
    if (!(t_entry < t_exit)) return 0.0;
    return oracle::mul(t_exit - t_entry, oracle::length3(d));
}

// w * value with the product kept opaque (no FMA with the following sum; visibility.hpp's mul).
inline double weighted(double value, double w) { return oracle::mul(value, w); }
inline glm::dvec3 weighted(const glm::dvec3& value, double w) {
    return {oracle::mul(value.x, w), oracle::mul(value.y, w), oracle::mul(value.z, w)};
}

inline int channels(double) { return 1; }
inline int channels(const glm::dvec3&) { return 3; }
inline double channel(double value, int) { return value; }
inline double channel(const glm::dvec3& value, int k) { return value[k]; }

inline void checkIndexedPoint(const glm::dvec3& p, const char* function, const char* array, size_t i, const char* member) {
    PENUMBRA_CHECK(oracle::finiteBounded(p), function, ": ", array, "[", i, "].", member,
                   " must be finite with |coordinate| <= ", oracle::kMaxCoordinate, " (got ", p.x, ", ", p.y, ", ",
                   p.z, ")");
}

}  // namespace transmittance
}  // namespace detail

namespace reference {

/// The oracle. Construction validates the mesh, the opacities and the medium, drops degenerate
/// triangles and builds the BVH; every query is const and may run concurrently.
/// Value: double (grey opacity) or glm::dvec3 (RGB opacity).
template <typename Value>
class BasicTransmittanceOracle {
    static_assert(std::is_same_v<Value, double> || std::is_same_v<Value, glm::dvec3>,
                  "BasicTransmittanceOracle: Value must be double or glm::dvec3");

public:
    using value_type = Value;

    /// Triangle i is (indices[3i], indices[3i+1], indices[3i+2]); every triangle has `opacity`.
    /// Position: glm::dvec3 or glm::vec3 (converted to double exactly).
    template <typename Position>
    BasicTransmittanceOracle(const std::vector<Position>& positions, const std::vector<uint32_t>& indices,
                             const Value& opacity, const HomogeneousMedium& medium = {}) {
        build(positions, indices, medium);
        checkOpacity(opacity, nullptr);
        opacity_.assign(triangle_count_, opacity);
    }

    /// One opacity per triangle: Source float or double (TransmittanceOracle), glm::dvec3 or
    /// glm::vec3 (ColourTransmittanceOracle).
    template <typename Position, typename Source>
    BasicTransmittanceOracle(const std::vector<Position>& positions, const std::vector<uint32_t>& indices,
                             const std::vector<Source>& opacities, const HomogeneousMedium& medium = {}) {
        static_assert(std::is_same_v<Value, double> ? (std::is_same_v<Source, float> || std::is_same_v<Source, double>)
                                                    : (std::is_same_v<Source, glm::dvec3> ||
                                                       std::is_same_v<Source, glm::vec3>),
                      "per-triangle opacities: float/double for TransmittanceOracle, glm::dvec3/vec3 for "
                      "ColourTransmittanceOracle");
        build(positions, indices, medium);
        PENUMBRA_CHECK(opacities.size() == triangle_count_, "TransmittanceOracle: ", opacities.size(),
                       " opacities for ", triangle_count_, " triangles (need one per triangle)");
        opacity_.resize(triangle_count_);
        for (size_t i = 0; i < triangle_count_; ++i) {
            opacity_[i] = Value(opacities[i]);
            checkOpacity(opacity_[i], &i);
        }
    }

    /// Number of triangles in the caller's list (degenerate ones included).
    size_t triangleCount() const { return triangle_count_; }
    /// Triangles dropped as degenerate (they never attenuate).
    size_t degenerateTriangleCount() const { return triangle_count_ - bvh_.triangles().size(); }
    const HomogeneousMedium& medium() const { return medium_; }
    /// E of the tolerances' scale (VisibilityOracle::sceneExtent() of the same mesh; 0 when empty).
    double sceneExtent() const { return scene_extent_; }
    /// The opacity of the caller's triangle `triangle`.
    const Value& opacity(size_t triangle) const {
        PENUMBRA_ASSERT(triangle < triangle_count_);
        return opacity_[triangle];
    }

    /// Transmittance of the open segment (p, q) (options.threads is ignored).
    TransmittanceResult<Value> transmittance(const glm::dvec3& p, const glm::dvec3& q,
                                             const TransmittanceOptions& options = {}) const {
        return single(p, q, options, false, "transmittance");
    }
    /// The same from a loop over all triangles, without the BVH: bit-identical (for tests).
    TransmittanceResult<Value> transmittanceBruteForce(const glm::dvec3& p, const glm::dvec3& q,
                                                       const TransmittanceOptions& options = {}) const {
        return single(p, q, options, true, "transmittanceBruteForce");
    }

    /// The medium's factor exp(-sigma_t L) alone for the segment (p, q) (1 without a medium).
    double mediumTransmittance(const glm::dvec3& p, const glm::dvec3& q) const {
        ::penumbra::detail::oracle::checkPoint(p, "mediumTransmittance", "p");
        ::penumbra::detail::oracle::checkPoint(q, "mediumTransmittance", "q");
        return mediumFactor(::penumbra::detail::transmittance::boxLength(medium_.lo, medium_.hi, p, q));
    }

    /// Many segments through the BVH, on options.threads threads.
    TransmittanceBatch<Value> evaluate(const std::vector<TransmittanceSegment>& segments,
                                       const TransmittanceOptions& options = {}) const {
        return evaluateImpl(segments, options, false, "evaluate");
    }
    /// The same over every triangle, without the BVH: bit-identical to evaluate().
    TransmittanceBatch<Value> evaluateBruteForce(const std::vector<TransmittanceSegment>& segments,
                                                 const TransmittanceOptions& options = {}) const {
        return evaluateImpl(segments, options, true, "evaluateBruteForce");
    }

    /// sum w_i T_i / sum w_i over the taps (evaluated like evaluate(), summed in tap order).
    FilteredTransmittance<Value> filteredTransmittance(const std::vector<FilterTap>& taps,
                                                       const TransmittanceOptions& options = {}) const {
        namespace oracle = ::penumbra::detail::oracle;
        const char* function = "filteredTransmittance";
        oracle::checkOptions(options, function);
        PENUMBRA_CHECK(!taps.empty(), function, ": no taps (the weight sum must be non-zero)");
        double total = 0.0;
        std::vector<TransmittanceSegment> segments(taps.size());
        for (size_t i = 0; i < taps.size(); ++i) {
            const double w = taps[i].weight;
            PENUMBRA_CHECK(std::isfinite(w) && w > 0.0, function, ": taps[", i, "].weight must be finite and > 0 (got ",
                           w, ")");
            ::penumbra::detail::transmittance::checkIndexedPoint(taps[i].p, function, "taps", i, "p");
            ::penumbra::detail::transmittance::checkIndexedPoint(taps[i].q, function, "taps", i, "q");
            segments[i] = TransmittanceSegment{taps[i].p, taps[i].q};
            total += w;
        }
        PENUMBRA_CHECK(std::isfinite(total), function, ": the sum of the weights overflows (got ", total, ")");
        const TransmittanceBatch<Value> batch = evaluateImpl(segments, options, false, function);
        Value sum(0.0);
        double tie_weight = 0.0;
        FilteredTransmittance<Value> result;
        for (size_t i = 0; i < taps.size(); ++i) {
            sum += ::penumbra::detail::transmittance::weighted(batch.results[i].transmittance, taps[i].weight);
            if (batch.results[i].tie) {
                tie_weight += taps[i].weight;
                ++result.tie_taps;
            }
        }
        result.transmittance = sum / total;
        result.tie = result.tie_taps > 0;
        result.tie_weight_fraction = tie_weight / total;
        return result;
    }

    /// Every crossing of origin + t * direction for 0 < t < t_max, sorted by t then triangle: the
    /// exact visibility function of a light ray without the medium (see the header comment).
    RayTransmittance<Value> transmittanceAlongRay(const glm::dvec3& origin, const glm::dvec3& direction, double t_max,
                                                  const TransmittanceOptions& options = {}) const {
        namespace oracle = ::penumbra::detail::oracle;
        namespace tr = ::penumbra::detail::transmittance;
        const char* function = "transmittanceAlongRay";
        oracle::checkOptions(options, function);
        oracle::checkPoint(origin, function, "origin");
        oracle::checkPoint(direction, function, "direction");
        PENUMBRA_CHECK(direction != glm::dvec3(0.0), function, ": direction must be non-zero");
        PENUMBRA_CHECK(std::isfinite(t_max) && t_max > 0.0, function, ": t_max must be finite and > 0 (got ", t_max,
                       ")");
        RayTransmittance<Value> result;
        // Products kept opaque: with an FMA the end point (hence every bit) would depend on flags.
        result.end = origin + glm::dvec3(oracle::mul(t_max, direction.x), oracle::mul(t_max, direction.y),
                                         oracle::mul(t_max, direction.z));
        oracle::checkPoint(result.end, function, "origin + t_max * direction");
        if (result.end == origin) return result;
        std::vector<tr::Crossing> crossings;
        oracle::Counters counters;
        tr::allHits(bvh_, oracle::makeSegmentQuery(origin, result.end, options, scene_extent_), crossings, counters);
        for (const tr::Crossing& c : crossings) {
            result.fragile_triangles += c.fragile;
            if (c.hit) result.steps.push_back(RayStep<Value>{c.t * t_max, opacity_[c.triangle], c.triangle, c.fragile});
        }
        std::sort(result.steps.begin(), result.steps.end(), [](const RayStep<Value>& a, const RayStep<Value>& b) {
            return a.t < b.t || (a.t == b.t && a.triangle < b.triangle);
        });
        Value product(1.0);
        for (RayStep<Value>& step : result.steps) {
            product = product * (Value(1.0) - step.opacity);
            step.transmittance = product;
        }
        result.tie = result.fragile_triangles > 0;
        return result;
    }

private:
    template <typename Position>
    void build(const std::vector<Position>& positions, const std::vector<uint32_t>& indices,
               const HomogeneousMedium& medium) {
        static_assert(std::is_same_v<Position, glm::dvec3> || std::is_same_v<Position, glm::vec3>,
                      "positions: glm::dvec3 or glm::vec3");
        if constexpr (std::is_same_v<Position, glm::vec3>) {
            buildMesh(std::vector<glm::dvec3>(positions.begin(), positions.end()), indices);
        } else {
            buildMesh(positions, indices);
        }
        checkMedium(medium);
        medium_ = medium;
    }

    // The oracle's input rules and triangle list (detail::oracle::oracleTriangles), then the same BVH.
    void buildMesh(const std::vector<glm::dvec3>& positions, const std::vector<uint32_t>& indices) {
        std::vector<::penumbra::detail::oracle::Triangle> triangles =
            ::penumbra::detail::oracle::oracleTriangles(positions, indices, "TransmittanceOracle");
        triangle_count_ = indices.size() / 3;
        scene_extent_ = ::penumbra::detail::oracle::sceneExtent(triangles);
        linear_ = triangles;  // caller order, for the brute-force paths
        bvh_.build(std::move(triangles));
    }

    static void checkMedium(const HomogeneousMedium& medium) {
        namespace oracle = ::penumbra::detail::oracle;
        PENUMBRA_CHECK(std::isfinite(medium.sigma_t) && medium.sigma_t >= 0.0,
                       "TransmittanceOracle: medium.sigma_t must be finite and >= 0 (got ", medium.sigma_t, ")");
        oracle::checkPoint(medium.lo, "TransmittanceOracle", "medium.lo");
        oracle::checkPoint(medium.hi, "TransmittanceOracle", "medium.hi");
        for (int k = 0; k < 3; ++k) {
            PENUMBRA_CHECK(medium.lo[k] <= medium.hi[k], "TransmittanceOracle: medium.lo[", k, "] = ", medium.lo[k],
                           " exceeds medium.hi[", k, "] = ", medium.hi[k]);
        }
    }

    /// `triangle` null: the one opacity of every triangle.
    static void checkOpacity(const Value& opacity, const size_t* triangle) {
        namespace tr = ::penumbra::detail::transmittance;
        for (int k = 0; k < tr::channels(opacity); ++k) {
            const double a = tr::channel(opacity, k);
            if (a >= 0.0 && a <= 1.0) continue;  // NaN fails both
            std::string what = triangle ? "opacity of triangle " + std::to_string(*triangle) : std::string("opacity");
            if (tr::channels(opacity) > 1) what += " (channel " + std::to_string(k) + ")";
            ::penumbra::detail::fail("TransmittanceOracle: ", what, " must be finite and in [0, 1] (got ", a, ")");
        }
    }

    double mediumFactor(double length) const {
        if (medium_.sigma_t == 0.0) return 1.0;
        return std::exp(-::penumbra::detail::oracle::mul(medium_.sigma_t, length));
    }

    TransmittanceResult<Value> single(const glm::dvec3& p, const glm::dvec3& q, const TransmittanceOptions& options,
                                      bool brute_force, const char* function) const {
        ::penumbra::detail::oracle::checkOptions(options, function);
        ::penumbra::detail::oracle::checkPoint(p, function, "p");
        ::penumbra::detail::oracle::checkPoint(q, function, "q");
        std::vector<::penumbra::detail::transmittance::Crossing> scratch;
        ::penumbra::detail::oracle::Counters counters;
        return query(p, q, options, brute_force, scratch, counters);
    }

    TransmittanceResult<Value> query(const glm::dvec3& p, const glm::dvec3& q, const TransmittanceOptions& options,
                                     bool brute_force, std::vector<::penumbra::detail::transmittance::Crossing>& scratch,
                                     ::penumbra::detail::oracle::Counters& counters) const {
        namespace oracle = ::penumbra::detail::oracle;
        namespace tr = ::penumbra::detail::transmittance;
        TransmittanceResult<Value> result;
        result.medium_length = tr::boxLength(medium_.lo, medium_.hi, p, q);
        result.medium = mediumFactor(result.medium_length);
        if (p != q) {
            scratch.clear();
            const oracle::SegmentQuery segment = oracle::makeSegmentQuery(p, q, options, scene_extent_);
            if (brute_force) {
                for (const oracle::Triangle& tri : linear_) {
                    ++counters.tests;
                    tr::classify(tri, segment, scratch);
                }
            } else {
                tr::allHits(bvh_, segment, scratch, counters);
                // Caller order, as the brute-force loop: the product's bits do not depend on the BVH.
                std::sort(scratch.begin(), scratch.end(),
                          [](const tr::Crossing& a, const tr::Crossing& b) { return a.triangle < b.triangle; });
            }
            for (const tr::Crossing& c : scratch) {
                result.fragile_triangles += c.fragile;
                if (!c.hit) continue;
                ++result.hits;
                result.surfaces = result.surfaces * (Value(1.0) - opacity_[c.triangle]);
            }
        }
        result.tie = result.fragile_triangles > 0;
        result.transmittance = result.surfaces * result.medium;
        return result;
    }

    TransmittanceBatch<Value> evaluateImpl(const std::vector<TransmittanceSegment>& segments,
                                           const TransmittanceOptions& options, bool brute_force,
                                           const char* function) const {
        namespace oracle = ::penumbra::detail::oracle;
        oracle::checkOptions(options, function);
        for (size_t i = 0; i < segments.size(); ++i) {
            ::penumbra::detail::transmittance::checkIndexedPoint(segments[i].p, function, "segments", i, "p");
            ::penumbra::detail::transmittance::checkIndexedPoint(segments[i].q, function, "segments", i, "q");
        }
        TransmittanceBatch<Value> batch;
        batch.results.resize(segments.size());
        if (segments.empty()) return batch;

        unsigned threads = options.threads != 0 ? options.threads : std::thread::hardware_concurrency();
        threads = std::max(threads, 1u);
        const size_t chunk = std::max<size_t>(1, segments.size() / (size_t(threads) * 16));
        const size_t chunks = (segments.size() + chunk - 1) / chunk;
        threads = static_cast<unsigned>(std::min<size_t>(threads, chunks));

        std::atomic<size_t> next_chunk{0};
        std::vector<oracle::Counters> counters(threads);
        const auto work = [&](unsigned worker) {
            oracle::Counters local;
            std::vector<::penumbra::detail::transmittance::Crossing> scratch;
            for (size_t c = next_chunk.fetch_add(1); c < chunks; c = next_chunk.fetch_add(1)) {
                const size_t end = std::min(segments.size(), (c + 1) * chunk);
                for (size_t i = c * chunk; i < end; ++i)
                    batch.results[i] = query(segments[i].p, segments[i].q, options, brute_force, scratch, local);
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
            batch.nodes_visited += c.nodes;
            batch.triangle_tests += c.tests;
        }
        for (const TransmittanceResult<Value>& r : batch.results) batch.tie_count += r.tie;
        return batch;
    }

    size_t triangle_count_ = 0;
    double scene_extent_ = 0;  // E of the tolerances' scale: VisibilityOracle's, on the same triangles
    std::vector<Value> opacity_;                    // caller's triangle order
    HomogeneousMedium medium_;
    std::vector<::penumbra::detail::oracle::Triangle> linear_;  // non-degenerate, caller order
    ::penumbra::detail::oracle::Bvh bvh_;
};

/// Grey opacities: transmittance as double.
using TransmittanceOracle = BasicTransmittanceOracle<double>;
/// RGB opacities: transmittance per channel as glm::dvec3.
using ColourTransmittanceOracle = BasicTransmittanceOracle<glm::dvec3>;

}  // namespace reference
}  // namespace penumbra

#endif
