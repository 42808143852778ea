// penumbra/penumbra_casting.hpp — hierarchical penumbra casting on the CPU (laine2005 §3).
//
// Integration summary
//   Needs:    receiver points (a list: e.g. the G-buffer's surface points, any order, glm::dvec3),
//             a light (penumbra::Light: Disk / Rectangle are planar, Sphere / Ellipsoid volumetric)
//             with its K light-sample sets (penumbra/light_samples.hpp, makeLightSampleSets: N
//             samples per set, 8 sets by default), and blocker triangles streamed one at a time
//             (PenumbraCaster::addTriangle, or penumbraCast's callback). No scene hierarchy is ever
//             built and the geometry never has to be in memory at once: the caster buffers a
//             bounded batch (options.batch_triangles). Header-only: GLM, the C++17 standard
//             library, std::thread. No GPU, no GL.
//   Produces: per receiver an N-bit "blocked" mask and an N-bit "tie" mask, in the layout of
//             reference::VisibilityResult (bit s % 32 of word [r * words_per_receiver + s / 32]:
//             receiver r and sample s of ITS set), the visible fraction, and work counters.
//   Hooks:    none. Optional progress callback (also cancels).
//
//   Typical use:
//       const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {256, 8});
//       penumbra::PenumbraCaster caster(receivers, light, sets);
//       for (each triangle a, b, c of the scene, streamed) caster.addTriangle(a, b, c);
//       const penumbra::PenumbraCastingResult shadow = caster.finish();
//       // Every frame: caster.finish(last_result) (or penumbraCast(last_result, ...)) writes into
//       // last frame's result and allocates none of its R N / 16 bytes of bits again.
//       // shadow.visibleFraction(r), or the bits of receiver r against sets.worldSet(shadow.receiver_sets[r]).
//
// ---------------------------------------------------------------------------------------------
// Semantics: the oracle's, bit for bit (reference/visibility.hpp, "Semantics of one pair").
// Receiver r uses light-sample set receiver_sets[r] (default: r % K, K = sets.sets(); laine2005
// §3.4: one set per receiver, consistently). For the pair (receiver p, sample s of that set) the
// result equals VisibilityOracle::evaluate over the streamed (non-degenerate) triangles with the
// same samples and options.oracle: blocked = some triangle hits the open segment, tie = no robust
// hit and some fragile verdict (coplanar rule, locality rule, p == s never blocked). Every
// candidate pair is decided by the oracle's own per-triangle classification
// (detail::oracle::classifySegment) or by a certified fast verdict that provably equals it (see
// "Certified verdicts" below); the hierarchy only culls (triangle, pair) combinations that
// cannot give a verdict, with margins far above the oracle's tolerances (see "Culling" below), and
// the umbra shortcuts only skip pairs that already hold a ROBUST hit (whose bits can no longer
// change). The bits therefore do not depend on the triangle order, the batch size, the thread
// count or any optimisation switch.
//
// The algorithm (laine2005 §3.2-3.3):
//   - Receiver BVH: axis-aligned boxes; nodes above 1024 points are split at the middle of their
//     box's longest axis (median when that leaves a side empty), smaller ones at the SAH-best
//     position (sorted sweep over the three axes; each SAH subtree sorts its points once per axis
//     and splits the sorted orders stably, so every node sees the order a fresh sort would give,
//     and the subtrees are built on every thread and appended in a fixed order: the same tree
//     for any thread count); leaves hold <= options.leaf_size points.
//   - Light-sample groups: the K * N samples are partitioned spatially (recursive median splits
//     in the light's frame) into G = ceil(N / group_size) regions; group k of set j = the samples
//     of set j in region k (about group_size of them). Each region's bounding polygon (planar
//     light) or box (volumetric light) bounds its samples of ALL sets (§3.4), and so does the
//     light's (the box of all samples in the light's frame: a circumscribed rectangle for a disk,
//     a box for a sphere or ellipsoid).
//   - Per triangle T: the penumbra volume of the light V_L and of each group V_k = the separating
//     planes between T and the bounding polygon/volume (vertex-edge pairs of both), plus T's
//     plane when it does not cut the bound; hard shadow volumes V_i = the 3 planes through the
//     sample and T's edges + T's plane. Traversal from the BVH roots with the list of active
//     groups: a node is left when its box is outside V_L, groups whose V_k misses the box are
//     dropped; at a leaf every receiver inside V_L and V_k is tested against V_i of each sample
//     of its set in group k, and the survivors are classified by the oracle's test.
//   - §3.3 A (options.umbra_bits): group-umbra bits (all samples of group k of the receiver's set
//     robustly blocked) and full-umbra bits on receivers and nodes (AND of the children) stop
//     the traversal and prune groups; the BVH is rebuilt over the remaining receivers when a
//     quarter of its receivers are in full umbra (checked between chunks of 4096 triangles).
//     B (active_planes): a plane whose half-space contains the node's box is not tested below it.
//     C (lazy_volumes): V_k and V_i are built on first need (off: all of them for every triangle
//     that reaches a root). D (on_demand_masks): a receiver's masks are allocated at its first
//     verdict and released when it is in full umbra (off: all robust masks up front).
//     Coarse blocker sorting (area_sort): each buffered batch is processed in buckets of
//     floor(log2(area)), largest first, arrival order inside a bucket.
//   - Threads: the BVH is cut into up to 64 subtrees (a breadth-first frontier, independent of
//     the thread count); each chunk of triangles is processed subtree by subtree, subtrees
//     handed out dynamically to options.threads threads. A subtree's receivers, masks and umbra
//     bits belong to the one thread processing it, so nothing is shared and the bits — and every
//     counter except mask_bytes_peak — are deterministic.
//
// Culling (why the bits stay the oracle's). Let E be the inf-norm extent of the box of all
// receivers, all samples and T (every oracle scale of T is <= E), eps = options.oracle.tie_epsilon,
// delta = E * (16 eps + 64 * 2^-52 / max(eps, 2^-40) + 1e-12) and eta = 2 eps + delta / E. A robust
// hit means the exact segment [p, s] meets T (the sheared-frame margin eps * scale of rule 3b
// bounds the error of t by ~2^-52 / eps of T's size), and a fragile verdict means the segment,
// extended by eta at both ends, passes within delta of T. A plane with T on its positive side and
// every sample within h of its negative side then holds every such p up to
//     margin = (delta + eta * R + rounding) * max(1, 2E / (D - delta)),
// D a lower bound of the distance from T to the samples and R of |plane(sample)|; a node, receiver
// or pair is culled only when it is farther than the margin outside. Volumes are not used (no
// culling at that level) when D <= 2 (delta + 2 eta E): a triangle touching the light or a
// group's bound, or a sample within that distance of T. The near-parallel configurations whose t
// is meaningless (|n.d| ~ 2^-52 of |n| |d|) can only be fragile verdicts and are only caught when
// they lie within delta. Exactness therefore holds for tie_epsilon >= 1e-12 (the default is
// 1e-9); below, delta grows towards E and culling fades out.
//
// Certified verdicts (options.certified_fast_path, default on; off: every surviving pair goes to
// classifySegment as before, with the same bits). Per (T, receiver p) reaching a leaf:
//   - Coplanar skip. The oracle's side_p = dot3(n, v0 - p) and pointTriangleDistance2(p, T) depend
//     on T and p only; its limit and reach grow monotonically with its scale = max(|s - p|_inf,
//     S_T), S_T = max_i |v_i - p|_inf. Evaluating rule 2 exactly as the oracle does with S_T for
//     the scale therefore proves "T ignored for every sample": the relation is skipped whole
//     (stats.coplanar_skips; receivers on T itself, the bulk of on-surface work).
//   - Shadow pyramid (laine2005's hard volume seen from p instead of s): unit normals n_e of the
//     planes through p and T's edges (third vertex positive) and T's unit normal oriented so that
//     h_p = dist(p, plane) > 0; per sample d = s - p, h_e = n_e . d, H = n_T . d (t = h_p / H).
//     In the sheared frame of the oracle's ray the 2D distance from the ray's trace to the
//     projected line of edge e is >= dist(p, line e) |h_e| / |d| (the projection lies in the plane
//     through e parallel to d), and the trace is on T's side of it iff h_e H > 0. The oracle's
//     sheared vertices are within 12 u S of the exact ones (u = 2^-53, S >= its scale), its
//     nearEdge rounding is below 23 u S, and with a sheared margin M >= 2^-26 S its t differs
//     from the exact h_p / H by < 2^-20 S / H (vertex displacement times the plane's slope 1/H in
//     the sheared frame, plus the edge functions' rounding over 2 area >= M * perimeter).
//     A pair is a certified ROBUST HIT when h_e >= M dmax / dist(p, e) + err (all e, M = (eps +
//     2^-26) S), eps H < h_p - 2^-20 S and (1 - eps) H > h_p + 2^-20 S (rule 3a, t in (eps,
//     1 - eps)), h_p and H - h_p > cop S + 48 u kappa S (rule 2 not triggered and rule 3c's
//     plane sides certain: kappa = |e1| |e2| / |n| bounds the oracle's side error), all with
//     the computed quantities' error bounds (normals' 32 u conditioning, dmax >= |s - p|) added;
//     rule 4's slab test passes since the exact hit point lies in T's box and the box grows by
//     >= 1e-12 of its scale. It is a certified CLEAR MISS when |H| > err and some edge has h_e of
//     the other sign with |h_e| >= (eps (1 + 2^-40) + 2^-40) S dmax / dist(p, e) + err: the trace
//     is then farther than eps * scale plus every rounding from the whole computed triangle, so
//     the oracle is "not inside, not near an edge" and returns at once. It is a certified
//     BACKWARD MISS when the trace is inside with the hit's edge margins (h_e <= -hit_e: h_e H > 0
//     with H < 0) and -H < (h_p - 2^-20 S) / eps (minus err), with h_p > 48 u kappa S: the line
//     crosses T robustly at t = h_p / H < -eps (the oracle's t is within 2^-20 S / |H| of it, as
//     for hits), so rule 3a sees no hit and no tie, rule 3b no near edge (the margin), and rule 3c
//     sees p and s on the same side of T's plane (s is farther than p, both beyond the oracle's
//     side error): it returns no verdict. These are the receivers of a convex surface against
//     its neighbouring facets (the light's side of the surface: the line crosses the neighbour
//     just behind p): on columns they were 93% of the band.
//   - Miss-only pyramid (when the pyramid above is ill-conditioned: p within rounding of T's
//     plane or of an edge's line, e.g. receivers on T's plane outside its coplanar reach, on a
//     coplanar or adjacent face sharing an edge or vertex with T; on columns these were 93% of the
//     classified pairs). The orientation tests through p are what fails there, and only the
//     clear-miss test needs no orientation through p: with n_e = unit((v_a - p) x (v_b - v_a))
//     NOT oriented by the third vertex and T's own unit normal n_T (of (v1 - v0) x (v2 - v0), NOT
//     oriented by p), the triple products U_e = d . ((v_a - p) x (v_b - v_a)) = |..| h_e sum to
//     N . d, and U_e / d_kz, N . d / d_kz are the edge function of the trace and twice the signed
//     area of the projected T in the oracle's sheared frame, for EVERY p. So the trace is on the
//     far side of edge e's line iff h_e and H have opposite signs, at a 2D distance >=
//     dist(p, line e) |h_e| / |d|, and the clear-miss thresholds above apply unchanged (same
//     normals up to sign, same error bounds). Edges whose plane is unusable (p on the edge's
//     line, conditioning > 1e6) never certify; hits are not certified; the remaining pairs take
//     the hard volumes and classifySegment as before.
//     Everything else (no usable normal or edge plane; pairs in the bands) goes to
//     classifySegment. Own rounding: every bound is inflated by (1 + 2^-40) per
//     step; FMA contraction only lowers the errors bounded. The whole group is decided at once
//     when its bound's vertices (plus slack) all certify (group hit: OR of the group's mask).
//     Backward misses are decided per group the same way (bound's vertices plus slack).
//     stats.pairs_certified / pairs_certified_hits count pairs so decided, pairs_classified
//     (= pairs_tested) the oracle's classifications. Valid for every tie_epsilon and
//     coplanar_epsilon in [0, 0.1]; tests/penumbra_casting_test.cpp checks every certified
//     verdict of adversarial configurations against classifySegment of that triangle alone.
//
// Degenerate input:
//   - A triangle with a NaN / infinite vertex or |coordinate| > 1e50 -> addTriangle throws
//     penumbra::Error naming the triangle's number (in the stream) and the vertex; the caster stays
//     usable (the triangle is not buffered).
//   - A degenerate triangle (penumbra::detail::degenerateTriangle: zero area, repeated or
//     collinear vertices, slivers) is dropped and counted (stats.triangles_degenerate), as the
//     oracle drops it.
//   - A receiver on a blocker's plane: the coplanar rule (the oracle's) leaves it unblocked by
//     that blocker.
//   - A light of zero area or volume: makeLightSampleSets rejects a zero size, so a point light
//     is given as LightSampleSets whose world samples coincide (e.g. every world[] set to the
//     centre): the bounds degenerate to segments or points and every pair is still decided as
//     the oracle decides it with those samples (all N bits of a receiver equal).
//   - No receivers, no triangles: valid (empty / all-visible result).
//   - Bad arguments (penumbra::Error naming the value): receivers or light samples not finite or
//     beyond 1e50, more than 2^32 - 1 receivers, sets.world of the wrong size, receiver_sets of the
//     wrong size or naming a set >= K, leaf_size or group_size 0, batch_triangles 0, oracle
//     epsilons outside [0, 0.1]; addTriangle / finish after finish().
//
// Memory: the receivers, K * N samples, per receiver one N-bit robust mask while it has a robust
// hit and is not in full umbra (plus 2 N bits while it has a non-robust verdict), the BVH, one
// batch of triangles (72 bytes each) and per thread K * N hard volumes (~140 bytes
// each). stats.mask_bytes_peak measures the masks against R * N / 8 (stats.mask_bytes_full).
//
// Progress and cancellation: options.progress(fraction) is called on the calling thread between
// subtrees and chunks, fraction = processed / received triangles so far (while streaming the
// total is unknown, so it can go down when more triangles arrive), and once with 1.0 at the end
// of finish(). Returning false cancels: processing stops at the next subtree boundary, further
// triangles are ignored, and finish() returns stats.cancelled = true with the bits of an
// unspecified subset of the (triangle, subtree) work done so far: not a usable shadow.
#ifndef PENUMBRA_PENUMBRA_CASTING_HPP
#define PENUMBRA_PENUMBRA_CASTING_HPP

