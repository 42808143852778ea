// penumbra/pipelines/sample_based_soft.hpp — sample-based soft shadows (sintorn2008 §4, Fig. 6):
// per view sample an N-bit mask of the light samples its casters block, from the light-sample LUT.
// This header holds the CPU twin of the pipeline's per-sample work (the GPU pipeline, which
// rasterizes influence regions to find the (sample, caster) pairs, calls the same GLSL functions
// per pair: lookup.glsl); no GL.
//
// Integration summary
//   Needs:    GLM; light_samples.hpp (K sets of N samples, LightFrame), light_lut.hpp (a LUT built
//             for those sets; certified for Exact), reference/visibility.hpp (the oracle's
//             per-triangle segment verdict, for the samples the LUT cannot vouch for).
//   Produces: sampleBasedSoftCpu(): per receiver the mask (bit s of word [r * W + s / 32]: light
//             sample s of the receiver's set is blocked) and the work counters.
//
// Per (view sample p, caster triangle T) — sintorn2008 Fig. 6: the light samples T blocks for p
// are those behind the three planes through p and T's edges and beyond T's plane. Each plane is
// computed in double from the float inputs, mapped to the light's normalised space
// (LightFrame::planeToLocal) and looked up; the four masks are ANDed, and the per-caster masks ORed.
//   Lut:   the seed's approximation (centre sampling, penumbraLutBehind); casters the receiver lies
//          on (the oracle's coplanar rule for every sample) are ignored, as in Exact.
//   Exact: certified lookups (lutCertain / lutCombine); the uncertain bits are decided by the
//          pair's own world planes where they prove the side with the LUT's separation
//          (soft::sideVerdict: nearly all), the rest by the oracle's own per-triangle verdict
//          (detail::oracle::classifySegment with the oracle's options), so the mask equals
//          reference::VisibilityOracle::evaluate's bit for bit on every pair the oracle does not
//          call a tie. Certain bits (and side-plane verdicts) are only trusted where that is proven:
//            - each plane carries a rounding bound (float inputs, double arithmetic, the change of
//              frame) in normalised units; a plane whose bound exceeds half the LUT's tolerance
//              counts as all-uncertain;
//            - T is ignored for every light sample when p lies within the oracle's coplanar reach
//              of T for all of them, and all of T's bits are uncertain when p lies within
//              2 max(tie, coplanar epsilon) * scale of T, or when the LUT's margin in world units
//              (tolerance / 2 * the light's smallest semi-axis) is not above 2 tie_epsilon * scale
//              (2 max(tie, coplanar epsilon) * scale where the light's bounding sphere comes within
//              that coplanar reach of T): there the oracle's coplanar rule (for a light sample on
//              T) or its t-near-0/1 rounding could decide differently;
//          elsewhere a certain bit is the geometric truth by a margin far above the oracle's
//          rounding, hence the oracle's verdict (its near-edge "ties" still count as blocked or not
//          exactly as the oracle says: a tie only flags closeness).
//   Brute: every sample decided by the oracle's per-triangle verdict (ground truth, slow).
// Degenerate casters (detail::degenerateTriangle, the oracle's and the GPU's one rule) cast nothing.
//
// Bad input (penumbra::Error): a LUT not built for these sets (N, K), Exact with a LUT that is not
// certified, receiver sets out of range, non-finite positions, indices out of range.
//
// GPU pipeline setup (GL-free, after the twin): SampleBasedSoftGpuOptions (mode, grid, list
// blocks, the oracle's epsilons, plane budget, work counters, timers) and its validation,
// sampleBasedSoftParams() (the light pass's PenumbraSbsParams block: light frame, bounds, budget,
// epsilons, grid, LUT params; shaders/penumbra/sample_based_soft/sample_based_soft_shared.h) and
// sampleBasedSoftSampleTable() (the fp64 world samples the exact test reads). The executor is
// penumbra/gl/pipelines/sample_based_soft.hpp; its fragment stage runs this twin's per-pair steps
// in fp64 (light_pass.frag.glsl), except that it looks the planes up in float (the twin: double)
// and proves them against plane_budget (0.25 of the tolerance; the twin: 0.5). Exact and Brute
// stay equal to the oracle; Lut may differ from the twin's Lut in bits whose plane lies within
// float rounding of a cell border (measured: 0-2 bits of 51 200).
#ifndef PENUMBRA_PIPELINES_SAMPLE_BASED_SOFT_HPP
#define PENUMBRA_PIPELINES_SAMPLE_BASED_SOFT_HPP

#include "penumbra/detail/geometry.hpp"
#include "penumbra/pipelines/caster_class.hpp"
#include "penumbra/error.hpp"
#include "penumbra/light_lut.hpp"
#include "penumbra/light_samples.hpp"
#include "penumbra/reference/visibility.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

// The GPU pipeline's parameter block (opens namespace penumbra::shared itself).
#if defined(__has_include) && __has_include(<penumbra/sample_based_soft/sample_based_soft_shared.h>)
#include <penumbra/sample_based_soft/sample_based_soft_shared.h>
#else
#include "../../../shaders/penumbra/sample_based_soft/sample_based_soft_shared.h"
#endif