#include <penumbra/detail/geometry.hpp>
#include <penumbra/error.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/reference/visibility.hpp>

#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

namespace penumbra {

/// Value-initialised = defaults (laine2005 §4: 16 receivers per leaf, 32 samples per group).
struct PenumbraCastingOptions {
    uint32_t leaf_size = 16;             ///< receivers per BVH leaf (>= 1)
    uint32_t group_size = 32;            ///< light samples per group, on average per set (>= 1)
    bool umbra_bits = true;              ///< §3.3 A: group / full umbra bits, BVH rebuild
    bool active_planes = true;           ///< §3.3 B: active plane sets
    bool lazy_volumes = true;            ///< §3.3 C: build V_k and V_i on first need
    bool on_demand_masks = true;         ///< §3.3 D: allocate masks at the first verdict, free in umbra
    bool area_sort = true;               ///< coarse blocker sorting: area buckets, largest first
    bool certified_fast_path = true;     ///< decide pairs without the oracle where provably safe (see "Certified verdicts")
    unsigned threads = 0;                ///< 0: std::thread::hardware_concurrency()
    uint32_t batch_triangles = 65536;    ///< triangles buffered (and area-sorted) before processing
    reference::VisibilityOptions oracle; ///< tie / coplanar epsilons, as the oracle (threads ignored)
    /// E capping the segment's length in the oracle's tolerances (> 0): VisibilityOracle::sceneExtent()
    /// of the whole mesh streamed (the caster sees it a batch at a time, so it cannot compute it).
    /// +inf = the uncapped rule: lights ~1 / coplanar_epsilon scene sizes away lose their shadows.
    double scene_extent = std::numeric_limits<double>::infinity();
    std::function<bool(double fraction)> progress;  ///< optional; return false to cancel
};

/// Work counters. All are deterministic (independent of the thread count) except
/// mask_bytes_peak with more than one thread.
struct PenumbraCastingStats {
    uint64_t triangles = 0;             ///< received (degenerate ones included)
    uint64_t triangles_degenerate = 0;  ///< dropped by detail::degenerateTriangle
    uint64_t triangles_near_light = 0;  ///< no light penumbra volume (T too close to the light)
    uint64_t pairs_tested = 0;          ///< oracle classifications (detail::oracle::classifySegment)
    uint64_t pairs_classified = 0;      ///< the same count as pairs_tested (the name the fast path's reports use)
    uint64_t pairs_certified = 0;       ///< candidate pairs decided by the certified fast path (hits + misses)
    uint64_t pairs_certified_hits = 0;  ///< of which robust hits
    uint64_t coplanar_skips = 0;        ///< (triangle, receiver) relations skipped whole: the coplanar rule ignores T for p
    uint64_t pyramids_built = 0;        ///< per-(triangle, receiver) shadow pyramids built (certified fast path)
    uint64_t pairs_hard_culled = 0;     ///< candidate pairs rejected by a hard shadow volume
    uint64_t nodes_visited = 0;         ///< BVH nodes entered
    uint64_t umbra_skips = 0;           ///< nodes and groups skipped thanks to umbra bits
    uint64_t group_volumes_built = 0;   ///< penumbra volumes V_k
    uint64_t hard_volumes_built = 0;    ///< hard shadow volumes V_i
    uint64_t rebuilds = 0;              ///< BVH rebuilds (§3.3 A), the first build not counted
    uint64_t ties = 0;                  ///< set tie bits in the result
    uint64_t mask_bytes_peak = 0;       ///< peak bytes of per-receiver masks held at once
    uint64_t mask_bytes_full = 0;       ///< R * N / 8: one bit per pair
    uint32_t groups = 0;                ///< G
    bool cancelled = false;
};

struct PenumbraCastingResult {
    uint32_t samples = 0;                 ///< N per receiver
    size_t words_per_receiver = 0;        ///< N / 32
    std::vector<uint32_t> blocked, ties;  ///< same layout as reference::VisibilityResult
    std::vector<uint32_t> receiver_sets;  ///< the set each receiver used
    PenumbraCastingStats stats;

    size_t receivers() const { return receiver_sets.size(); }
    bool isBlocked(size_t r, uint32_t s) const { return (blocked[r * words_per_receiver + s / 32] >> (s % 32)) & 1u; }
    bool isTie(size_t r, uint32_t s) const { return (ties[r * words_per_receiver + s / 32] >> (s % 32)) & 1u; }
    /// 1 - (blocked samples) / N; 1 when N == 0.
    double visibleFraction(size_t r) const {
        PENUMBRA_ASSERT(r < receiver_sets.size());
        if (samples == 0) return 1.0;
        uint32_t count = 0;
        for (size_t w = 0; w < words_per_receiver; ++w)
            count += detail::oracle::popcount32(blocked[r * words_per_receiver + w]);
        return 1.0 - static_cast<double>(count) / static_cast<double>(samples);
    }
};

namespace detail {
namespace casting {

inline constexpr uint32_t kMaxPlanes = 24;           // more separating planes are dropped (conservative)
inline constexpr uint32_t kHalvingThreshold = 1024;  // laine2005 §3.2: halve the box above 1K points
inline constexpr uint32_t kRootTarget = 64;          // subtrees handed to threads
inline constexpr uint32_t kChunkTriangles = 4096;    // rebuild checks / progress granularity
inline constexpr double kUlp = 0x1p-52;
inline constexpr double kMaxConditioning = 1e6;      // 1 / sin of a plane's spanning angle

/// One half-space n . (p - o) >= -margin (n unit length).
struct Plane {
    glm::dvec3 n{0.0};
    glm::dvec3 o{0.0};
    double margin = 0.0;
};

/// Intersection of half-spaces; culls == false means "everything" (no usable plane or gap).
struct Volume {
    bool culls = false;
    uint32_t count = 0;
    std::array<Plane, kMaxPlanes> planes;
    uint32_t allMask() const { return count >= 32 ? 0xffffffffu : ((1u << count) - 1u); }
};

/// Hard shadow volume of T from one sample: planes 0..2 through the sample (anchor s), 3 T's plane.
struct HardVolume {
    bool culls = false;
    glm::dvec3 n[4];
    double margin[4] = {0, 0, 0, 0};
};

/// A convex polygon or polyhedron: vertices, edges, and how far samples may lie outside it.
struct Polytope {
    std::vector<glm::dvec3> vertices;
    std::vector<std::pair<uint32_t, uint32_t>> edges;
    double slack = 0.0;
    glm::dvec3 centroid{0.0};
};

/// Error scales of one triangle's culling tests.
struct Tolerance {
    double delta = 0;    // distance slack of a verdict
    double eta = 0;      // parameter slack of a verdict
    double span = 0;     // 2E >= any |p - s|, |p - v|
    double abs_err = 0;  // rounding of differences of absolute coordinates
};

inline double maxAbs3(const glm::dvec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

/// Index of the lowest set bit of a non-zero word.
inline uint32_t lowestBit(uint32_t bits) {
#if defined(__GNUC__) || defined(__clang__)
    return static_cast<uint32_t>(__builtin_ctz(bits));
#else
    uint32_t i = 0;
    while (!(bits & 1u)) bits >>= 1, ++i;
    return i;
#endif
}

/// Index of the lowest set bit of a non-zero 64-bit word.
inline uint32_t lowestBit64(uint64_t bits) {
#if defined(__GNUC__) || defined(__clang__)
    return static_cast<uint32_t>(__builtin_ctzll(bits));
#else
    uint32_t i = 0;
    while (!(bits & 1ull)) bits >>= 1, ++i;
    return i;
#endif
}

/// Unit normal of a x b and a bound of its error (relative); false when ill-conditioned.
inline bool unitCross(const glm::dvec3& a, const glm::dvec3& b, glm::dvec3& n, double& err) {
    const glm::dvec3 c = glm::cross(a, b);
    const double len = glm::length(c);
    const double la = glm::length(a), lb = glm::length(b);
    if (!(len > 0.0) || !(la > 0.0) || !(lb > 0.0)) return false;
    const double conditioning = (la * lb) / len;
    if (!(conditioning <= kMaxConditioning)) return false;
    n = c / len;
    err = 16.0 * kUlp * conditioning;
    return true;
}

/// Rounding of evaluating a plane with normal error `normal_err` at distances <= span.
inline double evalError(const Tolerance& tol, double normal_err) {
    return normal_err * tol.span + 8.0 * kUlp * tol.span + tol.abs_err;
}

/// Lower bound of the distance between T and every sample bounded by P.
inline double gapLowerBound(const glm::dvec3 (&t)[3], const Polytope& poly, const glm::dvec3& t_normal, bool t_normal_ok,
                            const Tolerance& tol, const std::vector<glm::dvec3>& extra_directions) {
    double best = -std::numeric_limits<double>::infinity();
    const auto tryDirection = [&](const glm::dvec3& w) {
        double min_t = std::numeric_limits<double>::infinity(), max_p = -std::numeric_limits<double>::infinity();
        for (const glm::dvec3& v : t) min_t = std::min(min_t, glm::dot(w, v - poly.centroid));
        for (const glm::dvec3& x : poly.vertices) max_p = std::max(max_p, glm::dot(w, x - poly.centroid));
        best = std::max(best, min_t - max_p);
    };
    if (t_normal_ok) {
        tryDirection(t_normal);
        tryDirection(-t_normal);
    }
    const glm::dvec3 d = (t[0] + t[1] + t[2]) / 3.0 - poly.centroid;
    const double len = glm::length(d);
    if (len > 0.0) tryDirection(d / len);
    for (const glm::dvec3& w : extra_directions) tryDirection(w);
    return best - poly.slack - evalError(tol, 1e-12);
}

/// Plane with T on its positive side and P on its negative one, or false; sets its margin.
inline bool finishSeparatingPlane(glm::dvec3 n, const glm::dvec3& o, double normal_err, const glm::dvec3 (&t)[3],
                                  const Polytope& poly, double gap, const Tolerance& tol, Plane& out) {
    const double err = evalError(tol, normal_err);
    for (int attempt = 0; attempt < 2; ++attempt, n = -n) {
        double min_t = std::numeric_limits<double>::infinity(), max_p = -std::numeric_limits<double>::infinity();
        double max_abs_p = 0.0;
        for (const glm::dvec3& v : t) min_t = std::min(min_t, glm::dot(n, v - o));
        for (const glm::dvec3& x : poly.vertices) {
            const double e = glm::dot(n, x - o);
            max_p = std::max(max_p, e);
            max_abs_p = std::max(max_abs_p, std::fabs(e));
        }
        if (min_t < -err || max_p > err) continue;
        const double rho_t = std::max(0.0, -min_t) + err;
        const double h = std::max(0.0, max_p) + poly.slack + err;
        const double r = max_abs_p + poly.slack + err;
        const double factor = std::max(1.0, tol.span / (gap - tol.delta));
        out.n = n;
        out.o = o;
        out.margin = (tol.delta + rho_t + h + tol.eta * r) * factor + err;
        return true;
    }
    return false;
}

/// Penumbra volume of T and P (laine2005 §3.2): separating planes from vertex-edge pairs, plus
/// T's plane when it does not cut P. gap: lower bound of dist(T, samples), > 2 (delta + eta span).
inline void buildPenumbraVolume(const glm::dvec3 (&t)[3], const glm::dvec3& t_normal, double t_normal_err, bool t_normal_ok,
                                const Polytope& poly, double gap, const Tolerance& tol, Volume& volume) {
    volume.count = 0;
    volume.culls = false;
    if (!(gap > 2.0 * (tol.delta + tol.eta * tol.span))) return;
    const auto add = [&](const glm::dvec3& n, const glm::dvec3& o, double err) {
        if (volume.count >= kMaxPlanes) return;  // dropping a plane only culls less
        Plane plane;
        if (finishSeparatingPlane(n, o, err, t, poly, gap, tol, plane)) volume.planes[volume.count++] = plane;
    };
    for (int e = 0; e < 3; ++e) {
        const glm::dvec3& a = t[e];
        const glm::dvec3& b = t[(e + 1) % 3];
        for (const glm::dvec3& x : poly.vertices) {
            glm::dvec3 n;
            double err = 0;
            if (unitCross(b - a, x - a, n, err)) add(n, a, err);
        }
    }
    for (const auto& edge : poly.edges) {
        const glm::dvec3& a = poly.vertices[edge.first];
        const glm::dvec3& b = poly.vertices[edge.second];
        for (const glm::dvec3& v : t) {
            glm::dvec3 n;
            double err = 0;
            if (unitCross(b - a, v - a, n, err)) add(n, a, err);
        }
    }
    if (t_normal_ok) {
        // The cap: T's plane, oriented away from P, when every sample lies strictly on one side.
        const double err = evalError(tol, t_normal_err);
        double max_p = -std::numeric_limits<double>::infinity(), min_p = std::numeric_limits<double>::infinity();
        for (const glm::dvec3& x : poly.vertices) {
            const double e = glm::dot(t_normal, x - t[0]);
            max_p = std::max(max_p, e);
            min_p = std::min(min_p, e);
        }
        if (max_p + poly.slack + err < 0.0 || min_p - poly.slack - err > 0.0) add(t_normal, t[0], t_normal_err);
    }
    volume.culls = volume.count > 0;
}

/// Box [lo, hi] vs the planes of `mask`: false when it lies outside one of them; with `update`,
/// planes whose half-space holds the whole box leave the mask (§3.3 B).
inline bool boxInside(const Volume& volume, const glm::dvec3& lo, const glm::dvec3& hi, uint32_t& mask, bool update) {
    const glm::dvec3 c = (lo + hi) * 0.5, e = (hi - lo) * 0.5;
    for (uint32_t bits = mask; bits != 0; bits &= bits - 1) {
        const uint32_t i = lowestBit(bits);
        const Plane& plane = volume.planes[i];
        const double d = glm::dot(plane.n, c - plane.o);
        const double r = std::fabs(plane.n.x) * e.x + std::fabs(plane.n.y) * e.y + std::fabs(plane.n.z) * e.z;
        if (d + r < -plane.margin) return false;
        if (update && d - r >= -plane.margin) mask &= ~(1u << i);
    }
    return true;
}

inline bool pointInside(const Volume& volume, const glm::dvec3& p, uint32_t mask) {
    for (uint32_t bits = mask; bits != 0; bits &= bits - 1) {
        const Plane& plane = volume.planes[lowestBit(bits)];
        if (glm::dot(plane.n, p - plane.o) < -plane.margin) return false;
    }
    return true;
}

/// Hard shadow volume of T from sample s (laine2005 §3.2: 3 edge planes + T's plane).
inline void buildHardVolume(const glm::dvec3 (&t)[3], const glm::dvec3& t_normal, double t_normal_err, bool t_normal_ok,
                            const glm::dvec3& s, double gap, const Tolerance& tol, HardVolume& hv) {
    hv.culls = false;
    const double need = 2.0 * (tol.delta + tol.eta * tol.span);
    if (!t_normal_ok) return;
    if (!(gap > need)) {
        const double d2 = penumbra::detail::pointTriangleDistance2<double>(s, t[0], t[1], t[2]);
        gap = std::sqrt(d2) * (1.0 - 1e-6) - evalError(tol, 1e-12);
        if (!(gap > need)) return;
    }
    const double factor = std::max(1.0, tol.span / (gap - tol.delta));
    for (int e = 0; e < 3; ++e) {
        const glm::dvec3& a = t[e];
        const glm::dvec3& b = t[(e + 1) % 3];
        const glm::dvec3& c = t[(e + 2) % 3];
        glm::dvec3 n;
        double normal_err = 0;
        if (!unitCross(b - a, s - a, n, normal_err)) return;
        const double err = evalError(tol, normal_err);
        double side = glm::dot(n, c - s);
        if (side < 0.0) {
            n = -n;
            side = -side;
        }
        if (!(side > err)) return;  // s (nearly) in T's plane: no usable volume
        hv.n[e] = n;
        hv.margin[e] = (tol.delta + err) * factor + err;
    }
    glm::dvec3 n = t_normal;
    const double err = evalError(tol, t_normal_err);
    double side = glm::dot(n, s - t[0]);
    if (side > 0.0) {
        n = -n;
        side = -side;
    }
    if (!(side < -err)) return;
    hv.n[3] = n;
    hv.margin[3] = (tol.delta + err + tol.eta * (-side + err)) * factor + err;
    hv.culls = true;
}

inline bool hardInside(const HardVolume& hv, const glm::dvec3& p, const glm::dvec3& s, const glm::dvec3& v0) {
    const glm::dvec3 ps = p - s;
    if (glm::dot(hv.n[0], ps) < -hv.margin[0]) return false;
    if (glm::dot(hv.n[1], ps) < -hv.margin[1]) return false;
    if (glm::dot(hv.n[2], ps) < -hv.margin[2]) return false;
    return glm::dot(hv.n[3], p - v0) >= -hv.margin[3];
}

/// A box in the light's frame (active axes only) as a polytope in world space.
inline Polytope boxPolytope(const glm::dvec3& center, const glm::dvec3 (&axes)[3], const double (&lo)[3],
                            const double (&hi)[3], double slack) {
    Polytope poly;
    poly.slack = slack;
    int two_valued[3];
    int count = 0;
    for (int a = 0; a < 3; ++a)
        if (hi[a] > lo[a]) two_valued[count++] = a;
    const uint32_t corners = 1u << count;
    for (uint32_t m = 0; m < corners; ++m) {
        double q[3] = {lo[0], lo[1], lo[2]};
        for (int a = 0; a < 3; ++a) q[a] = lo[a] == hi[a] ? lo[a] : q[a];
        for (int j = 0; j < count; ++j)
            if (m & (1u << j)) q[two_valued[j]] = hi[two_valued[j]];
        poly.vertices.push_back(center + q[0] * axes[0] + q[1] * axes[1] + q[2] * axes[2]);
        for (int j = 0; j < count; ++j)
            if (!(m & (1u << j))) poly.edges.emplace_back(m, m | (1u << j));
    }
    glm::dvec3 sum(0.0);
    for (const glm::dvec3& v : poly.vertices) sum += v;
    poly.centroid = sum / static_cast<double>(poly.vertices.size());
    return poly;
}

struct Node {
    glm::dvec3 lo{0.0}, hi{0.0};
    uint32_t first = 0;  // leaf: first index into order; interior: left child (right = first + 1)
    uint32_t count = 0;  // 0 = interior
    bool full = false;   // full-umbra bit (§3.3 A)
};

struct GroupEntry {
    uint32_t group;
    uint32_t mask;  // active planes of V_k
    bool built;     // V_k was available when the mask was made
};

struct Counters {
    uint64_t pairs_tested = 0, pairs_hard_culled = 0, nodes_visited = 0, umbra_skips = 0;
    uint64_t group_volumes_built = 0, hard_volumes_built = 0;
    uint64_t pairs_certified = 0, pairs_certified_hits = 0, coplanar_skips = 0, pyramids_built = 0;
    void add(const Counters& c) {
        pairs_certified += c.pairs_certified;
        pairs_certified_hits += c.pairs_certified_hits;
        coplanar_skips += c.coplanar_skips;
        pyramids_built += c.pyramids_built;
        pairs_tested += c.pairs_tested;
        pairs_hard_culled += c.pairs_hard_culled;
        nodes_visited += c.nodes_visited;
        umbra_skips += c.umbra_skips;
        group_volumes_built += c.group_volumes_built;
        hard_volumes_built += c.hard_volumes_built;
    }
};

/// A non-degenerate triangle of the current chunk with its light-level data.
struct TriangleRecord {
    oracle::Triangle tri;
    glm::dvec3 v[3];
    glm::dvec3 normal{0.0};
    double normal_err = 0;
    bool normal_ok = false;
    Tolerance tol;
    double gap = 0;  // lower bound of dist(T, all samples)
    Volume light_volume;
    // The oracle's own plane data (rules 2 and 3c), bit for bit: n = cross3(v1 - v0, v2 - v0).
    glm::dvec3 oracle_n{0.0};
    double oracle_n_length = 0;  // length3(n)
    double kappa = 0;            // >= |v1 - v0| |v2 - v0| / |n| (conditioning of the oracle's plane test)
};

/// Certified fast path (see "Certified verdicts" in the header comment): the shadow pyramid of T
/// seen from one receiver p. For d = s - p (computed), h_e = n[e] . d (e < 3: the plane through p
/// and edge e, T's third vertex on its positive side) and H = n[3] . d (T's unit normal, oriented
/// so that h_p = n[3] . (v0 - p) > 0):
///   certified robust hit  <=> h_e >= hit[e] (e < 3) and hit_lo < H < hit_hi;
///   certified clear miss  <=> H > h_err and some h_e <= -miss[e], or H < -h_err and some h_e >= miss[e].
///   certified backward miss <=> h_e <= -hit[e] (e < 3) and -back_hi < H < -h_err (the line
///                             crosses T robustly inside, at t < -eps: see "Certified verdicts");
struct Pyramid {
    double n[4][3];
    double hit[3], miss[3];
    double hit_lo = 0, hit_hi = 0, h_err = 0;
    double back_hi = -std::numeric_limits<double>::infinity();  // backward crossings: -inf off
};

inline constexpr double kU = 0x1p-53;                 // unit roundoff
inline constexpr double kUp = 1.0 + 0x1p-40;          // covers the rounding of a few operations on a bound
inline constexpr double kDown = 1.0 - 0x1p-40;
inline constexpr double kHitMargin = 0x1p-26;         // certified hits: sheared edge margin >= (eps + 2^-26) * scale
inline constexpr double kMissMargin = 0x1p-40;        // certified misses: sheared margin >= eps * scale + 2^-40 * scale
inline constexpr double kParameterError = 0x1p-20;    // |t_oracle - t_exact| <= 2^-20 * scale / H on a certified hit

/// True when the oracle ignores T for EVERY pair (p, s) by its coplanar rule for the receiver
/// (rule 2). The oracle's side_p and point-triangle distance depend on T and p only, and its
/// limit and reach grow with its scale = max(|s - p|_inf, S_T) >= S_T (rounding is monotone):
/// evaluating them exactly as the oracle does with S_T in place of the scale is a sufficient test.
inline bool coplanarIgnoredForAll(const TriangleRecord& rec, const glm::dvec3& p, double coplanar_epsilon) {
    namespace oracle = detail::oracle;
    const glm::dvec3 a = rec.tri.v0 - p, b = rec.tri.v1 - p, c = rec.tri.v2 - p;
    const double s_t = std::max(oracle::maxAbs(a), std::max(oracle::maxAbs(b), oracle::maxAbs(c)));
    const double reach = coplanar_epsilon * s_t;
    const double limit = reach * rec.oracle_n_length;
    const double side_p = oracle::dot3(rec.oracle_n, rec.tri.v0 - p);
    if (!(std::fabs(side_p) <= limit)) return false;
    return penumbra::detail::pointTriangleDistance2<double>(p, rec.tri.v0, rec.tri.v1, rec.tri.v2) <= reach * reach;
}

/// Sets a record's triangle, its unit normal and the oracle's plane data (not its volumes).
inline void setTriangle(TriangleRecord& rec, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
    rec.v[0] = a;
    rec.v[1] = b;
    rec.v[2] = c;
    rec.tri = detail::oracle::Triangle{a, b, c, 0u};
    rec.normal_ok = unitCross(b - a, c - a, rec.normal, rec.normal_err);
    rec.oracle_n = detail::oracle::cross3(rec.tri.v1 - rec.tri.v0, rec.tri.v2 - rec.tri.v0);
    rec.oracle_n_length = detail::oracle::length3(rec.oracle_n);
    // |n - N| <= 8 u |e1| |e2| for the exact normal N (cross3 of rounded differences).
    const double product = glm::length(b - a) * glm::length(c - a) * kUp;
    const double exact_lo = rec.oracle_n_length * kDown - 8.0 * kU * product;
    rec.kappa = exact_lo > 0.0 ? product / exact_lo * kUp : std::numeric_limits<double>::infinity();
}

/// Scores of one sample (d = s - p, computed): hit > 0 certifies a robust hit, miss > 0 a clear
/// miss. a - b > 0 <=> a > b for doubles and fl(a + b) <= 0 <=> a + b <= 0, so these are the
/// comparisons of Pyramid's comment (made strict). Branch-free: the group loop vectorises.
inline void pyramidScores(const Pyramid& py, double dx, double dy, double dz, double& hit, double& miss) {
    const double h0 = py.n[0][0] * dx + py.n[0][1] * dy + py.n[0][2] * dz;
    const double h1 = py.n[1][0] * dx + py.n[1][1] * dy + py.n[1][2] * dz;
    const double h2 = py.n[2][0] * dx + py.n[2][1] * dy + py.n[2][2] * dz;
    const double hh = py.n[3][0] * dx + py.n[3][1] * dy + py.n[3][2] * dz;
    hit = std::min(std::min(std::min(h0 - py.hit[0], h1 - py.hit[1]), std::min(h2 - py.hit[2], hh - py.hit_lo)), py.hit_hi - hh);
    const double beyond = std::min(hh - py.h_err, -std::min(std::min(h0 + py.miss[0], h1 + py.miss[1]), h2 + py.miss[2]));
    const double behind = std::min(-hh - py.h_err, std::max(std::max(h0 - py.miss[0], h1 - py.miss[1]), h2 - py.miss[2]));
    const double backward = std::min(std::min(std::min(-h0 - py.hit[0], -h1 - py.hit[1]), -h2 - py.hit[2]),
                                     std::min(-hh - py.h_err, hh + py.back_hi));
    miss = std::max(std::max(beyond, behind), backward);
}

/// Upper bounds of |s - p|_2 and |s - p|_inf over every sample within `slack` of the convex hull
/// of `vertices` (the norms are convex).
inline void sampleReach(const std::vector<glm::dvec3>& vertices, double slack, const glm::dvec3& p, double& reach2,
                        double& reach_inf) {
    double r2 = 0.0, ri = 0.0;
    for (const glm::dvec3& x : vertices) {
        const glm::dvec3 d = x - p;
        r2 = std::max(r2, glm::length(d));
        ri = std::max(ri, maxAbs3(d));
    }
    reach2 = (r2 * kUp + slack) * kUp;
    reach_inf = (ri * kUp + slack) * kUp;
}

/// Builds the shadow pyramid of T from p, or false when it is ill-conditioned (p near T's plane
/// or near the line of an edge): those pairs take the oracle path. reach2 / reach_inf: upper
/// bounds of |s - p|_2 and |s - p|_inf over every sample.
/// T's vertices relative to p, upper bounds of their lengths, and S >= the oracle's scale of
/// every pair (p, s): what both pyramids measure their margins against.
struct PyramidFrame {
    glm::dvec3 w[3];
    double w_len[3];
    double scale;
};

inline PyramidFrame pyramidFrame(const TriangleRecord& rec, const glm::dvec3& p, double reach_inf) {
    PyramidFrame f;
    double w_inf = 0.0;
    for (int i = 0; i < 3; ++i) {
        f.w[i] = rec.v[i] - p;
        f.w_len[i] = glm::length(f.w[i]) * kUp;
        w_inf = std::max(w_inf, maxAbs3(f.w[i]));
    }
    f.scale = std::max(w_inf, reach_inf) * kUp;
    return f;
}

inline bool buildPyramid(const TriangleRecord& rec, const glm::dvec3& p, double reach2, double reach_inf, double eps,
                         double cop, Pyramid& py) {
    py.back_hi = -std::numeric_limits<double>::infinity();
    if (!rec.normal_ok) return false;
    const PyramidFrame frame = pyramidFrame(rec, p, reach_inf);
    const glm::dvec3* w = frame.w;
    const double* w_len = frame.w_len;
    const double scale = frame.scale;  // every margin below is measured against it
    glm::dvec3 nt = rec.normal;
    double hp = glm::dot(nt, w[0]);
    if (hp < 0.0) {
        nt = -nt;
        hp = -hp;
    }
    const double e_n = rec.normal_err + 8.0 * kU;
    const double e_hp = e_n * w_len[0] * kUp;
    if (!(hp > 2.0 * e_hp)) return false;  // the side of p is not certain
    const double m_hit = (eps + kHitMargin) * scale * kUp;
    const double m_miss = (eps * kUp + kMissMargin) * scale * kUp;
    for (int e = 0; e < 3; ++e) {
        const int a = e, b = (e + 1) % 3, c = (e + 2) % 3;
        const glm::dvec3 edge = rec.v[b] - rec.v[a];
        const glm::dvec3 cr = glm::cross(edge, w[a]);
        const double len = glm::length(cr), edge_len = glm::length(edge);
        if (!(len > 0.0) || !(edge_len > 0.0)) return false;
        const double conditioning = edge_len * w_len[a] / len;
        if (!(conditioning <= kMaxConditioning)) return false;
        glm::dvec3 n = cr / len;
        const double err = 16.0 * kUlp * conditioning + 8.0 * kU;  // unitCross's bound + the evaluation's rounding
        double side = glm::dot(n, w[c]);
        if (side < 0.0) {
            n = -n;
            side = -side;
        }
        if (!(side > 2.0 * err * w_len[c])) return false;  // orientation not certain
        const double dist_lo = (len / edge_len) * kDown - 16.0 * kU * w_len[a];  // <= dist(p, line of e)
        if (!(dist_lo > 0.0)) return false;
        const double stretch = reach2 / dist_lo * kUp;
        const double e_he = err * reach2 * kUp;
        py.n[e][0] = n.x;
        py.n[e][1] = n.y;
        py.n[e][2] = n.z;
        py.hit[e] = m_hit * stretch * kUp + e_he;
        py.miss[e] = m_miss * stretch * kUp + e_he;
    }
    py.n[3][0] = nt.x;
    py.n[3][1] = nt.y;
    py.n[3][2] = nt.z;
    py.h_err = e_n * reach2 * kUp;
    const double h_lo = hp - e_hp, h_hi = hp + e_hp;
    const double t_err = kParameterError * scale;
    const double cop_p = cop * scale * kUp + 24.0 * kU * rec.kappa * scale;
    const double cop_s = cop * scale * kUp + 48.0 * kU * rec.kappa * scale;
    if (h_lo * kDown > t_err * kUp && h_lo * kDown > cop_p * kUp) {
        py.hit_lo = std::max((h_hi + t_err) / (1.0 - eps), h_hi + cop_s) * kUp + py.h_err;
        py.hit_hi = eps > 0.0 ? (h_lo - t_err * kUp) / eps * kDown - py.h_err : std::numeric_limits<double>::infinity();
        if (h_lo * kDown > 48.0 * kU * rec.kappa * scale * kUp) py.back_hi = py.hit_hi;
    } else {
        py.hit_lo = std::numeric_limits<double>::infinity();
        py.hit_hi = -std::numeric_limits<double>::infinity();
    }
    return true;
}

/// Miss-only shadow pyramid for the receivers whose 4-plane pyramid is ill-conditioned (p within
/// rounding of T's plane or of an edge's line: receivers on T's plane outside its coplanar reach,
/// on a neighbouring face sharing an edge or a vertex, ...). See "Certified verdicts": the planes
/// through p and each edge, unit normal n_e = unit((v_a - p) x (v_b - v_a)) NOT oriented by the
/// third vertex, and T's unit normal n_T = unit((v1 - v0) x (v2 - v0)) NOT oriented by p. With
/// exact d = s - p, the triple products U_e = d . ((v_a - p) x (v_b - v_a)) sum to N . d, and in
/// the oracle's sheared frame U_e / d_kz and N . d / d_kz are the edge function of the ray's trace
/// and twice the signed area of the projected T: the trace is on the far side of edge e's line
/// from T iff U_e and N . d have opposite signs, for EVERY p (no orientation test through p is
/// needed). Its 2D distance to that line is >= |U_e| / (|e| |d|) = dist(p, line e) |h_e| / |d|.
/// The clear-miss thresholds are those of buildPyramid (same normals up to sign, same error
/// bounds); certified hits are disabled (hit thresholds +inf). Edges whose plane is not usable
/// (p on the edge's line, conditioning > kMaxConditioning) get n_e = 0 and miss = +inf: they
/// never certify. False when T's normal is not usable or no edge is.
inline bool buildMissPyramid(const TriangleRecord& rec, const glm::dvec3& p, double reach2, double reach_inf, double eps,
                             Pyramid& py) {
    if (!rec.normal_ok) return false;
    const PyramidFrame frame = pyramidFrame(rec, p, reach_inf);
    const glm::dvec3* w = frame.w;
    const double* w_len = frame.w_len;
    const double scale = frame.scale;
    const double m_miss = (eps * kUp + kMissMargin) * scale * kUp;
    bool any = false;
    for (int e = 0; e < 3; ++e) {
        const int a = e, b = (e + 1) % 3;
        const glm::dvec3 edge = rec.v[b] - rec.v[a];
        const glm::dvec3 cr = glm::cross(w[a], edge);
        const double len = glm::length(cr), edge_len = glm::length(edge);
        py.n[e][0] = py.n[e][1] = py.n[e][2] = 0.0;
        py.hit[e] = std::numeric_limits<double>::infinity();
        py.miss[e] = std::numeric_limits<double>::infinity();
        if (!(len > 0.0) || !(edge_len > 0.0)) continue;
        const double conditioning = edge_len * w_len[a] / len;
        if (!(conditioning <= kMaxConditioning)) continue;
        const double dist_lo = (len / edge_len) * kDown - 16.0 * kU * w_len[a];  // <= dist(p, line of e)
        if (!(dist_lo > 0.0)) continue;
        const glm::dvec3 n = cr / len;
        const double err = 16.0 * kUlp * conditioning + 8.0 * kU;
        const double stretch = reach2 / dist_lo * kUp;
        const double e_he = err * reach2 * kUp;
        py.n[e][0] = n.x;
        py.n[e][1] = n.y;
        py.n[e][2] = n.z;
        py.miss[e] = m_miss * stretch * kUp + e_he;
        any = true;
    }
    if (!any) return false;
    py.n[3][0] = rec.normal.x;
    py.n[3][1] = rec.normal.y;
    py.n[3][2] = rec.normal.z;
    py.h_err = (rec.normal_err + 8.0 * kU) * reach2 * kUp;
    py.hit_lo = std::numeric_limits<double>::infinity();
    py.hit_hi = -std::numeric_limits<double>::infinity();
    py.back_hi = -std::numeric_limits<double>::infinity();  // p's plane side is not certain
    return true;
}

}  // namespace casting
}  // namespace detail

/// One frame / bake: receivers and light fixed at construction, triangles streamed.
/// Not copyable; not thread-safe itself (it runs its own threads inside addTriangle / finish).
class PenumbraCaster {
public:
    /// receivers: the points to shade. light / sets: the light and its K sample sets (sets.world
    /// is what every pair uses). receiver_sets: the set of each receiver (empty: r % K).
    /// Throws penumbra::Error naming a bad value (see the header comment).
    PenumbraCaster(std::vector<glm::dvec3> receivers, const Light& light, const LightSampleSets& sets,
                   PenumbraCastingOptions options = {}, std::vector<uint32_t> receiver_sets = {})
        : receivers_(std::move(receivers)), options_(std::move(options)), receiver_sets_(std::move(receiver_sets)) {
        setup(light, sets);
    }
    PenumbraCaster(const PenumbraCaster&) = delete;
    PenumbraCaster& operator=(const PenumbraCaster&) = delete;
    ~PenumbraCaster() { releaseMasks(); }