namespace penumbra {

enum class SoftMode : uint32_t {
    Exact = 0,  ///< certified LUT + the oracle's verdict on uncertain bits: equals the oracle
    Lut = 1,    ///< the seed's LUT approximation (centre sampling)
    Brute = 2,  ///< every light sample tested (ground truth)
};

inline const char* softModeName(SoftMode mode) {
    return mode == SoftMode::Exact ? "exact" : mode == SoftMode::Lut ? "lut" : mode == SoftMode::Brute ? "brute" : "?";
}

/// Work the pipeline may skip (sintorn2008 §4.3, "skip what a scene doesn't need"). Each skip
/// leaves every mask bit of Exact and Brute unchanged (the argument is with each flag; the tests
/// compare masks with each skip on and off, bit for bit, on every built-in and shared scene); Lut
/// is an approximation whose bits may move with the plane cut and the silhouette skip.
/// Value-initialised = all on but silhouettes (which needs adjacency).
struct SoftSkips {
    /// GPU only: a light-pass fragment whose list block is empty is never shaded (about half the
    /// fragments of a typical frame): an occupancy pass counts each texel's non-empty list blocks
    /// into a stencil, and the light pass of block b tests it with early fragment tests (a fragment
    /// that gets through anyway, past block 254, returns before the caster's per-fragment setup).
    /// Counted: fragments_skipped.
    bool empty_blocks = true;
    /// Casters drawn as CasterClass::Closed (watertight, consistently outward-oriented meshes, as
    /// scene::Mesh::closed promises; unions of such meshes qualify) cast only their triangles that
    /// do not face away from the whole light: a triangle with the light's bounding sphere strictly
    /// behind its plane (beyond the rounding bound of detail::soft::casterPlane) is culled once, in the geometry
    /// stage. Why nothing changes: a segment from a receiver p to a light sample l that meets a
    /// closed mesh must leave the mesh's solid before it reaches l (l lies outside every solid), and
    /// the face it leaves through has l strictly in front (winding number: entering faces raise it,
    /// leaving faces lower it, and it ends at 0); culled faces have every light sample behind, so
    /// the face that blocks the segment is always kept — geometrically. The oracle's coplanar rule
    /// (rule 2) ignores a triangle for receivers within coplanar_epsilon * scale of it, a reach that
    /// differs from triangle to triangle: for a receiver just outside a convex edge it can ignore the
    /// face the segment leaves through and count the culled one it enters through. So a receiver
    /// within that reach (scale_hi, the largest over the light) of a kept closed triangle, and not
    /// provably on its outer side (from there a segment to a light point the face faces never
    /// crosses its plane, so it cannot leave through it), gets the culled triangles too (a second
    /// pass over them that only such receivers take: counted pairs_recovered); every other
    /// receiver has the leaving face counted. (The seed's opposite
    /// choice, light-facing triangles culled, loses receivers whose segment enters the solid right
    /// at the receiver: self-shadowed receivers, concave creases.) Counted: triangles_culled.
    bool closed_casters = true;
    /// A (receiver p, caster T) pair is skipped before its edge planes are built when p and the
    /// whole light lie strictly on the same side of T's plane, each farther from it than the
    /// oracle's reach at that pair (2 max(tie, coplanar epsilon) * scale) plus the rounding bound:
    /// the segment never comes near T's plane, so neither the geometry nor any rule of the oracle
    /// makes T block a light sample (sintorn2008 §4.3's supporting-plane cut, per pair; the
    /// influence region's own cut is InfluenceRegionOptions::cut_by_supporting_plane).
    /// Counted: pairs_cut.
    bool plane_cut = true;
    /// GPU only, off by default (it needs the casters with adjacency: the run's DrawAdjacency
    /// callback, penumbra::triangleAdjacency; sampleBasedSoftCpu ignores it, the marked texels'
    /// twin is sampleBasedSoftSilhouetteMarks in penumbra/pipelines/silhouette_marks.hpp):
    /// penumbrae come only from edges that are silhouettes from some point of the light
    /// (laine2005 §3.3). An edge is a potential silhouette unless the whole light lies strictly in
    /// front of both its faces or strictly behind both (the faces oriented as one sheet across the
    /// edge; open and non-manifold edges always are). A silhouette pass rasterizes every potential
    /// silhouette's influence region into a texel mask; view samples of unmarked texels take one
    /// exact test from the light centre per caster, which sets all N bits or none. Why nothing changes: as a light point moves over the light, whether its segment
    /// to p meets the casters changes only where the segment crosses a silhouette edge, and outside
    /// every silhouette's region no segment from p to the light does; so every light sample has the
    /// centre's verdict, and the casters that block the centre are exactly those needed. Needs every
    /// receiver in front of the influence setup's far plane by 2^-12 of the far plane's distance
    /// from the light (edges crossing it are clipped that far in front of it; the demo's plane lies
    /// 1 % beyond the farthest receiver). The oracle's coplanar rule opens edges that are no
    /// silhouettes (a triangle it ignores for p next to one it counts: detail::soft::coplanarOpen),
    /// so a second draw marks the texels of view samples where it may (each triangle's region).
    /// Counted: pairs_hard.
    bool silhouettes = false;
    /// A (receiver p, caster T) pair is skipped before anything else when p lies beyond one of T's
    /// wedge planes (detail::soft::wedgePlanes: the three planes through T's edges tangent to a
    /// sphere about the light's centre holding every light sample, sampleBasedSoftSampleReach, and
    /// T's plane, each with T on one side and every light sample strictly on the other) by more than 2 mu max(S, |p|_inf), mu = 4 max(tie, coplanar epsilon) + 2^-21,
    /// S the largest coordinate of T and the light. Every point of a blocked segment lies on T's
    /// side of each plane, so T blocks no light sample for p, and p and the segment stay farther
    /// from T than any rule of the oracle reaches: not near a closed triangle, no tie. The GPU
    /// builds the planes once per triangle in the geometry stage and tests them per view sample
    /// in float in the fragment stage, so a rejected pair is never appended (deferred_pairs).
    /// Most pairs a conservative influence region brings are such pairs (the light wholly in front
    /// of one of the pair's planes: pairs_front). Counted: pairs_wedged.
    bool wedges = true;
};

/// Value-initialised = defaults.
struct SampleBasedSoftOptions {
    SoftMode mode = SoftMode::Exact;
    /// The oracle's tie and coplanar tolerances (rules 2 and 3 of reference/visibility.hpp): Exact
    /// and Brute decide uncertain pairs with exactly these. threads is ignored.
    reference::VisibilityOptions oracle{};
    /// R rotation steps about the light's local z (1 = none; 1..256; R > 1 needs a light symmetric
    /// about it, LightFrame::symmetric): a receiver's selection word picks step r, and its light
    /// samples are its set's rotated by r / R turns (sintorn2008 §4.2's per-pixel jitter). The
    /// oracle's samples are sampleBasedSoftSampleTable's.
    uint32_t rotations = 1;
    /// closed_casters and plane_cut (empty_blocks is the GPU's); the masks do not change.
    SoftSkips skips{};
    /// E of the oracle's tolerance scale (> 0): the largest side of the scene's bounding box, as
    /// VisibilityOracle::sceneExtent(). +inf = the uncapped rule: lights ~1e3 scene sizes away
    /// then lose their shadows (issue 41).
    double scene_extent = std::numeric_limits<double>::infinity();
};

/// Casters: indexed triangles (float positions, as the GPU sees them).
struct SoftCasters {
    const glm::vec3* positions = nullptr;
    size_t vertex_count = 0;
    const uint32_t* indices = nullptr;  ///< 3 per triangle
    size_t triangle_count = 0;
    /// Per triangle: nonzero = its mesh is closed (drawn as CasterClass::Closed); null = all open.
    const uint8_t* closed = nullptr;
};

/// Receivers (view samples): float positions and, optionally, the selection word of each
/// (sampleBasedSoftSelection per pixel: bits 0-7 the light-sample set, bits 8-15 the rotation
/// step); null = set 0, no rotation for all.
struct SoftReceivers {
    const glm::vec3* positions = nullptr;
    size_t count = 0;
    const uint32_t* sets = nullptr;
};

/// The selection word of a view sample (what SoftReceivers::sets and the GPU pipeline's per-sample
/// buffer hold): set lightSampleSet(x, y, frame, K) in bits 0-7, and with R > 1 rotation steps the
/// step (floor(lightSampleRotationHash(x, y, frame / (K R), seed) * R / 2^32) + frame / K) mod R in
/// bits 8-15. sintorn2008 §4.2: neighbours get other sets and other rotations; over K R consecutive
/// frames (temporal jitter) a pixel takes every (set, step) pair exactly once — the set cycles every
/// frame, the step advances once per set cycle from a per-pixel start — so a running average never
/// repeats a pattern before it has used them all.
inline uint32_t sampleBasedSoftSelection(uint32_t x, uint32_t y, uint32_t frame, uint32_t sets, uint32_t rotations,
                                         uint32_t seed = 0) {
    const uint32_t set = lightSampleSet(x, y, frame, sets);
    if (rotations <= 1) return set;
    const uint32_t k = std::max<uint32_t>(sets, 1u);
    const uint32_t cycle = frame / k / rotations;
    const uint32_t start = static_cast<uint32_t>((uint64_t(lightSampleRotationHash(x, y, cycle, seed)) * rotations) >> 32);
    const uint32_t step = (start + frame / k % rotations) % rotations;
    return set | (step << 8);
}

/// The light samples of every (set, rotation step) in world space, as the GPU reads them and the
/// oracle must get them: dvec4 (xyz, 0), index (set * R + step) * N + i; step 0 is
/// LightSampleSets::world bit for bit, step r the local sample rotated by r / R turns about local z
/// (cos/sin from the library-independent cosSinTurns, products unfused) then LightFrame::toWorld.
/// Then R entries (cos, sin, 0, 0) of the steps. Throws when R is outside 1..256 or R > 1 for a
/// light that is not symmetric about its local z.
inline std::vector<glm::dvec4> sampleBasedSoftSampleTable(const LightSampleSets& sets, uint32_t rotations) {
    PENUMBRA_CHECK(rotations >= 1 && rotations <= 256, "penumbra::sampleBasedSoftSampleTable: rotations = ", rotations,
                   " must be in [1, 256]");
    PENUMBRA_CHECK(rotations == 1 || sets.frame.symmetric, "penumbra::sampleBasedSoftSampleTable: rotations = ", rotations,
                   " needs a light symmetric about its local z axis (sphere, disk, ellipsoid with equal x and y); "
                   "this one is not: use 1");
    const uint32_t n = sets.count(), k = sets.sets();
    std::vector<glm::dvec2> steps(rotations);
    for (uint32_t r = 0; r < rotations; ++r) {
        double c = 1.0, sn = 0.0;
        if (r) detail::light_samples::cosSinTurns(double(r) / double(rotations), c, sn);
        steps[r] = glm::dvec2(c, sn);
    }
    std::vector<glm::dvec4> out;
    out.reserve(size_t(n) * k * rotations + rotations);
    for (uint32_t s = 0; s < k; ++s)
        for (uint32_t r = 0; r < rotations; ++r)
            for (uint32_t i = 0; i < n; ++i) {
                if (r == 0) {
                    out.emplace_back(sets.worldSet(s)[i], 0.0);
                    continue;
                }
                const glm::dvec3 q = sets.local[size_t(s) * n + i];
                const double c = steps[r].x, sn = steps[r].y;
                const glm::dvec3 rotated(detail::mulRounded(c, q.x) - detail::mulRounded(sn, q.y),
                                         detail::mulRounded(sn, q.x) + detail::mulRounded(c, q.y), q.z);
                out.emplace_back(sets.frame.toWorld(rotated), 0.0);
            }
    for (uint32_t r = 0; r < rotations; ++r) out.emplace_back(steps[r], 0.0, 0.0);
    return out;
}

/// SoftSkips::wedges: the radius about the light's centre of a sphere holding every light sample of
/// `table` (sampleBasedSoftSampleTable's; its first `samples` entries), 1e-9 relative above the
/// largest distance computed in double. The wedge planes need only the samples on their far side:
/// every bit is a sample's. (For a spherical light about r; the shape's bound, r sqrt 3, is 1.7x.)
inline double sampleBasedSoftSampleReach(const std::vector<glm::dvec4>& table, size_t samples, const glm::dvec3& centre) {
    double reach = 0.0;
    for (size_t i = 0; i < samples && i < table.size(); ++i)
        reach = std::max(reach, detail::oracle::length3(glm::dvec3(table[i]) - centre));
    return reach * (1.0 + 1e-9);
}

struct SampleBasedSoftCpuResult {
    uint32_t words_per_receiver = 0;  ///< ceil(N / 32)
    std::vector<uint32_t> masks;      ///< receivers * words_per_receiver: blocked light samples
    // Device-independent work counters.
    uint64_t pairs = 0;             ///< (receiver, caster) pairs evaluated
    uint64_t pairs_ignored = 0;     ///< caster ignored for the receiver: the coplanar rule for all samples, or
                                    ///< p in T's plane with the whole light on one side (T blocks nothing)
    uint64_t pairs_unproven = 0;    ///< Exact: every bit of the pair decided by the oracle's verdict
    uint64_t planes = 0;            ///< plane lookups (per table)
    uint64_t planes_unproven = 0;   ///< Exact: planes whose rounding bound exceeded the tolerance
    uint64_t bits = 0;              ///< pair bits evaluated (pairs x N)
    uint64_t uncertain_bits = 0;    ///< Exact: pair bits the LUT could not vouch for
    /// Per-sample oracle verdicts computed (Exact: the uncertain bits the side planes left, and
    /// every bit of unproven pairs; Brute: every bit).
    uint64_t exact_tests = 0;
    uint64_t triangles_culled = 0;  ///< SoftSkips::closed_casters: casters culled (each counted once)
    uint64_t pairs_cut = 0;         ///< SoftSkips::plane_cut: pairs skipped (not in `pairs`)
    uint64_t pairs_wedged = 0;      ///< SoftSkips::wedges: pairs skipped first (in no other counter)
    /// SoftSkips::closed_casters: (receiver, culled caster) pairs evaluated after all, the receiver
    /// lying within the oracle's coplanar reach of a kept closed triangle (then in pairs, pairs_cut or
    /// pairs_wedged).
    uint64_t pairs_recovered = 0;
    /// Lut and Exact: pairs decided at once because the whole light lies in front of one of the
    /// pair's planes (a trivial LUT cell; in Exact a proven plane): T blocks nothing for the
    /// receiver, no table is read (in `pairs`, not in `planes`).
    uint64_t pairs_front = 0;