    /// Streams one blocker triangle (buffered; a full batch is processed before returning).
    /// Throws penumbra::Error for a non-finite vertex or |coordinate| > 1e50 (the triangle is not
    /// taken); degenerate triangles are counted and dropped. Ignored after a cancellation.
    void addTriangle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
        PENUMBRA_CHECK(!finished_, "PenumbraCaster::addTriangle: the caster is spent (finish() was called)");
        const glm::dvec3* v[3] = {&a, &b, &c};
        for (int k = 0; k < 3; ++k) {
            PENUMBRA_CHECK(detail::oracle::finiteBounded(*v[k]), "PenumbraCaster::addTriangle: vertex ", "abc"[k],
                           " of triangle ", stats_.triangles, " must be finite with |coordinate| <= ",
                           detail::oracle::kMaxCoordinate, " (got ", v[k]->x, ", ", v[k]->y, ", ", v[k]->z, ")");
        }
        ++stats_.triangles;
        if (cancelled_) return;
        if (penumbra::detail::degenerateTriangle(a, b, c)) {
            ++stats_.triangles_degenerate;
            return;
        }
        batch_.push_back({a, b, c});
        if (batch_.size() >= options_.batch_triangles) flush();
    }

    /// True once the progress callback returned false.
    bool cancelled() const { return cancelled_; }

    /// Processes the buffered triangles and returns the result; the caster is spent afterwards.
    PenumbraCastingResult finish() {
        PenumbraCastingResult result;
        finish(result);
        return result;
    }

    /// The same, into `result`, whose vectors keep their storage: a caller that casts every frame
    /// passes last frame's result and allocates (and first-touches) none of its R N / 16 bytes
    /// again. Every field is overwritten.
    void finish(PenumbraCastingResult& result) {
        PENUMBRA_CHECK(!finished_, "PenumbraCaster::finish: called twice");
        flush();
        finished_ = true;
        result.stats = {};
        result.samples = n_;
        result.words_per_receiver = words_;
        result.receiver_sets = receiver_sets_;
        const size_t r_count = receivers_.size();
        result.blocked.resize(r_count * words_);
        result.ties.resize(r_count * words_);
        // Every word is written below, by blocks of receivers on every thread.
        constexpr size_t kBlock = 4096;
        const size_t blocks = (r_count + kBlock - 1) / kBlock;
        std::vector<uint64_t> block_ties(blocks, 0);
        std::atomic<bool> stop{false};
        parallelFor(
            blocks,
            [&](size_t block, Worker&) {
                uint64_t tie_count = 0;
                for (size_t r = block * kBlock; r < std::min(r_count, (block + 1) * kBlock); ++r) {
                    uint32_t* blocked = result.blocked.data() + r * words_;
                    uint32_t* ties = result.ties.data() + r * words_;
                    const State& st = state_[r];
                    if (st.full) {
                        std::fill(blocked, blocked + words_, 0xffffffffu);
                        std::fill(ties, ties + words_, 0u);
                        continue;
                    }
                    for (size_t w = 0; w < words_; ++w) {
                        const uint32_t robust = st.robust ? st.robust[w] : 0u;
                        const uint32_t weak_hit = st.weak ? st.weak[w] : 0u;
                        const uint32_t fragile = st.weak ? st.weak[words_ + w] : 0u;
                        blocked[w] = robust | weak_hit;
                        ties[w] = fragile & ~robust;
                        tie_count += detail::oracle::popcount32(ties[w]);
                    }
                }
                block_ties[block] = tie_count;
            },
            [](size_t) { return true; }, stop);
        for (uint64_t t : block_ties) stats_.ties += t;
        stats_.mask_bytes_peak = mask_bytes_peak_.load();
        stats_.cancelled = cancelled_;
        stats_.groups = groups_;
        result.stats = stats_;
        releaseMasks();
        if (options_.progress && !cancelled_) options_.progress(1.0);
    }

private:
    struct TriangleInput {
        glm::dvec3 a, b, c;
    };
    /// Per-receiver masks (§3.3 D): robust hits; weak = [hit bits | fragile bits] of non-robust
    /// verdicts (rare: near ties). null = all zero.
    struct State {
        std::unique_ptr<uint32_t[]> robust_owned;
        uint32_t* robust = nullptr;
        std::unique_ptr<uint32_t[]> weak;
        bool full = false;  // full-umbra bit: every pair robustly blocked
    };
    /// Scratch of one SAH subtree build.
    struct SahScratch {
        std::vector<uint32_t> sorted[3];  // the subtree's points by (coordinate, index) per axis
        std::vector<uint32_t> partition;
        std::vector<double> right_area;
        std::vector<uint8_t> left;  // per receiver: on the left of the current split
    };
    /// A subtree below the halving threshold: its root node, its range of order_ and its bounds.
    struct SahTask {
        uint32_t node, begin, end;
        glm::dvec3 lo, hi;
    };
    /// Scratch of one thread: lazily built volumes of the current (subtree, triangle).
    struct Worker {
        SahScratch sah;
        std::vector<detail::casting::Volume> group_volume;
        std::vector<double> group_gap;
        std::vector<uint64_t> group_stamp;
        std::vector<detail::casting::HardVolume> hard;
        std::vector<uint64_t> hard_stamp;  // per (set, group)
        std::vector<detail::casting::GroupEntry> entries;
        std::vector<double> scores;  // certified fast path: scores of one group's samples
        uint64_t stamp = 0;
        uint64_t eager_done = 0;
        uint64_t newly_full = 0;
        detail::casting::Counters counters;
    };