    bool blocked(size_t r, uint32_t s) const { return (masks[r * words_per_receiver + s / 32] >> (s % 32)) & 1u; }
    uint32_t blockedCount(size_t r) const {
        uint32_t c = 0;
        for (uint32_t w = 0; w < words_per_receiver; ++w)
            c += detail::oracle::popcount32(masks[r * words_per_receiver + w]);
        return c;
    }
};

namespace detail::soft {

inline constexpr double kEpsilon = 0x1.0p-53;

/// A local plane and whether its rounding bound allows certain answers.
struct LocalPlane {
    glm::dvec4 plane{0.0};
    bool proven = false;
};

inline double maxAbs3(const glm::dvec3& v) { return std::max(std::fabs(v.x), std::max(std::fabs(v.y), std::fabs(v.z))); }

/// The plane through `origin` spanned by a and b (world), oriented by `flip`, in the light's
/// normalised space, with its rounding bound checked against `budget` (normalised units):
///   |dn| <= 8 eps |a| |b| (differences and the cross product rounded, products of floats exact),
///   world signed-distance error at a light point x <= (|dn| + 4 eps |n|) (|x| + |origin|) / |n|,
///   normalised by the smallest semi-axis, plus 24 eps (planeToLocal, a rotation step).
inline LocalPlane localPlane(const LightFrame& frame, const glm::dvec3& origin, const glm::dvec3& a, const glm::dvec3& b,
                             bool flip, double reach, double min_scale, double budget) {
    LocalPlane out;
    glm::dvec3 n = oracle::cross3(a, b);
    const double length = oracle::length3(n);
    if (!(length > 0.0) || !std::isfinite(length)) return out;
    if (flip) n = -n;
    const double w = -oracle::dot3(n, origin);
    const double dn = 8.0 * kEpsilon * oracle::length3(a) * oracle::length3(b);
    // (+ 16 eps for planeToLocal, + 8 eps for a rotation step applied afterwards.)
    const double error = (dn + 4.0 * kEpsilon * length) * (reach + oracle::length3(origin)) / length / min_scale + 24.0 * kEpsilon;
    out.plane = frame.planeToLocal(glm::dvec4(n, w));
    out.proven = error <= budget;
    return out;
}

/// Exact: a plane that decides the LUT's uncertain bits in world space (the GPU's
/// penumbraSbsSidePlane, step for step): the plane through `origin` spanned by a and b (flipped by
/// `flip`; behind: dot(n, x - origin) < 0, localPlane's side) and the threshold above which
/// |dot(n, l - origin)| proves a light sample l farther than `margin` (world units) from the exact
/// plane on the same inputs, on the computed value's side. Why: the value is off by at most
/// (dn + 4 eps |n|) |l - origin| (dn = 8 eps |a| |b| as in localPlane; l - origin rounds by eps
/// |l - origin|, the dot product by 3 eps |n| |l - origin|), |l - origin| <= |centre - origin| +
/// light_reach, and the exact normal is at most |n| + dn long; 1e-6 relative covers the bound's
/// own rounding. A zero normal decides nothing (its value is 0).
struct SidePlane {
    glm::dvec3 n{0.0};
    double threshold = 0.0;
};

inline SidePlane sidePlane(const glm::dvec3& origin, const glm::dvec3& a, const glm::dvec3& b, bool flip,
                           const glm::dvec3& centre, double light_reach, double margin) {
    SidePlane out;
    out.n = oracle::cross3(a, b);
    if (flip) out.n = -out.n;
    const double length = oracle::length3(out.n);
    const double dn = 8.0 * kEpsilon * oracle::length3(a) * oracle::length3(b);
    const double reach = (oracle::length3(centre - origin) + light_reach) * (1.0 + 1e-6);
    out.threshold = ((dn + 4.0 * kEpsilon * length) * reach + margin * (length + dn)) * (1.0 + 1e-6);
    return out;
}

/// A light sample l against T's three edge planes through p and T's plane through v0 (sidePlane):
/// -1 behind every one by the margin (T blocks l for p), 1 in front of one by the margin (T does
/// not), 0 neither (left to the oracle's test). With the margin above the oracle's tie and coplanar
/// reach at l (the pair-level conditions under which Exact trusts the LUT), a decided sample gets
/// the oracle's verdict: the same argument as a certain LUT bit's.
inline int sideVerdict(const glm::dvec3& l, const glm::dvec3& p, const glm::dvec3& v0, const SidePlane (&planes)[4]) {
    const glm::dvec3 dp = l - p, d0 = l - v0;
    const double g0 = oracle::dot3(planes[0].n, dp), g1 = oracle::dot3(planes[1].n, dp), g2 = oracle::dot3(planes[2].n, dp),
                 g3 = oracle::dot3(planes[3].n, d0);
    if (g0 > planes[0].threshold || g1 > planes[1].threshold || g2 > planes[2].threshold || g3 > planes[3].threshold) return 1;
    if (g0 < -planes[0].threshold && g1 < -planes[1].threshold && g2 < -planes[2].threshold && g3 < -planes[3].threshold)
        return -1;
    return 0;
}

/// A caster's supporting plane against the light, for the skips (the GPU's light_pass.geom.glsl
/// and light_pass.frag.glsl compute the same, step for step). normal = (v1 - v0) x (v2 - v0) in
/// double from the float vertices; a signed distance dot(normal, x - v0) / |normal| is off by at
/// most (dn + 4 eps |normal|) |x - v0| / |normal| with dn = 8 eps |v1 - v0| |v2 - v0| (localPlane's
/// bound), shrunk by another 1e-9 relative for the divisions.
struct CasterPlane {
    glm::dvec3 v0{0.0}, normal{0.0};
    double normal_length = 0.0;
    double error_per_unit = 0.0;  ///< (dn + 4 eps |normal|) / |normal|: error per unit of |x - v0|
    double light_side = 0.0;      ///< dot(normal, centre - v0): the light centre's side
    /// The light's clearance: every light point lies on light_side's side, at least this far from
    /// the plane (<= 0: not proven; the light may straddle the plane).
    double light_clearance = 0.0;
};

inline CasterPlane casterPlane(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2, const glm::dvec3& centre,
                               double light_reach) {
    CasterPlane c;
    c.v0 = v0;
    const glm::dvec3 e0 = v1 - v0, e1 = v2 - v0;
    c.normal = oracle::cross3(e0, e1);
    c.normal_length = oracle::length3(c.normal);
    if (!(c.normal_length > 0.0) || !std::isfinite(c.normal_length)) return c;
    const double dn = 8.0 * kEpsilon * oracle::length3(e0) * oracle::length3(e1);
    c.error_per_unit = (dn + 4.0 * kEpsilon * c.normal_length) / c.normal_length;
    const glm::dvec3 to_centre = centre - v0;
    c.light_side = oracle::dot3(c.normal, to_centre);
    c.light_clearance =
        (std::fabs(c.light_side) / c.normal_length - c.error_per_unit * oracle::length3(to_centre)) * (1.0 - 1e-9) - light_reach;
    return c;
}

/// SoftSkips::closed_casters: the whole light strictly behind the plane (culled when closed).
inline bool casterFacesAway(const CasterPlane& c) { return c.light_side < 0.0 && c.light_clearance > 0.0; }

/// p strictly on the plane's positive side (normal = (v1 - v0) x (v2 - v0): outside a closed,
/// outward-oriented mesh's face): a segment from p to a light point in front of the face never
/// crosses its plane, so it cannot leave a solid through it (SoftSkips::closed_casters).
inline bool casterPlaneOutside(const CasterPlane& c, const glm::dvec3& p) {
    if (!(c.normal_length > 0.0)) return false;
    const glm::dvec3 to_p = p - c.v0;
    const double side = oracle::dot3(c.normal, to_p);
    return side > 0.0 && (side / c.normal_length - c.error_per_unit * oracle::length3(to_p)) * (1.0 - 1e-9) > 0.0;
}

/// SoftSkips::plane_cut: p and the whole light strictly on one side, both farther than `reach`.
inline bool casterPlaneCuts(const CasterPlane& c, const glm::dvec3& p, double reach) {
    if (!(c.light_clearance > reach)) return false;
    const glm::dvec3 to_p = p - c.v0;
    const double side = oracle::dot3(c.normal, to_p);
    const double clearance = (std::fabs(side) / c.normal_length - c.error_per_unit * oracle::length3(to_p)) * (1.0 - 1e-9);
    return clearance > reach && (side > 0.0) == (c.light_side > 0.0);
}

/// SoftSkips::silhouettes' second condition (silhouettes.frag.glsl's near pass computes the same,
/// step for step): true when the oracle's coplanar rule may ignore T for some light sample of p
/// (p or the sample within coplanar_epsilon * scale of T) while a segment from p to the light could
/// cross T's plane where another triangle is counted: T's edges are then open for p, and p's light
/// need not be all-or-nothing outside every silhouette's region (a grazing light over a floor
/// made of two triangles: the crossing walks from the ignored one over the diagonal into the
/// counted one). False needs the whole light strictly on one side of T's plane and p strictly on
/// that side too (no segment meets the plane) or so close to the plane that every segment meets
/// it within epsilon * s_min of p, where every triangle is ignored for every light sample
/// (s_min <= |l - p|_inf for each light point l). scale_v: max |v_i - p|_inf; distance2: p to T,
/// light_distance2: the light's centre to T, both squared. scene_extent: the oracle's E; s_min and
/// s_max are capped at it as the oracle caps |l - p|_inf (min(., E) is monotone: still bounds).
inline bool coplanarOpen(const CasterPlane& c, const glm::dvec3& p, double scale_v, double distance2, double light_distance2,
                         const glm::dvec3& centre, double light_reach, double epsilon, double scene_extent) {
    const glm::dvec3 to_centre = centre - p;
    const double centre_reach = std::max(std::fabs(to_centre.x), std::max(std::fabs(to_centre.y), std::fabs(to_centre.z)));
    const double s_min = std::min(std::max(0.0, centre_reach - light_reach), scene_extent);
    const double s_max = std::min(centre_reach + light_reach, scene_extent);
    const double reach = epsilon * std::max(scale_v, s_max);
    const double light_near = reach + light_reach;
    const bool p_near = !(distance2 > reach * reach * (1.0 + 1e-9));
    const bool light_near_t = !(light_distance2 > light_near * light_near * (1.0 + 1e-9));
    if (!p_near && !light_near_t) return false;  // T is counted for every light sample
    if (light_near_t || !(c.normal_length > 0.0) || !(c.light_clearance > 0.0)) return true;
    const glm::dvec3 to_p = p - c.v0;
    const double side = oracle::dot3(c.normal, to_p);
    const double error = c.error_per_unit * oracle::length3(to_p);
    const double distance = std::fabs(side) / c.normal_length;
    if ((side > 0.0) == (c.light_side > 0.0) && (distance - error) * (1.0 - 1e-9) > 0.0) return false;  // p on the light's side
    // The segment to a light point l meets the plane d |l - p| / (d + h) <= d |l - p| / clearance from p.
    const double d_hi = (distance + error) * (1.0 + 1e-9);
    const double length_hi = (oracle::length3(to_centre) + light_reach) * (1.0 + 1e-9);
    const double r_min = epsilon * s_min * (1.0 - 1e-6);
    return !(d_hi * length_hi < r_min * c.light_clearance);
}

/// SoftSkips::wedges: up to four planes F(x) = n . x + d per caster T (float n, d: what the
/// light pass's fragment stage evaluates), each proven to have T's three vertices on its closed
/// positive side and a sphere about the light's centre holding every light sample
/// (sampleBasedSoftSampleReach) strictly on its negative side. A blocked segment
/// from p to a light point l meets T, so F(p) >= 0 on each (F is affine, F(l) < 0 <= F(t) and
/// p = t + s (t - l), s >= 0). Per edge the plane through it tangent to the sphere grown by 4
/// delta, shifted delta towards the light (T's side of the edge's dihedral wedge, sintorn2008
/// §4.1's penumbra wedge); the fourth is T's own plane when the whole light lies on one side.
/// (0, 0, 0, 1) where no plane is proven: it never rejects.
struct WedgePlanes {
    glm::vec4 planes[4];
    float margin = 0.0f;  ///< 2 mu S (rounded up): the reject margin at receivers inside [-S, S]^3
    float reach = 0.0f;   ///< S: the box [-S, S]^3 holds T's vertices and the light; receivers beyond 4 S are kept
};

/// The wedges' tolerance: 4 max(tie, coplanar epsilon) (the oracle's reach at a pair is at most
/// that epsilon times twice the receiver's or the scene's largest coordinate) plus 2^-21 for the
/// float planes' rounding.
inline double wedgeMu(double eps) { return 4.0 * eps + 0x1.0p-21; }
/// wedgeRejects' per-receiver margin factor, float(2 mu * 1.001): set up once (the GPU reads it from
/// the parameter block, PenumbraSbsParams::reserved.z).
inline float wedgeMu2(double eps) { return static_cast<float>(2.0 * wedgeMu(eps) * 1.001); }

/// `plane` (float coefficients, evaluated exactly in double up to the bounded rounding) has every
/// vertex on its closed positive side and the sphere (centre, reach) strictly on its negative side.
inline bool wedgeProven(const glm::vec4& plane, const glm::dvec3 (&v)[3], const glm::dvec3& centre, double reach) {
    const glm::dvec3 n(plane.x, plane.y, plane.z);
    const double d = plane.w;
    for (const glm::dvec3& x : v) {
        // Float times float is exact in double: only the three additions round.
        const double f = ((n.x * x.x + n.y * x.y) + n.z * x.z) + d;
        const double size = std::fabs(n.x * x.x) + std::fabs(n.y * x.y) + std::fabs(n.z * x.z) + std::fabs(d);
        if (!(f - 4.0 * kEpsilon * size >= 0.0)) return false;
    }
    const double f = ((n.x * centre.x + n.y * centre.y) + n.z * centre.z) + d;
    const double size = std::fabs(n.x * centre.x) + std::fabs(n.y * centre.y) + std::fabs(n.z * centre.z) + std::fabs(d);
    const double length = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z) * (1.0 + 64.0 * kEpsilon);  // GPUs: sqrt within 2.5 ulp
    return f + reach * length * (1.0 + 8.0 * kEpsilon) + 8.0 * kEpsilon * size < 0.0;
}

inline WedgePlanes wedgePlanes(const glm::dvec3& v0, const glm::dvec3& v1, const glm::dvec3& v2, const glm::dvec3& centre,
                               double reach, double eps) {
    namespace oracle = detail::oracle;
    const glm::dvec3 v[3] = {v0, v1, v2};
    const double scene = std::max(std::max(maxAbs3(v0), maxAbs3(v1)), std::max(maxAbs3(v2), maxAbs3(centre) + reach));
    const double mu = wedgeMu(eps), delta = 2.0 * mu * scene, grown = reach + 4.0 * delta;
    WedgePlanes w;
    for (glm::vec4& q : w.planes) q = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    w.margin = static_cast<float>(2.0 * mu * scene * 1.001);
    w.reach = static_cast<float>(scene);
    for (int e = 0; e < 3; ++e) {
        const glm::dvec3 a = v[e], b = v[(e + 1) % 3], o = v[(e + 2) % 3];
        glm::dvec3 u = b - a;
        const double length = oracle::length3(u);
        if (!(length > 0.0)) continue;
        u = u / length;
        // In the plane across the edge: the sphere's centre at distance D, the opposite vertex.
        const glm::dvec3 ca = centre - a, oa = o - a;
        const glm::dvec3 w_c = ca - oracle::dot3(ca, u) * u, w_o = oa - oracle::dot3(oa, u) * u;
        const double distance = oracle::length3(w_c);
        if (!(distance > grown * (1.0 + 1e-6))) continue;  // the edge's line meets the grown sphere
        const glm::dvec3 across = w_c / distance, side = oracle::cross3(u, across);
        const double alpha = -grown / distance, beta = std::sqrt(std::max(0.0, 1.0 - alpha * alpha));
        const glm::dvec3 m = alpha * across + (oracle::dot3(side, w_o) < 0.0 ? -beta : beta) * side;
        const glm::vec4 plane(static_cast<float>(m.x), static_cast<float>(m.y), static_cast<float>(m.z),
                              static_cast<float>(delta - oracle::dot3(m, a)));
        if (wedgeProven(plane, v, centre, reach)) w.planes[e] = plane;
    }
    glm::dvec3 normal = oracle::cross3(v1 - v0, v2 - v0);
    const double length = oracle::length3(normal);
    if (length > 0.0) {
        normal = normal / length;
        if (oracle::dot3(normal, centre - v0) > 0.0) normal = -normal;
        const glm::vec4 plane(static_cast<float>(normal.x), static_cast<float>(normal.y), static_cast<float>(normal.z),
                              static_cast<float>(delta - oracle::dot3(normal, v0)));
        if (wedgeProven(plane, v, centre, reach)) w.planes[3] = plane;
    }
    return w;
}

/// The float test of light_pass.frag.glsl (the same operations): p lies farther than the margin
/// on the negative side of one of the planes, so T blocks no light point for p and the oracle's
/// rules cannot reach it (its distance to T's planes exceeds 2 mu max(S, |p|_inf)); receivers
/// beyond 4 S are kept. `mu2` = wedgeMu2.
inline bool wedgeRejects(const WedgePlanes& w, const glm::vec3& p, float mu2) {
    const float size = std::max(std::fabs(p.x), std::max(std::fabs(p.y), std::fabs(p.z)));
    if (!(size <= 4.0f * w.reach)) return false;
    const float margin = std::max(w.margin, mu2 * size);
    for (const glm::vec4& q : w.planes) {
        const float f = ((q.x * p.x + q.y * p.y) + q.z * p.z) + q.w;
        const float e = ((std::fabs(q.x * p.x) + std::fabs(q.y * p.y)) + std::fabs(q.z * p.z)) + std::fabs(q.w);
        if (f < -(margin + 1e-6f * e)) return true;
    }
    return false;
}

}  // namespace detail::soft