    // ---- setup -----------------------------------------------------------------------------

    void setup(const Light& light, const LightSampleSets& sets) {
        namespace dc = detail::casting;
        namespace oracle = detail::oracle;
        oracle::checkOptions(options_.oracle, "PenumbraCaster");
        PENUMBRA_CHECK(options_.scene_extent > 0,  // NaN fails too; +inf is the uncapped rule
                       "PenumbraCaster: options.scene_extent must be > 0 or +inf (got ", options_.scene_extent, ")");
        PENUMBRA_CHECK(options_.leaf_size >= 1, "PenumbraCaster: options.leaf_size must be >= 1 (got ", options_.leaf_size, ")");
        PENUMBRA_CHECK(options_.group_size >= 1, "PenumbraCaster: options.group_size must be >= 1 (got ", options_.group_size, ")");
        PENUMBRA_CHECK(options_.batch_triangles >= 1, "PenumbraCaster: options.batch_triangles must be >= 1 (got ",
                       options_.batch_triangles, ")");
        n_ = sets.count();
        k_ = sets.sets();
        PENUMBRA_CHECK(n_ >= 1 && k_ >= 1, "PenumbraCaster: sets must hold at least one set of one sample (got ", k_,
                       " sets of ", n_, ")");
        PENUMBRA_CHECK(sets.world.size() == static_cast<size_t>(n_) * k_, "PenumbraCaster: sets.world holds ",
                       sets.world.size(), " samples, expected sets() * count() = ", static_cast<size_t>(n_) * k_);
        oracle::checkPoints(sets.world, "PenumbraCaster", "sets.world");
        oracle::checkPoints(receivers_, "PenumbraCaster", "receivers");
        PENUMBRA_CHECK(receivers_.size() <= 0xffffffffull, "PenumbraCaster: too many receivers (", receivers_.size(), ")");
        samples_ = sets.world;
        words_ = (n_ + 31) / 32;
        const size_t r_count = receivers_.size();
        if (receiver_sets_.empty()) {
            receiver_sets_.resize(r_count);
            for (size_t r = 0; r < r_count; ++r) receiver_sets_[r] = static_cast<uint32_t>(r % k_);
        }
        PENUMBRA_CHECK(receiver_sets_.size() == r_count, "PenumbraCaster: receiver_sets has ", receiver_sets_.size(),
                       " entries for ", r_count, " receivers");
        for (size_t r = 0; r < r_count; ++r) {
            PENUMBRA_CHECK(receiver_sets_[r] < k_, "PenumbraCaster: receiver_sets[", r, "] = ", receiver_sets_[r],
                           " names no set (", k_, " sets)");
        }
        threads_ = options_.threads != 0 ? options_.threads : std::thread::hardware_concurrency();
        threads_ = std::max(threads_, 1u);

        // Bounds of everything a pair can span (the oracle's scales are below their extent).
        box_lo_ = glm::dvec3(std::numeric_limits<double>::infinity());
        box_hi_ = -box_lo_;
        for (const glm::dvec3& p : receivers_) {
            box_lo_ = glm::min(box_lo_, p);
            box_hi_ = glm::max(box_hi_, p);
            max_coord_ = std::max(max_coord_, dc::maxAbs3(p));
        }
        for (const glm::dvec3& s : samples_) {
            box_lo_ = glm::min(box_lo_, s);
            box_hi_ = glm::max(box_hi_, s);
            max_coord_ = std::max(max_coord_, dc::maxAbs3(s));
        }
        setupGroups(light, sets);
        // Certified fast path: per receiver, upper bounds of |s - p|_2 and |s - p|_inf over every
        // sample (the light's box is convex and holds every sample within its slack), and the
        // samples of each (set, group) as coordinate arrays in members_ order.
        member_offset_.assign(members_.size() + 1, 0);
        max_members_ = 0;
        for (size_t slot = 0; slot < members_.size(); ++slot) {
            member_offset_[slot + 1] = member_offset_[slot] + members_[slot].size();
            max_members_ = std::max(max_members_, members_[slot].size());
        }
        member_x_.resize(member_offset_.back());
        member_y_.resize(member_offset_.back());
        member_z_.resize(member_offset_.back());
        for (size_t slot = 0; slot < members_.size(); ++slot) {
            const size_t base = (slot / groups_) * n_;
            for (size_t j = 0; j < members_[slot].size(); ++j) {
                const glm::dvec3& x = samples_[base + members_[slot][j]];
                member_x_[member_offset_[slot] + j] = x.x;
                member_y_[member_offset_[slot] + j] = x.y;
                member_z_[member_offset_[slot] + j] = x.z;
            }
        }

        state_.resize(r_count);
        stats_.mask_bytes_full = static_cast<uint64_t>(r_count) * n_ / 8;
        if (!options_.on_demand_masks && r_count > 0) {
            upfront_masks_.assign(r_count * words_, 0u);
            for (size_t r = 0; r < r_count; ++r) state_[r].robust = upfront_masks_.data() + r * words_;
            addMaskBytes(static_cast<int64_t>(r_count * words_ * sizeof(uint32_t)));
        }
        group_words_ = (groups_ + 63) / 64;
        last_group_word_ = groups_ % 64 == 0 ? ~0ull : ((1ull << (groups_ % 64)) - 1ull);
        receiver_umbra_.assign(r_count * group_words_, 0ull);
        for (size_t r = 0; r < r_count; ++r) {
            const uint32_t set = receiver_sets_[r];
            for (uint32_t k = 0; k < groups_; ++k)
                if (members_[set * groups_ + k].empty()) receiver_umbra_[r * group_words_ + k / 64] |= 1ull << (k % 64);
        }
        workers_.clear();
        for (unsigned t = 0; t < threads_; ++t) {
            auto w = std::make_unique<Worker>();
            w->group_volume.resize(groups_);
            w->group_gap.assign(groups_, 0.0);
            w->group_stamp.assign(groups_, 0);
            w->hard.resize(samples_.size());
            w->hard_stamp.assign(static_cast<size_t>(k_) * groups_, 0);
            w->scores.assign(2 * max_members_, 0.0);
            workers_.push_back(std::move(w));
        }
        reach2_.resize(r_count);
        reach_inf_.resize(r_count);
        std::atomic<bool> stop{false};
        parallelFor(
            (r_count + 4095) / 4096,
            [&](size_t block, Worker&) {
                for (size_t r = block * 4096; r < std::min(r_count, (block + 1) * 4096); ++r)
                    dc::sampleReach(light_poly_.vertices, light_poly_.slack, receivers_[r], reach2_[r], reach_inf_[r]);
            },
            [](size_t) { return true; }, stop);
        std::vector<uint32_t> all(r_count);
        std::iota(all.begin(), all.end(), 0u);
        buildTree(std::move(all));
    }

    /// Light frame coordinates, the light's bound and the spatial sample groups (laine2005 §3.1, §3.4).
    void setupGroups(const Light& light, const LightSampleSets& sets) {
        namespace dc = detail::casting;
        const glm::dvec3 center = sets.frame.center;
        const glm::dvec3 axes[3] = {sets.frame.rotation[0], sets.frame.rotation[1], sets.frame.rotation[2]};
        const size_t count = samples_.size();
        std::vector<glm::dvec3> q(count);
        double lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::numeric_limits<double>::infinity();
            hi[a] = -lo[a];
        }
        double reach = 0.0;
        for (size_t i = 0; i < count; ++i) {
            const glm::dvec3 d = samples_[i] - center;
            reach = std::max(reach, glm::length(d));
            for (int a = 0; a < 3; ++a) {
                q[i][a] = glm::dot(axes[a], d);
                lo[a] = std::min(lo[a], q[i][a]);
                hi[a] = std::max(hi[a], q[i][a]);
            }
        }
        // Planar lights (and any flat axis) are polygons: the thickness goes into the slack.
        const bool planar = light.shape == LightShape::Disk || light.shape == LightShape::Rectangle;
        const double largest = std::max(hi[0] - lo[0], std::max(hi[1] - lo[1], hi[2] - lo[2]));
        bool active[3];
        for (int a = 0; a < 3; ++a) {
            active[a] = hi[a] - lo[a] > 1e-9 * largest && !(planar && a == 2);
            if (!active[a]) lo[a] = hi[a] = 0.5 * (lo[a] + hi[a]);
        }
        const double rounding = 64.0 * dc::kUlp * (dc::maxAbs3(center) + 2.0 * reach) + 1e-300;
        // Slack: how far a sample lies from its clamped image in the bound (rigorous whatever the
        // axes, since the bound is the affine image of the clamped coordinates' box).
        const auto slackOf = [&](const std::vector<size_t>& items, const double (&blo)[3], const double (&bhi)[3]) {
            double slack = 0.0;
            for (size_t i : items) {
                const glm::dvec3 x = center + std::clamp(q[i][0], blo[0], bhi[0]) * axes[0] +
                                     std::clamp(q[i][1], blo[1], bhi[1]) * axes[1] +
                                     std::clamp(q[i][2], blo[2], bhi[2]) * axes[2];
                slack = std::max(slack, glm::length(samples_[i] - x));
            }
            return slack * (1.0 + 1e-9) + rounding;
        };
        std::vector<size_t> everything(count);
        std::iota(everything.begin(), everything.end(), size_t{0});
        light_poly_ = dc::boxPolytope(center, axes, lo, hi, slackOf(everything, lo, hi));

        // Recursive median splits of the pooled samples of every set along the widest active axis.
        groups_ = std::max<uint32_t>(1u, std::min<uint32_t>(n_, (n_ + options_.group_size - 1) / options_.group_size));
        std::vector<size_t> items = everything;
        std::vector<std::pair<size_t, size_t>> ranges;  // [begin, end) of each group in items
        const std::function<void(size_t, size_t, uint32_t)> split = [&](size_t begin, size_t end, uint32_t g) {
            if (g <= 1 || end - begin <= 1) {
                ranges.emplace_back(begin, end);
                for (uint32_t extra = 1; extra < g; ++extra) ranges.emplace_back(end, end);
                return;
            }
            int axis = 0;
            double widest = -1.0;
            for (int a = 0; a < 3; ++a) {
                if (!active[a]) continue;
                double mn = std::numeric_limits<double>::infinity(), mx = -mn;
                for (size_t j = begin; j < end; ++j) {
                    mn = std::min(mn, q[items[j]][a]);
                    mx = std::max(mx, q[items[j]][a]);
                }
                if (mx - mn > widest) {
                    widest = mx - mn;
                    axis = a;
                }
            }
            const uint32_t g_left = g / 2;
            const size_t mid = begin + (end - begin) * g_left / g;
            std::nth_element(items.begin() + static_cast<std::ptrdiff_t>(begin), items.begin() + static_cast<std::ptrdiff_t>(mid),
                             items.begin() + static_cast<std::ptrdiff_t>(end), [&](size_t x, size_t y) {
                                 return std::make_pair(q[x][axis], x) < std::make_pair(q[y][axis], y);
                             });
            split(begin, mid, g_left);
            split(mid, end, g - g_left);
        };
        split(0, count, groups_);
        members_.assign(static_cast<size_t>(k_) * groups_, {});
        group_masks_.assign(static_cast<size_t>(k_) * groups_ * words_, 0u);
        group_polys_.clear();
        for (uint32_t k = 0; k < groups_; ++k) {
            std::vector<size_t> group(items.begin() + static_cast<std::ptrdiff_t>(ranges[k].first),
                                      items.begin() + static_cast<std::ptrdiff_t>(ranges[k].second));
            std::sort(group.begin(), group.end());
            double glo[3], ghi[3];
            for (int a = 0; a < 3; ++a) {
                glo[a] = active[a] ? std::numeric_limits<double>::infinity() : lo[a];
                ghi[a] = active[a] ? -std::numeric_limits<double>::infinity() : hi[a];
            }
            for (size_t i : group) {
                for (int a = 0; a < 3; ++a) {
                    if (!active[a]) continue;
                    glo[a] = std::min(glo[a], q[i][a]);
                    ghi[a] = std::max(ghi[a], q[i][a]);
                }
                const uint32_t set = static_cast<uint32_t>(i / n_), index = static_cast<uint32_t>(i % n_);
                members_[set * groups_ + k].push_back(index);
                group_masks_[(static_cast<size_t>(set) * groups_ + k) * words_ + index / 32] |= 1u << (index % 32);
            }
            if (group.empty()) {
                for (int a = 0; a < 3; ++a) glo[a] = ghi[a] = 0.5 * (lo[a] + hi[a]);
            }
            group_polys_.push_back(dc::boxPolytope(center, axes, glo, ghi, slackOf(group, glo, ghi)));
        }
    }

    // ---- receiver BVH (laine2005 §3.2) -------------------------------------------------------

    static double halfArea(const glm::dvec3& lo, const glm::dvec3& hi) {
        const glm::dvec3 e = hi - lo;
        return e.x * e.y + e.y * e.z + e.z * e.x;
    }

    void buildTree(std::vector<uint32_t> items) {
        nodes_.clear();
        roots_.clear();
        order_ = std::move(items);
        tree_receivers_ = order_.size();
        tree_full_ = 0;
        if (order_.empty()) return;
        nodes_.reserve(2 * (order_.size() / std::max<uint32_t>(1u, options_.leaf_size)) + 2);
        nodes_.push_back(detail::casting::Node{});
        sah_tasks_.clear();
        buildNode(0, 0, static_cast<uint32_t>(order_.size()));
        // The SAH subtrees on every thread, each into its own nodes, then appended in task order
        // (the same tree for any thread count).
        std::vector<std::vector<detail::casting::Node>> subtrees(sah_tasks_.size());
        std::atomic<bool> stop{false};
        parallelFor(
            sah_tasks_.size(), [&](size_t t, Worker& w) { buildSah(sah_tasks_[t], w.sah, subtrees[t]); },
            [](size_t) { return true; }, stop);
        for (size_t t = 0; t < sah_tasks_.size(); ++t) {
            const std::vector<detail::casting::Node>& local = subtrees[t];
            const uint32_t base = static_cast<uint32_t>(nodes_.size()) - 1;  // local index i >= 1 -> base + i
            for (size_t i = 0; i < local.size(); ++i) {
                detail::casting::Node node = local[i];
                if (node.count == 0) node.first += base;
                if (i == 0)
                    nodes_[sah_tasks_[t].node] = node;
                else
                    nodes_.push_back(node);
            }
        }
        node_umbra_.assign(nodes_.size() * group_words_, 0ull);
        if (options_.umbra_bits) initUmbra(0);
        // Subtrees for the threads: a breadth-first frontier of >= kRootTarget nodes (or all leaves).
        std::vector<uint32_t> frontier = {0};
        while (frontier.size() < detail::casting::kRootTarget) {
            std::vector<uint32_t> next;
            bool expanded = false;
            for (uint32_t n : frontier) {
                if (nodes_[n].count == 0) {
                    next.push_back(nodes_[n].first);
                    next.push_back(nodes_[n].first + 1);
                    expanded = true;
                } else {
                    next.push_back(n);
                }
            }
            frontier.swap(next);
            if (!expanded) break;
        }
        roots_ = std::move(frontier);
    }

    void buildNode(uint32_t node_index, uint32_t begin, uint32_t end) {
        glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        for (uint32_t j = begin; j < end; ++j) {
            lo = glm::min(lo, receivers_[order_[j]]);
            hi = glm::max(hi, receivers_[order_[j]]);
        }
        nodes_[node_index].lo = lo;
        nodes_[node_index].hi = hi;
        const uint32_t count = end - begin;
        if (count <= options_.leaf_size) {
            nodes_[node_index].first = begin;
            nodes_[node_index].count = count;
            return;
        }
        const auto first = order_.begin() + begin, last = order_.begin() + end;
        const auto byAxis = [this](int axis) {
            return [this, axis](uint32_t x, uint32_t y) {
                return std::make_pair(receivers_[x][axis], x) < std::make_pair(receivers_[y][axis], y);
            };
        };
        uint32_t mid = begin;
        const glm::dvec3 extent = hi - lo;
        int longest = 0;
        if (extent.y > extent[longest]) longest = 1;
        if (extent.z > extent[longest]) longest = 2;
        if (count > detail::casting::kHalvingThreshold) {
            const double middle = 0.5 * (lo[longest] + hi[longest]);
            mid = static_cast<uint32_t>(std::partition(first, last, [&](uint32_t i) { return receivers_[i][longest] < middle; }) -
                                        order_.begin());
            if (mid == begin || mid == end) {
                mid = begin + count / 2;
                std::nth_element(first, order_.begin() + mid, last, byAxis(longest));
            }
        } else {
            // SAH below the halving threshold: the range sorted once per axis, then split recursively.
            sah_tasks_.push_back({node_index, begin, end, lo, hi});  // built in parallel by buildTree
            return;
        }
        const uint32_t left = static_cast<uint32_t>(nodes_.size());
        nodes_.push_back(detail::casting::Node{});
        nodes_.push_back(detail::casting::Node{});
        nodes_[node_index].first = left;
        nodes_[node_index].count = 0;
        buildNode(left, begin, mid);
        buildNode(left + 1, mid, end);
    }

    /// SAH subtree over order_[begin, end) with bounds lo / hi (laine2005 §3.2 below 1K points).
    /// Each axis's order is sorted once, by (coordinate, index), and partitioned stably at every
    /// split, so every node sees its points exactly as sorting them again would give: the sweep,
    /// the chosen split and the tree are those of a full sort per node, in O(n log n) overall.
    void buildSah(const SahTask& task, SahScratch& s, std::vector<detail::casting::Node>& nodes) {
        const uint32_t count = task.end - task.begin;
        for (int axis = 0; axis < 3; ++axis) {
            s.sorted[axis].assign(order_.begin() + task.begin, order_.begin() + task.end);
            std::sort(s.sorted[axis].begin(), s.sorted[axis].end(), [this, axis](uint32_t x, uint32_t y) {
                return std::make_pair(receivers_[x][axis], x) < std::make_pair(receivers_[y][axis], y);
            });
        }
        s.right_area.resize(count);
        s.partition.resize(count);
        if (s.left.size() < receivers_.size()) s.left.resize(receivers_.size());
        nodes.assign(1, detail::casting::Node{});
        sahNode(s, nodes, 0, task.begin, 0, count, task.lo, task.hi);
    }