/// CPU twin of the sample-based soft-shadow pipeline's per-sample work (see the header comment).
/// `lut` / `lut_words` may be null for Brute. Throws penumbra::Error for bad input.
inline SampleBasedSoftCpuResult sampleBasedSoftCpu(const LightSampleSets& sets, const LightLutSetup* lut,
                                                   const uint32_t* lut_words, const SoftCasters& casters,
                                                   const SoftReceivers& receivers,
                                                   const SampleBasedSoftOptions& options = {}) {
    namespace oracle = detail::oracle;
    namespace soft = detail::soft;
    const uint32_t n = sets.count(), k = sets.sets();
    const SoftMode mode = options.mode;
    PENUMBRA_CHECK(mode == SoftMode::Exact || mode == SoftMode::Lut || mode == SoftMode::Brute,
                   "sampleBasedSoftCpu: unknown mode ", static_cast<uint32_t>(mode));
    if (mode != SoftMode::Brute) {
        PENUMBRA_CHECK(lut != nullptr && lut_words != nullptr, "sampleBasedSoftCpu: mode ", softModeName(mode),
                       " needs a LUT");
        PENUMBRA_CHECK(lut->params.samples_per_set == n && lut->params.sets == k, "sampleBasedSoftCpu: the LUT was built for ",
                       lut->params.sets, " sets of ", lut->params.samples_per_set, " samples, the light has ", k, " of ", n);
        PENUMBRA_CHECK(mode != SoftMode::Exact || lut->options.certified,
                       "sampleBasedSoftCpu: mode exact needs a certified LUT (LightLutOptions::certified)");
    }
    PENUMBRA_CHECK(casters.triangle_count == 0 || (casters.positions && casters.indices),
                   "sampleBasedSoftCpu: casters need positions and indices");
    PENUMBRA_CHECK(receivers.count == 0 || receivers.positions, "sampleBasedSoftCpu: receivers need positions");
    for (size_t i = 0; i < casters.triangle_count * 3; ++i)
        PENUMBRA_CHECK(casters.indices[i] < casters.vertex_count, "sampleBasedSoftCpu: index ", i, " is ",
                       casters.indices[i], ", beyond the ", casters.vertex_count, " caster vertices");
    auto finite = [](const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    for (size_t i = 0; i < casters.vertex_count; ++i)
        PENUMBRA_CHECK(finite(casters.positions[i]), "sampleBasedSoftCpu: caster vertex ", i, " is not finite");
    PENUMBRA_CHECK(options.scene_extent > 0.0,  // NaN fails too; +inf is the uncapped rule
                   "sampleBasedSoftCpu: scene_extent ", options.scene_extent, " must be > 0 (or +inf)");
    const uint32_t rotations = options.rotations;
    const std::vector<glm::dvec4> table = sampleBasedSoftSampleTable(sets, rotations);  // checks rotations
    for (size_t r = 0; r < receivers.count; ++r) {
        PENUMBRA_CHECK(finite(receivers.positions[r]), "sampleBasedSoftCpu: receiver ", r, " is not finite");
        const uint32_t word = receivers.sets ? receivers.sets[r] : 0u;
        PENUMBRA_CHECK((word & 0xFFu) < k, "sampleBasedSoftCpu: receiver ", r, " uses set ", word & 0xFFu, " of ", k);
        PENUMBRA_CHECK((word >> 8) < rotations, "sampleBasedSoftCpu: receiver ", r, " uses rotation step ", word >> 8,
                       " of ", rotations);
    }

    SampleBasedSoftCpuResult result;
    result.words_per_receiver = (n + 31) / 32;
    const uint32_t words = result.words_per_receiver;
    result.masks.assign(receivers.count * words, 0u);
    const LightFrame& frame = sets.frame;
    const double min_scale = std::min(frame.scale.x, std::min(frame.scale.y, frame.scale.z));
    const double max_scale = std::max(frame.scale.x, std::max(frame.scale.y, frame.scale.z));
    const double tolerance = lut ? lut->options.tolerance : 0.0;
    const double budget = 0.5 * tolerance;
    const double margin_world = budget * min_scale;
    const double eps = std::max(options.oracle.tie_epsilon, options.oracle.coplanar_epsilon);
    const double light_reach = max_scale * std::sqrt(3.0);  // |x - centre| over the light, any norm
    const double extent = options.scene_extent;             // the oracle's E
    const uint32_t tables = lut ? lut->params.tables_per_set : 0;
    // T's plane depends on T alone: built once per caster, oriented per receiver by negation (exact:
    // every operation of localPlane commutes with it, so the bits are those of building it flipped).
    // So does the squared distance from the light's centre to T (is any light sample within the
    // oracle's coplanar reach of T?).
    std::vector<soft::LocalPlane> support(mode == SoftMode::Brute ? 0 : casters.triangle_count);
    std::vector<double> light_distance2(support.size()), normal_length(support.size()), light_gap(support.size());
    for (size_t t = 0; t < support.size(); ++t) {
        const glm::dvec3 v0(casters.positions[casters.indices[3 * t]]);
        const glm::dvec3 v1(casters.positions[casters.indices[3 * t + 1]]);
        const glm::dvec3 v2(casters.positions[casters.indices[3 * t + 2]]);
        support[t] = soft::localPlane(frame, v0, v1 - v0, v2 - v0, false, oracle::length3(frame.center) + light_reach,
                                      min_scale, budget);
        light_distance2[t] = detail::pointTriangleDistance2<double>(frame.center, v0, v1, v2);
        // Distance from T's plane to the nearest light point (<= 0: the light may straddle it).
        const glm::dvec3 normal = oracle::cross3(v1 - v0, v2 - v0);
        normal_length[t] = oracle::length3(normal);
        // (|dot| rounds by <= 4 eps |normal| |centre - v0|: subtracted, then 1e-9 for the rest.)
        light_gap[t] = normal_length[t] > 0.0
                           ? (std::fabs(oracle::dot3(normal, frame.center - v0)) / normal_length[t] -
                              4.0 * soft::kEpsilon * oracle::length3(frame.center - v0)) * (1.0 - 1e-9) - light_reach
                           : 0.0;
    }

    // The skips' view of each caster's plane; culled casters (closed, facing away from the light).
    const bool cull = options.skips.closed_casters && casters.closed != nullptr, cut = options.skips.plane_cut;
    std::vector<soft::CasterPlane> caster_planes(cull || cut ? casters.triangle_count : 0);
    std::vector<uint8_t> culled(casters.triangle_count, 0);
    for (size_t t = 0; t < caster_planes.size(); ++t) {
        const glm::dvec3 v0(casters.positions[casters.indices[3 * t]]);
        const glm::dvec3 v1(casters.positions[casters.indices[3 * t + 1]]);
        const glm::dvec3 v2(casters.positions[casters.indices[3 * t + 2]]);
        if (detail::degenerateTriangle(v0, v1, v2)) continue;
        caster_planes[t] = soft::casterPlane(v0, v1, v2, frame.center, light_reach);
        if (cull && casters.closed[t] != 0 && soft::casterFacesAway(caster_planes[t])) {
            culled[t] = 1;
            ++result.triangles_culled;
        }
    }

    // SoftSkips::wedges: each caster's planes (the geometry stage's).
    const bool wedges = options.skips.wedges;
    std::vector<soft::WedgePlanes> wedge(wedges ? casters.triangle_count : 0);
    const double sample_reach = sampleBasedSoftSampleReach(table, size_t(n) * k * rotations, frame.center);
    for (size_t t = 0; t < wedge.size(); ++t)
        wedge[t] = soft::wedgePlanes(glm::dvec3(casters.positions[casters.indices[3 * t]]),
                                     glm::dvec3(casters.positions[casters.indices[3 * t + 1]]),
                                     glm::dvec3(casters.positions[casters.indices[3 * t + 2]]), frame.center, sample_reach, eps);
    const float wedge_mu2 = soft::wedgeMu2(eps);

    for (size_t r = 0; r < receivers.count; ++r) {
        const glm::dvec3 p(receivers.positions[r]);
        const uint32_t word = receivers.sets ? receivers.sets[r] : 0u;
        const uint32_t set = word & 0xFFu, step = word >> 8;
        const glm::dvec4* world = table.data() + (size_t(set) * rotations + step) * n;
        const glm::dvec2 turn(table[size_t(n) * k * rotations + step]);
        uint32_t* out = result.masks.data() + r * words;
        // Bounds of the oracle's per-sample scale term min(|s - p|_inf, E) over the light (capping
        // keeps them bounds: min(., E) is monotone). s_far: uncapped, for rounding (below).
        const double centre_reach = soft::maxAbs3(frame.center - p);
        const double s_far = centre_reach + light_reach;
        const double s_min = std::min(std::max(0.0, centre_reach - light_reach), extent), s_max = std::min(s_far, extent);
        const double light_far = oracle::length3(frame.center) + light_reach;  // |x| over the light

        // SoftSkips::closed_casters, exactly: sweep 0 evaluates every caster but the culled ones and
        // finds whether p lies within the oracle's coplanar reach of a kept closed triangle (rule 2
        // may then ignore the face a blocked segment leaves through: see SoftSkips); only then does
        // sweep 1 evaluate the culled ones for p.
        bool near_closed = false;
        for (int sweep = 0; sweep < (cull ? 2 : 1); ++sweep)
        for (size_t t = 0; t < casters.triangle_count; ++t) {
            if ((culled[t] != 0) != (sweep == 1) || (sweep == 1 && !near_closed)) continue;
            const glm::dvec3 v0(casters.positions[casters.indices[3 * t]]);
            const glm::dvec3 v1(casters.positions[casters.indices[3 * t + 1]]);
            const glm::dvec3 v2(casters.positions[casters.indices[3 * t + 2]]);
            if (detail::degenerateTriangle(v0, v1, v2)) continue;
            if (sweep == 1) ++result.pairs_recovered;
            if (wedges && soft::wedgeRejects(wedge[t], receivers.positions[r], wedge_mu2)) {
                ++result.pairs_wedged;  // (farther from T than the closed casters' near reach, too)
                continue;
            }
            // The oracle's scale (rule 2/3) for this pair lies in [scale_lo, scale_hi] over the samples.
            const double scale_v = std::max(soft::maxAbs3(v0 - p), std::max(soft::maxAbs3(v1 - p), soft::maxAbs3(v2 - p)));
            const double scale_lo = std::max(scale_v, s_min), scale_hi = std::max(scale_v, s_max);
            if (cull && sweep == 0 && !near_closed && casters.closed[t] != 0) {
                const double reach_c = options.oracle.coplanar_epsilon * scale_hi;
                near_closed = detail::pointTriangleDistance2<double>(p, v0, v1, v2) <= reach_c * reach_c * (1.0 + 1e-9) &&
                              !soft::casterPlaneOutside(caster_planes[t], p);
            }
            if (cut && soft::casterPlaneCuts(caster_planes[t], p, 2.0 * eps * scale_hi)) {
                ++result.pairs_cut;
                continue;
            }
            ++result.pairs;
            result.bits += n;
            oracle::Triangle tri{v0, v1, v2, static_cast<uint32_t>(t)};
            auto decide = [&](uint32_t s) {  // the oracle's verdict for one pair
                ++result.exact_tests;
                const oracle::Verdict v =
                    oracle::classifySegment(tri, oracle::makeSegmentQuery(p, glm::dvec3(world[s]), options.oracle, extent));
                return v.hit;
            };
            if (mode == SoftMode::Brute) {
                for (uint32_t s = 0; s < n; ++s)
                    if (decide(s)) out[s / 32] |= 1u << (s % 32);
                continue;
            }
            bool unproven = false, near = false;
            const double distance2 = detail::pointTriangleDistance2<double>(p, v0, v1, v2);
            {
                const double ignore = options.oracle.coplanar_epsilon * scale_lo;
                if (distance2 < ignore * ignore * (1.0 - 1e-9)) {  // the oracle ignores T for every sample
                    ++result.pairs_ignored;
                    continue;
                }
                const double reach = 2.0 * eps * scale_hi;
                // The LUT's margin must exceed the reach of the oracle's rules at the light samples:
                // its tie/rounding reach always, its coplanar reach only where a light sample can
                // come that close to T (a light touching a caster, not an ordinary scene).
                const double light_near = 2.0 * options.oracle.coplanar_epsilon * scale_hi + light_reach;
                const bool light_touches = light_distance2[t] <= light_near * light_near * (1.0 + 1e-9);
                // The tie term stays uncapped (s_far): a certain bit's margin at the light must stay
                // far above the oracle's rounding, which is relative to |s - p|_inf (its shear and
                // edge functions see the light's direction, not the capped scale). Near lights: the
                // old value; far ones only take more pairs sample by sample.
                const double margin_reach =
                    2.0 * std::max(light_touches ? eps * scale_hi : 0.0, options.oracle.tie_epsilon * std::max(scale_v, s_far));
                near = distance2 <= reach * reach * (1.0 + 1e-9);
                unproven = mode == SoftMode::Exact && (near || !(margin_world > margin_reach));
            }
            // Orientation of the shadow cone: the opposite vertex behind each edge plane; p in front
            // of T's plane. det = (v0 - p) . ((v1 - p) x (v2 - p)) decides both: cross(a, b) . c,
            // cross(b, c) . a, cross(c, a) . b all equal det, and T's normal (v1 - v0) x (v2 - v0)
            // gives p the side -det.
            const glm::dvec3 a = v0 - p, b = v1 - p, c = v2 - p;
            const double det = oracle::dot3(a, oracle::cross3(b, c));
            const double det_bound = 16.0 * soft::kEpsilon * oracle::length3(a) * oracle::length3(b) * oracle::length3(c);
            if (!(std::fabs(det) > det_bound)) {
                // p lies (up to rounding) in T's plane: the edge planes degenerate into T's plane
                // and det's sign is noise. When the whole light lies on one side of that plane, a
                // segment from p to a light sample meets the plane only within delta * L / gap of
                // p (delta: p's distance to the plane, L: |s - p|), outside T when that is below
                // half p's distance to T (> reach, beyond the oracle's tie reach): T blocks
                // nothing for p, the oracle's verdict for every sample (receivers on a tessellated
                // floor against its other triangles).
                const double delta = (std::fabs(det) + det_bound) / normal_length[t] * (1.0 + 1e-9);
                const double reach_p = oracle::length3(frame.center - p) + light_reach;
                const double gap = light_gap[t];
                if (!near && gap > 0.0 && normal_length[t] > 0.0 &&
                    (delta * reach_p) * (delta * reach_p) <= 0.25 * gap * gap * distance2) {
                    ++result.pairs_ignored;
                    continue;
                }
                if (mode == SoftMode::Exact) unproven = true;
            }
            const bool positive = det > 0.0;
            // Edge planes through p: edge (v0 v1) opposite v2 is spanned by a, b, etc. With det > 0
            // the opposite vertex lies on the positive side of cross(a, b): flip so it is behind.
            const double reach_world = light_far;
            soft::LocalPlane planes[4] = {
                soft::localPlane(frame, p, a, b, positive, reach_world, min_scale, budget),
                soft::localPlane(frame, p, b, c, positive, reach_world, min_scale, budget),
                soft::localPlane(frame, p, c, a, positive, reach_world, min_scale, budget),
                // T's plane through v0, oriented with p in front: samples beyond T are behind it.
                support[t],
            };
            if (positive) planes[3].plane = -planes[3].plane;
            // Rotated samples are behind a plane when the unrotated ones (the LUT's) are behind it
            // rotated back (lightLutRotate; exact in its rounding: localPlane's bound covers it).
            if (step != 0)
                for (soft::LocalPlane& plane : planes) plane.plane = lightLutRotate(plane.plane, turn.x, turn.y);
            if (mode == SoftMode::Exact && unproven) {
                ++result.pairs_unproven;
                result.uncertain_bits += n;
                for (uint32_t s = 0; s < n; ++s)
                    if (decide(s)) out[s / 32] |= 1u << (s % 32);
                continue;
            }
            // The whole light in front of one plane (trivial cell: no sample behind it in any table;
            // in Exact only a proven plane's cell counts): every table would AND in a zero mask and
            // leave no bit uncertain, so T blocks nothing for p. The GPU light pass does the same.
            bool front = false;
            for (const soft::LocalPlane& plane : planes)
                front = front || ((mode == SoftMode::Lut || plane.proven) && lightLutLocate(lut->params, plane.plane).trivial < 0);
            if (front) {
                ++result.pairs_front;
                continue;
            }
            // Exact: the planes that decide the LUT's uncertain bits, with the LUT's separation in
            // world units (margin_world, above the oracle's reach at the light for this pair).
            soft::SidePlane side_planes[4];
            if (mode == SoftMode::Exact) {
                side_planes[0] = soft::sidePlane(p, a, b, positive, frame.center, light_reach, margin_world);
                side_planes[1] = soft::sidePlane(p, b, c, positive, frame.center, light_reach, margin_world);
                side_planes[2] = soft::sidePlane(p, c, a, positive, frame.center, light_reach, margin_world);
                side_planes[3] = soft::sidePlane(v0, v1 - v0, v2 - v0, positive, frame.center, light_reach, margin_world);
            }
            for (uint32_t block = 0; block < tables; ++block) {
                const uint32_t table = set * tables + block;
                result.planes += 4;
                if (mode == SoftMode::Lut) {
                    LutMask m{~0u, ~0u, ~0u, ~0u};
                    for (const soft::LocalPlane& plane : planes) {
                        const LutMask behind = lightLutLookup(lut->params, lut_words, table, plane.plane).centre;
                        for (int w = 0; w < 4; ++w) m[w] &= behind[w];
                    }
                    for (int w = 0; w < 4 && block * 4 + w < words; ++w) out[block * 4 + w] |= m[w];
                    continue;
                }
                LutCertain combined;
                for (int i = 0; i < 4; ++i) {
                    LutCertain c_i;
                    if (planes[i].proven) {
                        c_i = lutCertain(lightLutLookup(lut->params, lut_words, table, planes[i].plane));
                    } else {
                        ++result.planes_unproven;
                        c_i.uncertain = lightLutValidMask(lut->params, table);
                    }
                    combined = i == 0 ? c_i : lutCombine(combined, c_i);
                }
                const LutMask valid = lightLutValidMask(lut->params, table);
                for (int w = 0; w < 4 && block * 4 + w < words; ++w) {
                    uint32_t m = combined.behind[w];
                    uint32_t uncertain = combined.uncertain[w] & valid[w];
                    result.uncertain_bits += oracle::popcount32(uncertain);
                    while (uncertain) {
                        const uint32_t bit = static_cast<uint32_t>(__builtin_ctz(uncertain));
                        uncertain &= uncertain - 1u;
                        // The pair's own planes first (nearly every uncertain bit), then the oracle.
                        const uint32_t s = block * 128u + 32u * w + bit;
                        const int side = soft::sideVerdict(glm::dvec3(world[s]), p, v0, side_planes);
                        if (side < 0 || (side == 0 && decide(s))) m |= 1u << bit;
                    }
                    out[block * 4 + w] |= m;
                }
            }
        }
    }
    return result;
}


// ---------------------------------------------------------------------------------------------
// GPU pipeline setup (GL-free; the executor is penumbra/gl/pipelines/sample_based_soft.hpp).

using SbsParams = shared::PenumbraSbsParams;
static_assert(sizeof(SbsParams) == 7 * 32 + 4 * 16 + 48, "std140 layout the shaders assume: 7 dvec4, 4 uvec4, the LUT block");
static_assert(offsetof(SbsParams, grid) == 224 && offsetof(SbsParams, lut) == 288, "PenumbraSbsParams offsets");

/// How gl::SampleBasedSoftShadows finds the (caster triangle, light texel) pairs.
enum class SoftLightPass {
    /// Your DrawCasters callback draws the casters; a geometry stage emits each influence region
    /// (small ones go to the coverage pass), the rasteriser finds its texels. Needs geometry
    /// shaders; every option and skip.
    Raster,
    /// The casters are buffers (CasterBuffer); compute passes only, no draw call, query, stencil or
    /// framebuffer: one invocation per triangle builds what the geometry stage does
    /// (light_pass_setup.comp.glsl), the coverage pass visits every region's texels. The same
    /// bits as Raster in Exact and Brute (the counters differ by the coverage pass's boundary
    /// texels). Needs deferred_pairs > 0; not yet skips.silhouettes (its pass draws adjacency).
    Compute
};

/// Options of gl::SampleBasedSoftShadows (value-initialised = defaults; the grid size must be set).
struct SampleBasedSoftGpuOptions {
    SoftMode mode = SoftMode::Exact;
    /// Raster: run() with a DrawCasters callback; Compute: run() with CasterBuffer ranges.
    SoftLightPass light_pass = SoftLightPass::Raster;
    uint32_t grid_width = 0, grid_height = 0;  ///< light grid (sample lists and influence regions)
    /// View samples one fragment walks per pass (sintorn2008 §3.1's blocks). Keep
    /// list_block * N (brute / unproven pairs) below llvmpipe's 65 535 loop iterations per invocation.
    uint32_t list_block = 16;
    uint32_t max_list_blocks = 64;  ///< passes at most (decided on the GPU); samples beyond are untested
    /// The oracle's tolerances the exact test reproduces (coplanar rule 2; tie_epsilon only widens
    /// the proof margins): compare with reference::VisibilityOracle built with the same options.
    reference::VisibilityOptions oracle{};
    /// E of the oracle's tolerance scale (> 0): the largest side of the scene's bounding box, as
    /// VisibilityOracle::sceneExtent(). +inf = the uncapped rule: lights ~1e3 scene sizes away then
    /// lose their shadows (issue 41).
    double scene_extent = std::numeric_limits<double>::infinity();
    /// Fraction of the LUT's tolerance a plane's rounding may use before the plane counts as
    /// unproven (all-uncertain). The CPU twin uses 0.5; the GPU looks planes up in float after the
    /// fp64 construction, and the rounding to float (<= 3 * 2^-24 in d and in the normal) takes
    /// the other quarter: 0.25 leaves it.
    double plane_budget = 0.25;
    /// Rotation steps about the light's local z, picked per view sample by its selection word
    /// (SampleBasedSoftOptions::rotations; 1 = none).
    uint32_t rotations = 1;
    /// Work skips (each leaves Exact's and Brute's masks unchanged): SoftSkips. closed_casters acts
    /// on the draws of CasterClass::Closed only.
    SoftSkips skips{};
    bool count_work = true;  ///< work counters (atomics in the light pass)
    /// Deferred pairs: capacity, in (caster triangle, view sample) pairs, of a buffer the light
    /// pass's fragment stage appends its pairs to instead of working them (one per view sample of
    /// the fragment's list block that SoftSkips::wedges keeps); a compute pass then does the same work with one pair per
    /// invocation (light_pass.comp.glsl), densely packed, after the light pass's draws (and again
    /// after the closed casters' second pass); the pairs that need the LUT's tables go on to a
    /// tables pass (light_pass_tables.comp.glsl). Fragments whose pairs do not fit go whole to
    /// deferred_fragments; draws that overflow that too, or need more triangle slots than
    /// deferred_triangles, are drawn again with the fragment-stage program instead (decided on
    /// the GPU; SampleBasedSoftFrame::deferral_fallbacks counts them): every capacity gives the
    /// same bits and counters. 12 bytes per pair (8 in the pairs buffer, 4 in
    /// the tables pass's; default 2^20: 12 MiB); 0 = off, every pair in the fragment stage (no
    /// compute pass, one program fewer). Why:
    /// fragments run in 2 x 2 quads and rasteriser tiles, partly idle at the influence regions'
    /// edges; llvmpipe runs a fragment shader's every instruction for its masked-off lanes too;
    /// and some GPUs shade fragments far slower than they run compute (an H200's fragment
    /// arithmetic measured ~30x slower). On llvmpipe the soft pass ran 2.3-2.7x faster with every
    /// skip on (BM_SoftSkips: all_fragment against all).
    uint32_t deferred_pairs = 1u << 20;
    /// Triangle slots for deferred pairs (one per caster triangle, list block and caster class drawn
    /// that emits an influence region; 112 bytes each: the vertices, the draw, SoftSkips::wedges'
    /// planes; at most 2^24). 0: deferred_pairs / 4 (28 MiB by default). SoftLightPass::Compute:
    /// one region record per slot too (4 (2 + 2 (3k + 5)) bytes: 192 for k = 6), the triangles the
    /// host dispatches between two runs of the deferred passes; 0: 2^17 (14 + 24 MiB at k = 6).
    uint32_t deferred_triangles = 0;
    /// Deferred pairs: fragments whose pairs do not fit the pairs buffer (8 bytes each). They are
    /// appended whole, (triangle slot, texel), and worked by the compute pass's per-fragment
    /// program, one fragment's list block per invocation (slower per pair, as a group of lanes
    /// waits for its longest block and runs the tables in every pair's place, but no redraw);
    /// only draws that overflow this too are drawn again with the fragment-stage program. 0:
    /// deferred_pairs / 2 (4 MiB by default).
    uint32_t deferred_fragments = 0;
    /// Exact tests of deferred pairs: pending mask words (16 bytes each) the compute passes hand to
    /// an exact-test pass with one invocation per word (light_pass_tests.comp.glsl), instead of
    /// testing them in the pair's own loop, where a pair's lanes wait for the one with the most
    /// uncertain bits; words past the capacity are tested in the pair's loop (same bits). 0:
    /// deferred_pairs / 4 (4 MiB by default).
    uint32_t deferred_tests = 0;
    /// SoftLightPass::Compute: windows, in [0, 64], default 32. A run of the deferred passes whose
    /// pairs overflow the pairs and fragments buffers is split on the GPU into as many windows as
    /// the fragments asked for fill the fragments buffer, plus one, at most this many: window k
    /// works the run's records r with r % windows == k, at the pairs' speed (radius x16, 128 x 96:
    /// 19 windows, 393 ns per pair against 4 070 worked inline). Only a window that overflows too
    /// is worked by the coverage pass's inline program (SampleBasedSoftFrame::deferral_fallbacks),
    /// as is an overflow in a run of list blocks past the first only. Windows follow each run that
    /// holds list block 0 and could overflow (its records times the view samples past
    /// deferred_pairs), as many as it could need; each is the deferred passes' 14 dispatches,
    /// empty (no groups) unless its run split: on llvmpipe 32 idle windows cost ~5 % of the bench
    /// frame. 0: none.
    uint32_t overflow_windows = 32;
    /// Deferred pairs: influence regions whose bounding box spans at most this many texels are
    /// not drawn; the geometry stage hands them, as records (the triangle's slot and its polygon),
    /// to a coverage pass (light_pass_coverage.comp.glsl) that visits their texels in a loop and
    /// appends the same pairs the fragment stage would. The texels it visits are every texel GL's
    /// rule rasterizes and a few more on the boundary (within 1/64 pixel): Exact and Brute keep
    /// every bit; a visited texel's pairs are worked, so `fragments` and the pair counters may
    /// grow slightly, and Lut's pairs there may add bits of its approximation. Larger regions, and
    /// those past deferred_regions, are drawn. Why: llvmpipe's setup and rasterisation of the
    /// strips took ~18 of a frame's ~45 ms. 0 = off (every region drawn); at most 2^20.
    uint32_t coverage_texels = 4096;
    /// Records for coverage_texels (4 (2 + 2 (3k + 5)) bytes each: 192 for k = 6). 0: the smaller
    /// of the triangle slots and 2^16 (12 MiB at k = 6).
    uint32_t deferred_regions = 0;
    /// Per-stage GPU times (GL_TIME_ELAPSED around the list build, the predicate + light pass and
    /// the resolve), read by readFrame(). Off: no query calls per frame.
    bool timings = false;
};

inline void validateSampleBasedSoftGpuOptions(const SampleBasedSoftGpuOptions& o) {
    PENUMBRA_CHECK(o.mode == SoftMode::Exact || o.mode == SoftMode::Lut || o.mode == SoftMode::Brute,
                   "penumbra::SampleBasedSoftShadows: unknown mode ", static_cast<uint32_t>(o.mode));
    PENUMBRA_CHECK(o.grid_width >= 1 && o.grid_width <= 8192 && o.grid_height >= 1 && o.grid_height <= 8192,
                   "penumbra::SampleBasedSoftShadows: grid ", o.grid_width, " x ", o.grid_height, " must be 1 .. 8192 per side");
    PENUMBRA_CHECK(o.list_block >= 1 && o.list_block <= 4096, "penumbra::SampleBasedSoftShadows: list_block = ", o.list_block,
                   " must be in [1, 4096]");
    PENUMBRA_CHECK(o.max_list_blocks >= 1 && o.max_list_blocks <= 4096, "penumbra::SampleBasedSoftShadows: max_list_blocks = ",
                   o.max_list_blocks, " must be in [1, 4096]");
    PENUMBRA_CHECK(o.oracle.coplanar_epsilon >= 0.0 && o.oracle.coplanar_epsilon <= 0.1 && o.oracle.tie_epsilon >= 0.0 &&
                       o.oracle.tie_epsilon <= 0.1,
                   "penumbra::SampleBasedSoftShadows: oracle epsilons must be in [0, 0.1]");
    PENUMBRA_CHECK(o.scene_extent > 0.0,  // NaN fails too; +inf is the uncapped rule
                   "penumbra::SampleBasedSoftShadows: scene_extent ", o.scene_extent, " must be > 0 (or +inf)");
    PENUMBRA_CHECK(o.plane_budget > 0.0 && o.plane_budget <= 0.5, "penumbra::SampleBasedSoftShadows: plane_budget = ",
                   o.plane_budget, " must be in (0, 0.5]");
    PENUMBRA_CHECK(o.rotations >= 1 && o.rotations <= 256, "penumbra::SampleBasedSoftShadows: rotations = ", o.rotations,
                   " must be in [1, 256]");
    // The pairs' group count must fit one dispatch (GL's minimum 65 535 groups of 64).
    PENUMBRA_CHECK(o.deferred_pairs <= 65535u * 256u, "penumbra::SampleBasedSoftShadows: deferred_pairs = ", o.deferred_pairs,
                   " must be at most 16776960 (one dispatch of 65 535 groups of 256)");
    PENUMBRA_CHECK(o.deferred_triangles <= (1u << 24), "penumbra::SampleBasedSoftShadows: deferred_triangles = ",
                   o.deferred_triangles, " must be at most 16777216");
    PENUMBRA_CHECK(o.deferred_fragments <= 65535u * 256u, "penumbra::SampleBasedSoftShadows: deferred_fragments = ",
                   o.deferred_fragments, " must be at most 16776960 (one dispatch of 65 535 groups of 256)");
    PENUMBRA_CHECK(o.deferred_tests <= 65535u * 256u, "penumbra::SampleBasedSoftShadows: deferred_tests = ", o.deferred_tests,
                   " must be at most 16776960 (one dispatch of 65 535 groups of 256)");
    PENUMBRA_CHECK(o.overflow_windows <= 64u, "penumbra::SampleBasedSoftShadows: overflow_windows = ", o.overflow_windows,
                   " must be at most 64");
    PENUMBRA_CHECK(o.coverage_texels <= (1u << 20), "penumbra::SampleBasedSoftShadows: coverage_texels = ", o.coverage_texels,
                   " must be at most 1048576");
    PENUMBRA_CHECK(o.light_pass == SoftLightPass::Raster || o.light_pass == SoftLightPass::Compute,
                   "penumbra::SampleBasedSoftShadows: unknown light_pass ", static_cast<uint32_t>(o.light_pass));
    PENUMBRA_CHECK(o.light_pass != SoftLightPass::Compute || o.deferred_pairs > 0,
                   "penumbra::SampleBasedSoftShadows: light_pass = Compute needs deferred_pairs > 0 (its pairs are deferred)");
    PENUMBRA_CHECK(o.light_pass != SoftLightPass::Compute || !o.skips.silhouettes,
                   "penumbra::SampleBasedSoftShadows: light_pass = Compute does not take skips.silhouettes yet (the "
                   "silhouette pass draws adjacency); use light_pass = Raster for it");
    PENUMBRA_CHECK(o.deferred_regions <= 65535u * 64u, "penumbra::SampleBasedSoftShadows: deferred_regions = ", o.deferred_regions,
                   " must be at most 4194240 (one dispatch of 65 535 groups of 64)");
}

/// The light-pass parameter block for list block `block` and one caster class (the host fills one
/// slot per block and class; `closed`: the draw's casters are CasterClass::Closed; `culled_pass`:
/// the second pass over them, SoftSkips::closed_casters' culled triangles for near samples). `lut` may be
/// null in Brute mode. Throws penumbra::Error when the LUT does not fit the sets.
inline SbsParams sampleBasedSoftParams(const SampleBasedSoftGpuOptions& o, const LightSampleSets& sets,
                                       const LightLutSetup* lut, uint32_t sample_count, uint32_t block, bool has_sets,
                                       bool closed = false, bool culled_pass = false) {
    const uint32_t n = sets.count(), k = sets.sets();
    if (o.mode != SoftMode::Brute) {
        PENUMBRA_CHECK(lut != nullptr, "penumbra::SampleBasedSoftShadows: mode ", softModeName(o.mode), " needs a LUT");
        PENUMBRA_CHECK(lut->params.samples_per_set == n && lut->params.sets == k, "penumbra::SampleBasedSoftShadows: the LUT was built for ",
                       lut->params.sets, " sets of ", lut->params.samples_per_set, " samples, the light has ", k, " of ", n);
        PENUMBRA_CHECK(o.mode != SoftMode::Exact || lut->options.certified,
                       "penumbra::SampleBasedSoftShadows: mode exact needs a certified LUT (LightLutOptions::certified)");
    }
    const LightFrame& f = sets.frame;
    SbsParams p{};
    p.center = glm::dvec4(f.center, o.scene_extent);  // w: the oracle's E
    for (int i = 0; i < 3; ++i) p.rotation[i] = glm::dvec4(f.rotation[i], 0.0);
    const double min_scale = std::min(f.scale.x, std::min(f.scale.y, f.scale.z));
    const double max_scale = std::max(f.scale.x, std::max(f.scale.y, f.scale.z));
    p.scale = glm::dvec4(f.scale, min_scale);
    const double light_reach = max_scale * std::sqrt(3.0);
    const double budget = (lut ? lut->options.tolerance : 0.0) * o.plane_budget;
    p.bounds = glm::dvec4(light_reach, detail::oracle::length3(f.center) + light_reach, budget, budget * min_scale);
    // w: the wedges' sphere, the light shape's bound here (holds every sample); the pipeline
    // tightens it to its sample table's sampleBasedSoftSampleReach.
    const double eps = std::max(o.oracle.coplanar_epsilon, o.oracle.tie_epsilon);
    p.epsilon = glm::dvec4(o.oracle.coplanar_epsilon, o.oracle.tie_epsilon, eps, light_reach);
    p.grid = glm::uvec4(o.grid_width, o.grid_height, o.list_block, block);
    p.config = glm::uvec4(static_cast<uint32_t>(o.mode), n, k, (n + 31) / 32);
    p.counts = glm::uvec4(sample_count, o.max_list_blocks * o.list_block, lut ? lut->params.tables_per_set : (n + 127) / 128,
                          has_sets ? 1u : 0u);
    PENUMBRA_CHECK(o.rotations == 1 || f.symmetric, "penumbra::SampleBasedSoftShadows: rotations = ", o.rotations,
                   " needs a light symmetric about its local z axis (sphere, disk, ellipsoid with equal x and y)");
    const uint32_t flags = (o.skips.empty_blocks ? PENUMBRA_SBS_FLAG_SKIP_EMPTY : 0u) |
                           (o.skips.closed_casters && closed ? PENUMBRA_SBS_FLAG_CULL_CLOSED : 0u) |
                           (o.skips.plane_cut ? PENUMBRA_SBS_FLAG_PLANE_CUT : 0u) |
                           (o.skips.silhouettes ? PENUMBRA_SBS_FLAG_SILHOUETTES : 0u) |
                           (o.skips.closed_casters && closed && culled_pass ? PENUMBRA_SBS_FLAG_CULLED_PASS : 0u);
    float mu2 = detail::soft::wedgeMu2(eps);
    uint32_t mu2_bits = 0;
    std::memcpy(&mu2_bits, &mu2, sizeof mu2_bits);
    p.reserved = glm::uvec4(o.rotations, flags, mu2_bits, 0u);
    if (lut) p.lut = lut->params;
    return p;
}

/// The smallest certified-LUT tolerance (LightLutOptions::tolerance) at which Exact can vouch for
/// certain bits of a (view sample, caster) pair instead of testing every light sample, for
/// receivers and casters inside the box [lo, hi] (world). Exact trusts the LUT for a pair only
/// when the LUT's margin in world units, tolerance * plane_budget * (smallest semi-axis), exceeds
/// the oracle's reach at the light samples, 2 * tie_epsilon * s, s = the pair's largest
/// |x - p|_inf over the caster's vertices and the light (bounded here by the box's extent and its
/// farthest corner from the light centre plus the light's reach). (Casters the light comes within
/// the coplanar reach of need 2 * max(coplanar, tie) * s: those pairs are decided sample by
/// sample unless the tolerance covers that too; not counted here.) With the oracle's default
/// tie_epsilon 1e-9 the LUT's default 1e-6 suffices for scenes up to ~10^2 light radii across; a
/// larger tolerance widens every lookup's uncertain band by that much (cell coordinates, next to
/// the cells' half width 1/R): use this value, not more. Never below 1e-6. Throws for a
/// non-finite box. The tie reach here is uncapped by scene_extent, as Exact's check is (rounding
/// follows |s - p|_inf): far lights need this tolerance or take pairs sample by sample.
inline double sampleBasedSoftLutTolerance(const SampleBasedSoftGpuOptions& o, const LightFrame& frame,
                                          const glm::dvec3& lo, const glm::dvec3& hi) {
    validateSampleBasedSoftGpuOptions(o);
    PENUMBRA_CHECK(std::isfinite(lo.x) && std::isfinite(lo.y) && std::isfinite(lo.z) && std::isfinite(hi.x) &&
                       std::isfinite(hi.y) && std::isfinite(hi.z) && lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z,
                   "penumbra::sampleBasedSoftLutTolerance: the box (", lo.x, ", ", lo.y, ", ", lo.z, ") .. (", hi.x, ", ",
                   hi.y, ", ", hi.z, ") must be finite and ordered");
    const double min_scale = std::min(frame.scale.x, std::min(frame.scale.y, frame.scale.z));
    const double max_scale = std::max(frame.scale.x, std::max(frame.scale.y, frame.scale.z));
    const glm::dvec3 extent = hi - lo;
    const glm::dvec3 far_corner = glm::max(glm::abs(frame.center - lo), glm::abs(frame.center - hi));
    const double reach_scale = std::max(detail::soft::maxAbs3(extent), detail::soft::maxAbs3(far_corner) + max_scale * std::sqrt(3.0));
    const double needed = 2.0 * o.oracle.tie_epsilon * reach_scale / (o.plane_budget * min_scale);
    return std::max(1e-6, 1.25 * needed);  // 25 % above the bound: the per-pair check is strict
}


}  // namespace penumbra

#endif