    /// One SAH node: its points are sah_.sorted[a][first, first + count) on every axis a and
    /// order_[begin, begin + count) as a set; leaves keep their parent's order, as before.
    /// Writes order_[begin, begin + count) only, so subtrees can be built concurrently.
    void sahNode(SahScratch& s, std::vector<detail::casting::Node>& nodes, uint32_t node_index, uint32_t begin,
                 uint32_t first, uint32_t count, const glm::dvec3& lo, const glm::dvec3& hi) {
        nodes[node_index].lo = lo;
        nodes[node_index].hi = hi;
        if (count <= options_.leaf_size) {
            nodes[node_index].first = begin;
            nodes[node_index].count = count;
            return;
        }
        // Cost = area(left) * n_left + area(right) * n_right, over every split of every axis.
        double best_cost = std::numeric_limits<double>::infinity();
        int best_axis = -1;
        uint32_t best_split = 0;
        for (int axis = 0; axis < 3; ++axis) {
            const uint32_t* sorted = s.sorted[axis].data() + first;
            glm::dvec3 rlo(std::numeric_limits<double>::infinity()), rhi(-std::numeric_limits<double>::infinity());
            for (uint32_t i = count; i-- > 1;) {
                rlo = glm::min(rlo, receivers_[sorted[i]]);
                rhi = glm::max(rhi, receivers_[sorted[i]]);
                s.right_area[i] = halfArea(rlo, rhi);
            }
            glm::dvec3 llo(std::numeric_limits<double>::infinity()), lhi(-std::numeric_limits<double>::infinity());
            for (uint32_t i = 1; i < count; ++i) {
                llo = glm::min(llo, receivers_[sorted[i - 1]]);
                lhi = glm::max(lhi, receivers_[sorted[i - 1]]);
                const double cost = halfArea(llo, lhi) * i + s.right_area[i] * (count - i);
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_split = i;
                }
            }
        }
        if (best_axis < 0 || !(best_cost > 0.0)) {  // coincident / collinear points: median
            const glm::dvec3 extent = hi - lo;
            best_axis = 0;
            if (extent.y > extent[best_axis]) best_axis = 1;
            if (extent.z > extent[best_axis]) best_axis = 2;
            best_split = count / 2;
        }
        // This node's order is the chosen axis's; the other axes split stably by side.
        const uint32_t* chosen = s.sorted[best_axis].data() + first;
        std::copy(chosen, chosen + count, order_.begin() + begin);
        for (uint32_t i = 0; i < count; ++i) s.left[chosen[i]] = i < best_split ? 1 : 0;
        for (int axis = 0; axis < 3; ++axis) {
            if (axis == best_axis) continue;
            uint32_t* sorted = s.sorted[axis].data() + first;
            uint32_t l = 0, r = best_split;
            for (uint32_t i = 0; i < count; ++i) s.partition[s.left[sorted[i]] ? l++ : r++] = sorted[i];
            std::copy(s.partition.begin(), s.partition.begin() + count, sorted);
        }
        glm::dvec3 llo(std::numeric_limits<double>::infinity()), lhi(-std::numeric_limits<double>::infinity());
        glm::dvec3 rlo = llo, rhi = lhi;
        for (uint32_t i = 0; i < count; ++i) {
            const glm::dvec3& p = receivers_[chosen[i]];
            if (i < best_split) {
                llo = glm::min(llo, p);
                lhi = glm::max(lhi, p);
            } else {
                rlo = glm::min(rlo, p);
                rhi = glm::max(rhi, p);
            }
        }
        const uint32_t left = static_cast<uint32_t>(nodes.size());
        nodes.push_back(detail::casting::Node{});
        nodes.push_back(detail::casting::Node{});
        nodes[node_index].first = left;
        nodes[node_index].count = 0;
        sahNode(s, nodes, left, begin, first, best_split, llo, lhi);
        sahNode(s, nodes, left + 1, begin + best_split, first + best_split, count - best_split, rlo, rhi);
    }

    void initUmbra(uint32_t node_index) {
        if (nodes_[node_index].count == 0) {
            initUmbra(nodes_[node_index].first);
            initUmbra(nodes_[node_index].first + 1);
            combineUmbra(node_index);
        } else {
            leafUmbra(node_index);
        }
    }

    /// Leaf umbra bits = AND over its receivers (laine2005 Fig. 3, lines 77-80).
    void leafUmbra(uint32_t node_index) {
        detail::casting::Node& node = nodes_[node_index];
        uint64_t* bits = node_umbra_.data() + static_cast<size_t>(node_index) * group_words_;
        std::fill(bits, bits + group_words_, ~0ull);
        bool full = true;
        for (uint32_t j = node.first; j < node.first + node.count; ++j) {
            const uint32_t r = order_[j];
            if (state_[r].full) continue;
            full = false;
            const uint64_t* rb = receiver_umbra_.data() + static_cast<size_t>(r) * group_words_;
            for (size_t w = 0; w < group_words_; ++w) bits[w] &= rb[w];
        }
        node.full = full;
    }

    /// Interior umbra bits = AND of the children (lines 50-54).
    void combineUmbra(uint32_t node_index) {
        detail::casting::Node& node = nodes_[node_index];
        const uint32_t left = node.first;
        uint64_t* bits = node_umbra_.data() + static_cast<size_t>(node_index) * group_words_;
        const uint64_t* lb = node_umbra_.data() + static_cast<size_t>(left) * group_words_;
        const uint64_t* rb = lb + group_words_;
        for (size_t w = 0; w < group_words_; ++w) bits[w] = lb[w] & rb[w];
        node.full = nodes_[left].full && nodes_[left + 1].full;
    }

    // ---- masks (§3.3 D) ------------------------------------------------------------------------

    void addMaskBytes(int64_t bytes) {
        const uint64_t now = mask_bytes_.fetch_add(static_cast<uint64_t>(bytes)) + static_cast<uint64_t>(bytes);
        uint64_t peak = mask_bytes_peak_.load();
        while (now > peak && !mask_bytes_peak_.compare_exchange_weak(peak, now)) {
        }
    }

    void ensureRobust(State& st) {
        if (st.robust) return;
        st.robust_owned.reset(new uint32_t[words_]());
        st.robust = st.robust_owned.get();
        addMaskBytes(static_cast<int64_t>(words_ * sizeof(uint32_t)));
    }

    void record(State& st, uint32_t sample, const detail::oracle::Verdict& verdict) {
        const uint32_t word = sample / 32, bit = 1u << (sample % 32);
        if (verdict.hit && !verdict.fragile) {
            ensureRobust(st);
            st.robust[word] |= bit;
            return;
        }
        if (!st.weak) {
            st.weak.reset(new uint32_t[2 * words_]());
            addMaskBytes(static_cast<int64_t>(2 * words_ * sizeof(uint32_t)));
        }
        if (verdict.hit) st.weak[word] |= bit;
        if (verdict.fragile) st.weak[words_ + word] |= bit;
    }

    void releaseState(State& st) {
        if (st.robust_owned) {
            st.robust_owned.reset();
            addMaskBytes(-static_cast<int64_t>(words_ * sizeof(uint32_t)));
        }
        st.robust = nullptr;
        if (st.weak) {
            st.weak.reset();
            addMaskBytes(-static_cast<int64_t>(2 * words_ * sizeof(uint32_t)));
        }
    }

    void releaseMasks() {
        for (State& st : state_) {
            st.robust_owned.reset();
            st.robust = nullptr;
            st.weak.reset();
        }
        upfront_masks_.clear();
        upfront_masks_.shrink_to_fit();
    }

    // ---- per-triangle volumes ----------------------------------------------------------------

    void prepareRecord(const TriangleInput& in, detail::casting::TriangleRecord& rec) const {
        namespace dc = detail::casting;
        dc::setTriangle(rec, in.a, in.b, in.c);
        const glm::dvec3 lo = glm::min(box_lo_, glm::min(in.a, glm::min(in.b, in.c)));
        const glm::dvec3 hi = glm::max(box_hi_, glm::max(in.a, glm::max(in.b, in.c)));
        const double extent = dc::maxAbs3(hi - lo);
        const double max_coord =
            std::max(max_coord_, std::max(dc::maxAbs3(in.a), std::max(dc::maxAbs3(in.b), dc::maxAbs3(in.c))));
        const double eps = options_.oracle.tie_epsilon;
        rec.tol.delta = extent * (16.0 * eps + 64.0 * dc::kUlp / std::max(eps, 0x1p-40) + 1e-12);
        rec.tol.eta = 2.0 * eps + (extent > 0.0 ? rec.tol.delta / extent : 0.0);
        rec.tol.span = 2.0 * extent;
        rec.tol.abs_err = 16.0 * dc::kUlp * max_coord;
        rec.gap = dc::gapLowerBound(rec.v, light_poly_, rec.normal, rec.normal_ok, rec.tol, {});
        dc::buildPenumbraVolume(rec.v, rec.normal, rec.normal_err, rec.normal_ok, light_poly_, rec.gap, rec.tol,
                                rec.light_volume);
    }

    void ensureGroupVolume(Worker& w, const detail::casting::TriangleRecord& rec, uint32_t k) const {
        namespace dc = detail::casting;
        if (w.group_stamp[k] == w.stamp) return;
        w.group_stamp[k] = w.stamp;
        ++w.counters.group_volumes_built;
        // Group samples are a subset of the light's: the light's gap holds too.
        const double gap = std::max(rec.gap, dc::gapLowerBound(rec.v, group_polys_[k], rec.normal, rec.normal_ok, rec.tol, {}));
        w.group_gap[k] = gap;
        dc::buildPenumbraVolume(rec.v, rec.normal, rec.normal_err, rec.normal_ok, group_polys_[k], gap, rec.tol,
                                w.group_volume[k]);
    }

    void ensureHardVolumes(Worker& w, const detail::casting::TriangleRecord& rec, uint32_t set, uint32_t k) const {
        const size_t slot = static_cast<size_t>(set) * groups_ + k;
        if (w.hard_stamp[slot] == w.stamp) return;
        w.hard_stamp[slot] = w.stamp;
        ensureGroupVolume(w, rec, k);
        const size_t base = static_cast<size_t>(set) * n_;
        for (uint32_t i : members_[slot]) {
            detail::casting::buildHardVolume(rec.v, rec.normal, rec.normal_err, rec.normal_ok, samples_[base + i],
                                             w.group_gap[k], rec.tol, w.hard[base + i]);
            ++w.counters.hard_volumes_built;
        }
    }

    // ---- traversal (laine2005 Fig. 3) ---------------------------------------------------------

    bool groupUmbraBit(const uint64_t* bits, uint32_t k) const { return (bits[k / 64] >> (k % 64)) & 1ull; }

    void traverse(Worker& w, const detail::casting::TriangleRecord& rec, uint32_t node_index, uint32_t light_mask,
                  size_t group_begin, size_t group_end) {
        namespace dc = detail::casting;
        const bool umbra = options_.umbra_bits, active = options_.active_planes;
        ++w.counters.nodes_visited;
        const dc::Node& node = nodes_[node_index];
        if (umbra && node.full) {
            ++w.counters.umbra_skips;
            return;
        }
        if (rec.light_volume.culls && !dc::boxInside(rec.light_volume, node.lo, node.hi, light_mask, active)) return;
        if (!options_.lazy_volumes && w.eager_done != w.stamp) {
            // lazy_volumes off: every V_k and V_i once per (subtree, triangle) that gets this far.
            w.eager_done = w.stamp;
            for (uint32_t k = 0; k < groups_; ++k)
                for (uint32_t set = 0; set < k_; ++set) ensureHardVolumes(w, rec, set, k);
        }
        const size_t begin = w.entries.size();
        const uint64_t* node_bits = node_umbra_.data() + static_cast<size_t>(node_index) * group_words_;
        for (size_t e = group_begin; e < group_end; ++e) {
            dc::GroupEntry entry = w.entries[e];
            if (umbra && groupUmbraBit(node_bits, entry.group)) {
                ++w.counters.umbra_skips;
                continue;
            }
            if (w.group_stamp[entry.group] == w.stamp) {
                const dc::Volume& volume = w.group_volume[entry.group];
                if (!entry.built) {
                    entry.built = true;
                    entry.mask = volume.allMask();
                }
                if (volume.culls && !dc::boxInside(volume, node.lo, node.hi, entry.mask, active)) continue;
            }
            w.entries.push_back(entry);
        }
        const size_t end = w.entries.size();
        if (begin == end) return;
        if (node.count == 0) {
            traverse(w, rec, node.first, light_mask, begin, end);
            traverse(w, rec, node.first + 1, light_mask, begin, end);
            if (umbra) combineUmbra(node_index);
        } else {
            leaf(w, rec, node, light_mask, begin, end);
            if (umbra) leafUmbra(node_index);
        }
        w.entries.resize(begin);
    }

    void leaf(Worker& w, const detail::casting::TriangleRecord& rec, const detail::casting::Node& node,
              uint32_t light_mask, size_t group_begin, size_t group_end) {
        namespace dc = detail::casting;
        namespace oracle = detail::oracle;
        const bool umbra = options_.umbra_bits;
        const bool certified = options_.certified_fast_path;
        for (uint32_t j = node.first; j < node.first + node.count; ++j) {
            const uint32_t r = order_[j];
            State& st = state_[r];
            if (st.full) continue;
            const glm::dvec3& p = receivers_[r];
            if (rec.light_volume.culls && !dc::pointInside(rec.light_volume, p, light_mask)) continue;
            if (certified && dc::coplanarIgnoredForAll(rec, p, options_.oracle.coplanar_epsilon)) {
                ++w.counters.coplanar_skips;  // no verdict from T for any sample of p
                continue;
            }
            const uint32_t set = receiver_sets_[r];
            uint64_t* receiver_bits = receiver_umbra_.data() + static_cast<size_t>(r) * group_words_;
            bool group_completed = false;
            int pyramid_state = certified ? 0 : -1;  // 0: not built yet, 1: usable, 2: miss-only, -1: oracle path
            dc::Pyramid pyramid;
            for (size_t e = group_begin; e < group_end; ++e) {
                const dc::GroupEntry entry = w.entries[e];
                const uint32_t k = entry.group;
                if (umbra && groupUmbraBit(receiver_bits, k)) {
                    ++w.counters.umbra_skips;
                    continue;
                }
                const size_t slot = static_cast<size_t>(set) * groups_ + k;
                if (members_[slot].empty()) continue;
                ensureGroupVolume(w, rec, k);  // §3.3 C: a relation may become blocked here
                const dc::Volume& volume = w.group_volume[k];
                if (volume.culls && !dc::pointInside(volume, p, entry.built ? entry.mask : volume.allMask())) continue;
                if (pyramid_state == 0) {
                    ++w.counters.pyramids_built;
                    pyramid_state = dc::buildPyramid(rec, p, reach2_[r], reach_inf_[r], options_.oracle.tie_epsilon,
                                                     options_.oracle.coplanar_epsilon, pyramid)
                                        ? 1
                                        : -1;
                    if (pyramid_state == -1 &&
                        dc::buildMissPyramid(rec, p, reach2_[r], reach_inf_[r], options_.oracle.tie_epsilon, pyramid))
                        pyramid_state = 2;  // ill-conditioned: certified misses only, hard volumes for the rest
                }
                const size_t base = static_cast<size_t>(set) * n_;
                bool new_robust = false;
                if (pyramid_state >= 1) {
                    new_robust = pyramidGroup(w, rec, pyramid, st, p, slot, base, pyramid_state == 2);
                } else {
                ensureHardVolumes(w, rec, set, k);
                for (uint32_t i : members_[slot]) {
                    if (st.robust && ((st.robust[i / 32] >> (i % 32)) & 1u)) continue;  // already robustly blocked
                    const glm::dvec3& s = samples_[base + i];
                    if (p == s) continue;  // empty open segment: never blocked
                    const dc::HardVolume& hv = w.hard[base + i];
                    if (hv.culls && !dc::hardInside(hv, p, s, rec.v[0])) {
                        ++w.counters.pairs_hard_culled;
                        continue;
                    }
                    ++w.counters.pairs_tested;
                    const oracle::Verdict verdict =
                        oracle::classifySegment(rec.tri, oracle::makeSegmentQuery(p, s, options_.oracle, options_.scene_extent));
                    if (!verdict.hit && !verdict.fragile) continue;
                    record(st, i, verdict);
                    new_robust |= verdict.hit && !verdict.fragile;
                }
                }
                if (umbra && new_robust) {
                    const uint32_t* mask = group_masks_.data() + slot * words_;
                    bool complete = true;
                    for (size_t word = 0; word < words_ && complete; ++word)
                        complete = (st.robust[word] & mask[word]) == mask[word];
                    if (complete) {
                        receiver_bits[k / 64] |= 1ull << (k % 64);
                        group_completed = true;
                    }
                }
            }
            if (umbra && group_completed) {
                bool all = true;
                for (size_t word = 0; word + 1 < group_words_ && all; ++word) all = receiver_bits[word] == ~0ull;
                all = all && (receiver_bits[group_words_ - 1] & last_group_word_) == last_group_word_;
                if (all) {
                    st.full = true;
                    ++w.newly_full;
                    if (options_.on_demand_masks) releaseState(st);  // §3.3 D: the full-umbra bit says it all
                }
            }
        }
    }

    /// The samples of one (set, group) against the shadow pyramid of (T, p): certified hits are
    /// recorded as robust, certified misses dropped, the rest classified by the oracle. Returns
    /// whether a new robust hit was recorded.
    bool pyramidGroup(Worker& w, const detail::casting::TriangleRecord& rec, const detail::casting::Pyramid& py,
                      State& st, const glm::dvec3& p, size_t slot, size_t base, bool hard_cull) {
        namespace oracle = detail::oracle;
        const size_t first = member_offset_[slot], count = member_offset_[slot + 1] - first;
        const double* xs = member_x_.data() + first;
        const double* ys = member_y_.data() + first;
        const double* zs = member_z_.data() + first;
        const double px = p.x, py_ = p.y, pz = p.z;
        const double t0 = py.hit[0], t1 = py.hit[1], t2 = py.hit[2];
        const double m0 = py.miss[0], m1 = py.miss[1], m2 = py.miss[2];
        const double lo = py.hit_lo, hi = py.hit_hi, herr = py.h_err;
        const std::vector<uint32_t>& members = members_[slot];
        const uint32_t* group_mask = group_masks_.data() + slot * words_;

        // Whole group at once (its bound with slack): every sample certified hit, or every sample
        // certified missed through one edge plane. Same thresholds as per sample: the bound's
        // vertices are evaluated with the same rounding bound, the slack covers the samples.
        {
            const detail::casting::Polytope& poly = group_polys_[slot % groups_];
            const double slack = poly.slack * detail::casting::kUp;
            double mn[4], mx[4];
            for (int e = 0; e < 4; ++e) {
                mn[e] = std::numeric_limits<double>::infinity();
                mx[e] = -std::numeric_limits<double>::infinity();
            }
            for (const glm::dvec3& x : poly.vertices) {
                const double dx = x.x - px, dy = x.y - py_, dz = x.z - pz;
                for (int e = 0; e < 4; ++e) {
                    const double h = py.n[e][0] * dx + py.n[e][1] * dy + py.n[e][2] * dz;
                    mn[e] = std::min(mn[e], h);
                    mx[e] = std::max(mx[e], h);
                }
            }
            for (int e = 0; e < 4; ++e) {
                mn[e] -= slack;
                mx[e] += slack;
            }
            const bool all_hit = mn[0] >= t0 && mn[1] >= t1 && mn[2] >= t2 && mn[3] > lo && mx[3] < hi;
            const bool all_miss = (mn[3] > herr && (mx[0] <= -m0 || mx[1] <= -m1 || mx[2] <= -m2)) ||
                                  (mx[3] < -herr && (mn[0] >= m0 || mn[1] >= m1 || mn[2] >= m2)) ||
                                  (mx[0] <= -t0 && mx[1] <= -t1 && mx[2] <= -t2 && mx[3] < -herr && mn[3] > -py.back_hi);
            if (all_hit || all_miss) {
                uint64_t decided = 0;
                for (size_t word = 0; word < words_; ++word) {
                    const uint32_t robust = st.robust ? st.robust[word] : 0u;
                    decided += oracle::popcount32(group_mask[word] & ~robust);
                }
                w.counters.pairs_certified += decided;
                if (all_hit && decided > 0) {
                    w.counters.pairs_certified_hits += decided;
                    ensureRobust(st);
                    for (size_t word = 0; word < words_; ++word) st.robust[word] |= group_mask[word];
                    return true;
                }
                return false;
            }
        }

        // Per sample, branch-free (vectorisable): a score > 0 certifies.
        double* hit_score = w.scores.data();
        double* miss_score = hit_score + count;
        const detail::casting::Pyramid local = py;  // a local copy: the stores below cannot alias it
        for (size_t j = 0; j < count; ++j)
            detail::casting::pyramidScores(local, xs[j] - px, ys[j] - py_, zs[j] - pz, hit_score[j], miss_score[j]);
        bool new_robust = false;
        for (size_t chunk = 0; chunk < count; chunk += 64) {
            const size_t chunk_end = std::min(count, chunk + 64);
            uint64_t hits = 0, open = 0, blocked = 0;
            for (size_t j = chunk; j < chunk_end; ++j) {
                const uint32_t i = members[j];
                const uint64_t bit = 1ull << (j - chunk);
                hits |= hit_score[j] > 0.0 ? bit : 0ull;
                open |= (hit_score[j] > 0.0 || miss_score[j] > 0.0) ? 0ull : bit;
                if (st.robust) blocked |= ((st.robust[i / 32] >> (i % 32)) & 1u) ? bit : 0ull;  // already robust
            }
            hits &= ~blocked;
            open &= ~blocked;
            const uint64_t decided = ~(open | blocked) & (chunk_end - chunk == 64 ? ~0ull : (1ull << (chunk_end - chunk)) - 1ull);
            w.counters.pairs_certified += static_cast<uint64_t>(oracle::popcount32(static_cast<uint32_t>(decided)) +
                                                                oracle::popcount32(static_cast<uint32_t>(decided >> 32)));
            if (hits != 0) {
                new_robust = true;
                ensureRobust(st);
                for (uint64_t bits = hits; bits != 0; bits &= bits - 1) {
                    const uint32_t i = members[chunk + detail::casting::lowestBit64(bits)];
                    st.robust[i / 32] |= 1u << (i % 32);
                    ++w.counters.pairs_certified_hits;
                }
            }
            if (hard_cull && open != 0) ensureHardVolumes(w, rec, static_cast<uint32_t>(slot / groups_), static_cast<uint32_t>(slot % groups_));
            for (uint64_t bits = open; bits != 0; bits &= bits - 1) {
                const uint32_t i = members[chunk + detail::casting::lowestBit64(bits)];
                const glm::dvec3& s = samples_[base + i];
                if (p == s) continue;  // empty open segment: never blocked
                if (hard_cull) {
                    const detail::casting::HardVolume& hv = w.hard[base + i];
                    if (hv.culls && !detail::casting::hardInside(hv, p, s, rec.v[0])) {
                        ++w.counters.pairs_hard_culled;
                        continue;
                    }
                }
                ++w.counters.pairs_tested;
                const oracle::Verdict verdict =
                    oracle::classifySegment(rec.tri, oracle::makeSegmentQuery(p, s, options_.oracle, options_.scene_extent));
                if (!verdict.hit && !verdict.fragile) continue;
                record(st, i, verdict);
                new_robust |= verdict.hit && !verdict.fragile;
            }
        }
        return new_robust;
    }

    void processRoot(Worker& w, uint32_t root, size_t first, size_t last, const std::atomic<bool>& stop) {
        for (size_t t = first; t < last; ++t) {
            if (stop.load(std::memory_order_relaxed)) return;
            ++w.stamp;
            w.entries.clear();
            for (uint32_t k = 0; k < groups_; ++k) w.entries.push_back({k, 0u, false});
            const detail::casting::TriangleRecord& rec = records_[t];
            traverse(w, rec, root, rec.light_volume.allMask(), 0, groups_);
        }
    }

    // ---- batches, chunks, threads -------------------------------------------------------------

    /// fn(item, worker) for item in [0, count) on up to threads_ threads; the calling thread is
    /// worker 0 and reports progress(done items) between its items.
    template <class Fn, class Report>
    void parallelFor(size_t count, Fn&& fn, Report&& report, std::atomic<bool>& stop) {
        if (count == 0) return;
        std::atomic<size_t> next{0}, done{0};
        std::exception_ptr error;
        std::mutex error_mutex;
        const auto body = [&](unsigned worker) {
            try {
                for (;;) {
                    if (stop.load()) break;
                    const size_t item = next.fetch_add(1);
                    if (item >= count) break;
                    fn(item, *workers_[worker]);
                    const size_t finished = done.fetch_add(1) + 1;
                    if (worker == 0 && !report(finished)) stop.store(true);
                }
            } catch (...) {
                std::lock_guard<std::mutex> lock(error_mutex);
                if (!error) error = std::current_exception();
                stop.store(true);
            }
        };
        const unsigned threads = static_cast<unsigned>(std::min<size_t>(threads_, count));
        std::vector<std::thread> pool;
        pool.reserve(threads > 0 ? threads - 1 : 0);
        for (unsigned i = 1; i < threads; ++i) {
            try {
                pool.emplace_back(body, i);
            } catch (...) {
                break;  // fewer threads: the others pick up the items
            }
        }
        body(0);
        for (std::thread& thread : pool) thread.join();
        if (error) std::rethrow_exception(error);
    }

    bool reportProgress(double processed) {
        if (!options_.progress || cancelled_) return !cancelled_;
        const double total = static_cast<double>(std::max<uint64_t>(stats_.triangles, 1));
        const double fraction = std::min(1.0, (static_cast<double>(stats_.triangles_degenerate) + processed) / total);
        if (!options_.progress(fraction)) cancelled_ = true;
        return !cancelled_;
    }

    void flush() {
        if (batch_.empty()) return;
        if (cancelled_) {
            batch_.clear();
            return;
        }
        if (options_.area_sort) {
            // Coarse blocker sorting (laine2005 §3.3): buckets of floor(log2(area)), largest first.
            std::vector<std::pair<int, size_t>> keys(batch_.size());
            for (size_t i = 0; i < batch_.size(); ++i) {
                const TriangleInput& t = batch_[i];
                int exponent = 0;
                std::frexp(glm::length(glm::cross(t.b - t.a, t.c - t.a)), &exponent);
                keys[i] = {-exponent, i};
            }
            std::stable_sort(keys.begin(), keys.end(),
                             [](const std::pair<int, size_t>& x, const std::pair<int, size_t>& y) { return x.first < y.first; });
            std::vector<TriangleInput> sorted(batch_.size());
            for (size_t i = 0; i < keys.size(); ++i) sorted[i] = batch_[keys[i].second];
            batch_.swap(sorted);
        }
        for (size_t chunk = 0; chunk < batch_.size() && !cancelled_; chunk += detail::casting::kChunkTriangles) {
            const size_t chunk_end = std::min(batch_.size(), chunk + detail::casting::kChunkTriangles);
            processChunk(chunk, chunk_end);
        }
        batch_.clear();
    }

    void processChunk(size_t first, size_t last) {
        const size_t count = last - first;
        std::atomic<bool> stop{false};
        records_.resize(count);
        // Light-level volumes in parallel (independent per triangle).
        const size_t blocks = (count + 255) / 256;
        parallelFor(
            blocks,
            [&](size_t block, Worker&) {
                const size_t end = std::min(count, (block + 1) * 256);
                for (size_t t = block * 256; t < end; ++t) prepareRecord(batch_[first + t], records_[t]);
            },
            [](size_t) { return true; }, stop);
        for (size_t t = 0; t < count; ++t) stats_.triangles_near_light += records_[t].light_volume.culls ? 0 : 1;
        if (!roots_.empty()) {
            const double before = static_cast<double>(processed_);
            const size_t roots = roots_.size();
            parallelFor(
                roots, [&](size_t item, Worker& w) { processRoot(w, roots_[item], 0, count, stop); },
                [&](size_t finished) {
                    return reportProgress(before + static_cast<double>(count) * static_cast<double>(finished) /
                                                       static_cast<double>(roots));
                },
                stop);
        }
        processed_ += count;
        for (auto& w : workers_) {
            counters_.add(w->counters);
            w->counters = detail::casting::Counters{};
            tree_full_ += w->newly_full;
            w->newly_full = 0;
        }
        stats_.pairs_tested = counters_.pairs_tested;
        stats_.pairs_classified = counters_.pairs_tested;
        stats_.pairs_certified = counters_.pairs_certified;
        stats_.pairs_certified_hits = counters_.pairs_certified_hits;
        stats_.coplanar_skips = counters_.coplanar_skips;
        stats_.pyramids_built = counters_.pyramids_built;
        stats_.pairs_hard_culled = counters_.pairs_hard_culled;
        stats_.nodes_visited = counters_.nodes_visited;
        stats_.umbra_skips = counters_.umbra_skips;
        stats_.group_volumes_built = counters_.group_volumes_built;
        stats_.hard_volumes_built = counters_.hard_volumes_built;
        if (cancelled_ || stop.load()) {
            cancelled_ = cancelled_ || stop.load();
            return;
        }
        reportProgress(static_cast<double>(processed_));
        // §3.3 A: rebuild over the receivers not yet in full umbra when a quarter of the tree is.
        if (options_.umbra_bits && tree_receivers_ > 0 && tree_full_ * 4 > tree_receivers_) {
            std::vector<uint32_t> rest;
            rest.reserve(tree_receivers_ - tree_full_);
            for (uint32_t r : order_)
                if (!state_[r].full) rest.push_back(r);
            std::sort(rest.begin(), rest.end());
            buildTree(std::move(rest));
            ++stats_.rebuilds;
        }
    }

    std::vector<glm::dvec3> receivers_;
    PenumbraCastingOptions options_;
    std::vector<uint32_t> receiver_sets_;
    std::vector<glm::dvec3> samples_;  // K * N, set-major (sets.world)
    uint32_t n_ = 0, k_ = 0, groups_ = 0;
    size_t words_ = 0, group_words_ = 0;
    uint64_t last_group_word_ = 0;
    unsigned threads_ = 1;
    std::vector<std::vector<uint32_t>> members_;  // [set * G + k]: sample indices
    std::vector<uint32_t> group_masks_;           // [(set * G + k) * words + w]
    std::vector<size_t> member_offset_;           // [set * G + k]: first entry in member_x_ / _y_ / _z_
    std::vector<double> member_x_, member_y_, member_z_;
    size_t max_members_ = 0;
    std::vector<double> reach2_, reach_inf_;      // per receiver: bounds of |s - p|_2, |s - p|_inf
    detail::casting::Polytope light_poly_;
    std::vector<detail::casting::Polytope> group_polys_;
    glm::dvec3 box_lo_{0.0}, box_hi_{0.0};
    double max_coord_ = 0.0;

    std::vector<State> state_;
    std::vector<uint64_t> receiver_umbra_;  // [r * group_words + w]: group-umbra bits
    std::vector<uint32_t> upfront_masks_;   // on_demand_masks off
    std::atomic<uint64_t> mask_bytes_{0}, mask_bytes_peak_{0};

    std::vector<detail::casting::Node> nodes_;
    std::vector<SahTask> sah_tasks_;  // SAH subtrees of the current build
    std::vector<uint64_t> node_umbra_;  // [node * group_words + w]
    std::vector<uint32_t> order_;       // receivers in leaf order
    std::vector<uint32_t> roots_;
    size_t tree_receivers_ = 0, tree_full_ = 0;

    std::vector<TriangleInput> batch_;
    std::vector<detail::casting::TriangleRecord> records_;
    std::vector<std::unique_ptr<Worker>> workers_;
    detail::casting::Counters counters_;
    PenumbraCastingStats stats_;
    uint64_t processed_ = 0;
    bool cancelled_ = false, finished_ = false;
};

/// Convenience: triangles from `next(a, b, c)` (returns false at the end) until the end or a
/// cancellation, then finish().
template <class Next>
PenumbraCastingResult penumbraCast(std::vector<glm::dvec3> receivers, const Light& light, const LightSampleSets& sets,
                                   Next&& next, PenumbraCastingOptions options = {},
                                   std::vector<uint32_t> receiver_sets = {}) {
    PenumbraCastingResult result;
    penumbraCast(result, std::move(receivers), light, sets, std::forward<Next>(next), std::move(options),
                 std::move(receiver_sets));
    return result;
}

/// The same, into `result` (its storage reused: see PenumbraCaster::finish(result)).
template <class Next>
void penumbraCast(PenumbraCastingResult& result, std::vector<glm::dvec3> receivers, const Light& light,
                  const LightSampleSets& sets, Next&& next, PenumbraCastingOptions options = {},
                  std::vector<uint32_t> receiver_sets = {}) {
    PenumbraCaster caster(std::move(receivers), light, sets, std::move(options), std::move(receiver_sets));
    glm::dvec3 a, b, c;
    while (!caster.cancelled() && next(a, b, c)) caster.addTriangle(a, b, c);
    caster.finish(result);
}

}  // namespace penumbra

#endif
