// penumbra — sample-based soft shadows, light pass: the work of one (caster triangle, light texel
// its influence region covers) pair (sintorn2008 §4, Fig. 6), shared by the fragment stage
// (light_pass.frag.glsl) and the compute pass of deferred pairs (light_pass.comp.glsl): walk one
// block of the texel's list of view samples; per view sample p the light samples the triangle T
// blocks are those behind T's three edge planes through p and beyond T's supporting plane. GLSL twin of the
// per-pair work of penumbra::sampleBasedSoftCpu (include/penumbra/pipelines/sample_based_soft.hpp),
// step for step:
//   - the planes are built in fp64 from the float inputs (the twin's arithmetic, `precise`),
//     oriented by det = (v0 - p) . ((v1 - p) x (v2 - p)), mapped to the light's normalised space
//     (penumbraSbsPlaneToLocal: LightFrame::planeToLocal with the frame from the parameter block),
//     then rounded to float for the LUT lookup (penumbra/light_lut/lookup.glsl);
//   - Lut: the AND of the four centre masks (penumbraLutCentreCell; each plane's cell located once
//     per pair for all of the set's tables), OR-ed into the sample's mask;
//   - Exact: certified lookups combined with penumbraLutCombine; a plane whose rounding bound
//     exceeds the budget (params.bounds.z, a quarter of the LUT's tolerance by default: the float
//     rounding of the plane takes another quarter) is all-uncertain; pairs within the oracle's
//     coplanar/tie reach or with an unprovable det are decided sample by sample. Uncertain light
//     samples are decided by the pair's own world planes where their side is proven with the
//     LUT's separation (penumbraSbsSideVerdict: nearly all), the rest by the hard pipeline's exact
//     fp64 test (penumbra/alias_free_hard/blocker_test.glsl, penumbraAfhBlocks with that sample as
//     the point light: the oracle's verdict on every pair it does not call a tie, coplanar rule
//     with the oracle's epsilon);
//   - Brute: every light sample by that exact test.
// Result: atomicOr into masks[id * words + s / 32] (bit s % 32: light sample s of the view
// sample's set blocked).
// Defines: PENUMBRA_SBS_MODE (the pipeline's SoftMode, fixed when it is built: the other modes'
// code is compiled out), PENUMBRA_SBS_COUNT_WORK, PENUMBRA_SBS_SILHOUETTES, PENUMBRA_SBS_CLOSED_CASTERS.
// Cost model: SIMD drivers run every branch some lane of a group takes; llvmpipe (Mesa 22) runs
// every `if` under a lane mask without branching and every loop body at least once per group, so
// each pair has one exact-test site (the pending words below), not one per table and word.
#ifndef PENUMBRA_SBS_LIGHT_PASS_WORK_GLSL
#define PENUMBRA_SBS_LIGHT_PASS_WORK_GLSL
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/sample_based_soft/sample_based_soft_shared.h"

#ifndef PENUMBRA_SBS_COUNT_WORK
#define PENUMBRA_SBS_COUNT_WORK 1
#endif
#ifndef PENUMBRA_SBS_MODE
#define PENUMBRA_SBS_MODE PENUMBRA_SBS_MODE_EXACT_ID  // PENUMBRA_SBS_MODE_*_ID: the parameter block's config.x
#endif
#ifndef PENUMBRA_SBS_SILHOUETTES
#define PENUMBRA_SBS_SILHOUETTES 0  // 1: SoftSkips::silhouettes (the marks buffer is bound)
#endif
#ifndef PENUMBRA_SBS_CLOSED_CASTERS
#define PENUMBRA_SBS_CLOSED_CASTERS 0  // 1: SoftSkips::closed_casters (the near buffer is bound)
#endif
#ifndef PENUMBRA_SBS_STAGE
// 0: the whole pair (the fragment-stage program); deferred pairs: 1 the pairs' compute pass
// (light_pass.comp.glsl), which hands each pair that needs the LUT's tables to 2, the tables pass
// (light_pass_tables.comp.glsl), except with PENUMBRA_SBS_PER_FRAGMENT (a fragment's whole block
// per invocation: the tables too); all hand their pending exact-test words to the exact-test pass.
#define PENUMBRA_SBS_STAGE 0
#endif
#define PENUMBRA_SBS_DEFER_TESTS (PENUMBRA_SBS_STAGE != 0)
#ifndef PENUMBRA_SBS_PER_FRAGMENT
#define PENUMBRA_SBS_PER_FRAGMENT 0  // 1: stage 1 walks a whole fragment's block, the tables included
#endif
#define PENUMBRA_SBS_TABLES_HANDED_ON (PENUMBRA_SBS_STAGE == 1 && !PENUMBRA_SBS_PER_FRAGMENT)

layout(std140, binding = PENUMBRA_SBS_PARAMS_BINDING) uniform PenumbraSbsParamsBlock {
    PenumbraSbsParams penumbraSbsParams;
};
layout(std430, binding = PENUMBRA_SBS_COUNTS_BINDING) readonly buffer PenumbraSbsCounts { uint penumbraSbsCounts[]; };
layout(std430, binding = PENUMBRA_SBS_OFFSETS_BINDING) readonly buffer PenumbraSbsOffsets { uint penumbraSbsOffsets[]; };
layout(std430, binding = PENUMBRA_SBS_POSITIONS_BINDING) readonly buffer PenumbraSbsPositions { vec4 penumbraSbsPositions[]; };
layout(std430, binding = PENUMBRA_SBS_IDS_BINDING) readonly buffer PenumbraSbsIds { uint penumbraSbsIds[]; };
layout(std430, binding = PENUMBRA_SBS_MASKS_BINDING) buffer PenumbraSbsMasks { uint penumbraSbsMasks[]; };
layout(std430, binding = PENUMBRA_SBS_LUT_BINDING) readonly buffer PenumbraSbsLut { uvec4 penumbraSbsLut[]; };
layout(std430, binding = PENUMBRA_SBS_SAMPLES_BINDING) readonly buffer PenumbraSbsSamples { dvec4 penumbraSbsSamples[]; };
layout(std430, binding = PENUMBRA_SBS_SETS_BINDING) readonly buffer PenumbraSbsSets { uint penumbraSbsSets[]; };
#if PENUMBRA_SBS_SILHOUETTES
layout(std430, binding = PENUMBRA_SBS_MARKS_BINDING) readonly buffer PenumbraSbsMarks { uint penumbraSbsMarks[]; };
#endif
#if PENUMBRA_SBS_CLOSED_CASTERS
layout(std430, binding = PENUMBRA_SBS_NEAR_BINDING) buffer PenumbraSbsNear { uint penumbraSbsNear[]; };
#endif
#if PENUMBRA_SBS_COUNT_WORK
layout(std430, binding = PENUMBRA_SBS_WORK_BINDING) buffer PenumbraSbsWork { uint penumbraSbsWork[]; };
#endif
#if PENUMBRA_SBS_DEFER_TESTS
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
// (list slot, triangle slot, mask word, its bits): one pending word per entry.
layout(std430, binding = PENUMBRA_SBS_TESTS_BINDING) writeonly buffer PenumbraSbsTests { uvec4 penumbraSbsTests[]; };
uint penumbraSbsTestTriangle = 0u;  // the triangle slot of the pair being worked (the compute passes set it)
#endif
#if PENUMBRA_SBS_STAGE == 1
// Set by the compute pass: 1 in the per-fragment program (the fragment is counted with its block),
// 0 in the pairs' (the fragment stage counted the fragment when it appended its pairs).
uint penumbraSbsFragmentPairs = 0u;
#endif
#if PENUMBRA_SBS_TABLES_HANDED_ON
uint penumbraSbsPairIndex = 0u;  // the pair's index in the pairs buffer (the compute pass sets it)
// The pairs that need the LUT's tables, by index in the pairs buffer: as long as that buffer, so
// never full (each pair adds at most one).
layout(std430, binding = PENUMBRA_SBS_TABLE_PAIRS_BINDING) writeonly buffer PenumbraSbsTableWork { uint penumbraSbsTableWork[]; };
#endif

#define PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) penumbraSbsCounts[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) penumbraSbsOffsets[list]
#define PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) penumbraSbsPositions[slot]
#define PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) penumbraSbsIds[slot]
#define PENUMBRA_SAMPLE_LISTS_GRID_WIDTH penumbraSbsParams.grid.x
#include "penumbra/sample_lists/sample_lists.glsl"

#define PENUMBRA_LUT_PARAMS penumbraSbsParams.lut
#define PENUMBRA_LUT_LOAD(index) penumbraSbsLut[index]
// The local samples are not bound: the pipeline decides uncertain bits with the exact segment
// test on the world samples, never with penumbraLutResolve / penumbraExactBehind.
#define PENUMBRA_LUT_SAMPLE(table, bit) vec3(0.0)
#include "penumbra/light_lut/lookup.glsl"

#define PENUMBRA_AFH_EXACT 1
#include "penumbra/alias_free_hard/blocker_test.glsl"

#include "penumbra/sample_based_soft/caster_plane.glsl"
#include "penumbra/sample_based_soft/wedges.glsl"
#ifndef PENUMBRA_SBS_WEDGES
#define PENUMBRA_SBS_WEDGES 0
#endif
// SoftSkips::wedges: the pairs the last penumbraSbsTexelWork skipped by T's wedge planes.
uint penumbraSbsWedged;
// Planes that never reject (the pairs' passes: their pairs were tested in the fragment stage).
PenumbraSbsWedges penumbraSbsNoWedges() {
    const vec4 none = vec4(0.0, 0.0, 0.0, 1.0);
    return PenumbraSbsWedges(vec4[4](none, none, none, none), vec2(0.0));
}

// LightFrame::planeToLocal: world plane dot(n, x) + w = 0 -> unit local normal and offset (the
// signed distance of the light centre in normalised units). Zero normal -> 0 (nothing behind).
dvec4 penumbraSbsPlaneToLocal(dvec4 plane) {
    const dvec3 n = plane.xyz;
    const double m = penumbraSbsMaxAbs(n);
    if (!(m > 0.0LF)) return dvec4(0.0LF);
    precise dvec3 nm = n / m;
    precise double w = plane.w / m;
    const PenumbraSbsParams P = penumbraSbsParams;
    precise dvec3 local_n = dvec3(P.scale.x * penumbraSbsDot(P.rotation[0].xyz, nm), P.scale.y * penumbraSbsDot(P.rotation[1].xyz, nm),
                                  P.scale.z * penumbraSbsDot(P.rotation[2].xyz, nm));
    precise double local_w = penumbraSbsDot(nm, P.center.xyz) + w;
    precise double len = penumbraSbsLength(local_n);
    return dvec4(local_n / len, local_w / len);
}

// detail::soft::localPlane: the plane through `origin` spanned by a and b, flipped by `flip`, in
// the light's normalised space (rounded to float for the lookup), and whether its rounding bound
// (float inputs, fp64 arithmetic, the change of frame; normalised units) fits the budget.
struct PenumbraSbsPlane {
    dvec4 plane;  // rounded to float at the lookup (after the rotation step, if any)
    bool proven;
};
PenumbraSbsPlane penumbraSbsLocalPlane(dvec3 origin, dvec3 a, dvec3 b, bool flip) {
    const PenumbraSbsParams P = penumbraSbsParams;
    PenumbraSbsPlane result = PenumbraSbsPlane(dvec4(0.0LF), false);
    dvec3 n = penumbraSbsCross(a, b);
    const double length = penumbraSbsLength(n);
    if (!(length > 0.0LF) || !(length < 1e300LF)) return result;
    if (flip) n = -n;
    precise double w = -penumbraSbsDot(n, origin);
    precise double dn = 8.0LF * kPenumbraSbsEpsilon * penumbraSbsLength(a) * penumbraSbsLength(b);
    precise double error = (dn + 4.0LF * kPenumbraSbsEpsilon * length) * (P.bounds.y + penumbraSbsLength(origin)) / length /
                           P.scale.w + 24.0LF * kPenumbraSbsEpsilon;
    result.plane = penumbraSbsPlaneToLocal(dvec4(n, w));
    result.proven = error <= P.bounds.z;
    return result;
}

// Exact: the LUT's uncertain bits decided by the pair's own planes in world space, before any
// exact test (detail::soft::sidePlane / sideVerdict, step for step). The plane through `origin`
// spanned by a and b (flipped by `flip`; behind: dot(n, x - origin) < 0, the local plane's side)
// and the threshold above which |dot(n, l - origin)| proves a light sample l farther than `margin`
// (world units) from the exact plane on the float inputs, on the computed value's side: the value is
// off by at most (dn + 4 eps |n|) |l - origin| (dn = 8 eps |a| |b| as in penumbraSbsLocalPlane,
// l - origin and the dot product rounded), |l - origin| <= |centre - origin| + light_reach and the
// exact normal's length <= |n| + dn; 1e-6 relative covers the bound's own rounding. A zero normal
// decides nothing (value 0).
struct PenumbraSbsSidePlane {
    dvec3 n;
    double threshold;
};
PenumbraSbsSidePlane penumbraSbsSidePlane(dvec3 origin, dvec3 a, dvec3 b, bool flip, const PenumbraSbsParams P, double margin) {
    dvec3 n = penumbraSbsCross(a, b);
    if (flip) n = -n;
    const double length = penumbraSbsLength(n);
    precise double dn = 8.0LF * kPenumbraSbsEpsilon * penumbraSbsLength(a) * penumbraSbsLength(b);
    precise double reach = (penumbraSbsLength(P.center.xyz - origin) + P.bounds.x) * (1.0LF + 1e-6LF);
    precise double threshold = ((dn + 4.0LF * kPenumbraSbsEpsilon * length) * reach + margin * (length + dn)) * (1.0LF + 1e-6LF);
    return PenumbraSbsSidePlane(n, threshold);
}
// A light sample l against T's three edge planes through p and T's plane through v0: -1 behind
// every one by the margin (T blocks it), 1 in front of one by the margin (T does not), 0 neither.
int penumbraSbsSideVerdict(dvec3 l, dvec3 p, dvec3 v0, PenumbraSbsSidePlane e0, PenumbraSbsSidePlane e1,
                           PenumbraSbsSidePlane e2, PenumbraSbsSidePlane t) {
    precise dvec3 dp = l - p;
    precise dvec3 d0 = l - v0;
    const double g0 = penumbraSbsDot(e0.n, dp), g1 = penumbraSbsDot(e1.n, dp), g2 = penumbraSbsDot(e2.n, dp),
                 g3 = penumbraSbsDot(t.n, d0);
    if (g0 > e0.threshold || g1 > e1.threshold || g2 > e2.threshold || g3 > t.threshold) return 1;
    if (g0 < -e0.threshold && g1 < -e1.threshold && g2 < -e2.threshold && g3 < -t.threshold) return -1;
    return 0;
}

// A view sample's light-sample set and rotation step from its selection word (set 0, unrotated when
// no per-sample buffer is bound; out of range: set 0 / unrotated, which the CPU twin rejects).
uvec2 penumbraSbsSelection(const PenumbraSbsParams P, uint id) {
    const uint word = P.counts.w != 0u ? penumbraSbsSets[id] : 0u;
    uint set = word & 0xFFu, turn_step = word >> 8;
    if (set >= P.config.z) set = 0u;
    if (turn_step >= P.reserved.x) turn_step = 0u;
    return uvec2(set, turn_step);
}

// The light samples of mask word w (of n): bits 32 w .. min(32 w + 31, n - 1).
uint penumbraSbsWordBits(uint w, uint n) { return 32u * w + 32u <= n ? 0xFFFFFFFFu : (1u << (n - 32u * w)) - 1u; }

// One table's four mask words OR-ed into a view sample's mask from word `base` on (only the
// `left` words the sample has from there), constant indices, no atomic for an empty word.
void penumbraSbsOrTable(uint base, uint left, uvec4 m) {
    if (m.x != 0u) atomicOr(penumbraSbsMasks[base], m.x);
    if (left > 1u && m.y != 0u) atomicOr(penumbraSbsMasks[base + 1u], m.y);
    if (left > 2u && m.z != 0u) atomicOr(penumbraSbsMasks[base + 2u], m.z);
    if (left > 3u && m.w != 0u) atomicOr(penumbraSbsMasks[base + 3u], m.w);
}

/// The work of one (caster triangle T = v0 v1 v2, light texel) pair: the texel's view samples
/// `range` (penumbraSampleListsBlock of P's list block), their masks OR-ed (see the top). P: the
/// draw's parameter block (the compute pass of deferred pairs restores its block index and flags,
/// the only fields in which the draws' blocks differ).
void penumbraSbsTexelWork(const PenumbraSbsParams P, const uvec2 texel, const uvec2 range, const dvec3 v0, const dvec3 v1,
                          const dvec3 v2, const PenumbraSbsWedges wedges) {
    const uint mode = uint(PENUMBRA_SBS_MODE), n = P.config.y, words = P.config.w, tables = P.counts.z;
    const bool exact = mode == PENUMBRA_SBS_MODE_EXACT;
    // SoftSkips::plane_cut: T's plane against the light, once per fragment.
    const bool plane_cut = (P.reserved.y & PENUMBRA_SBS_FLAG_PLANE_CUT) != 0u;
    const bool closed_first = (P.reserved.y & (PENUMBRA_SBS_FLAG_CULL_CLOSED | PENUMBRA_SBS_FLAG_CULLED_PASS)) ==
                              PENUMBRA_SBS_FLAG_CULL_CLOSED;
    PenumbraSbsCasterPlane caster;
    if (plane_cut || closed_first) caster = penumbraSbsCasterPlane(v0, v1, v2, P.center.xyz, P.bounds.x);
    // SoftSkips::silhouettes: outside every potential silhouette's influence region, no segment from
    // a view sample to a light point crosses a silhouette edge, so the light is all visible or all
    // blocked (laine2005 §3.3): T blocks every light sample when it blocks the centre, else none
    // counts (the union over the casters is then the centre's verdict, which is every sample's).
    bool hard_texel = false;
#if PENUMBRA_SBS_SILHOUETTES
    if ((P.reserved.y & PENUMBRA_SBS_FLAG_SILHOUETTES) != 0u)
        hard_texel = penumbraSbsMarks[texel.y * P.grid.x + texel.x] == 0u;
#endif
    // T's plane depends on T alone: built once per fragment, oriented per sample by negation (which
    // commutes exactly with every operation of penumbraSbsLocalPlane: the same bits as building it
    // flipped).
    const PenumbraSbsPlane support = penumbraSbsLocalPlane(v0, v1 - v0, v2 - v0, false);
    // ... and so does the squared distance from the light's centre to T (can a light sample come
    // within the oracle's coplanar reach of T?).
    const double light_distance2 = penumbraAfhPointTriangleDistance2(P.center.xyz, v0, v1, v2);
    // Distance from T's plane to the nearest light point (<= 0: the light may straddle it), with
    // the twin's rounding allowance: computed on the first pair that needs it (p in T's plane).
    double normal_length = -1.0LF;
    precise double light_gap = 0.0LF;
    uint pairs = 0u, ignored = 0u, unproven_pairs = 0u, uncertain_bits = 0u, tests = 0u, unproven_planes = 0u, cut = 0u,
         hard = 0u, recovered = 0u, front = 0u, wedged = 0u;
#if PENUMBRA_SBS_WEDGES
    const float wedge_mu2 = uintBitsToFloat(P.reserved.z);  // detail::soft::wedgeMu2
#endif
    // SoftSkips::closed_casters (the twin's two sweeps): the first pass over a closed draw flags the
    // samples within the oracle's coplanar reach of a kept triangle and not provably outside it (and
    // their texel, after the samples' flags); the second pass gives only those the culled triangles.
    const bool culled_pass = (P.reserved.y & PENUMBRA_SBS_FLAG_CULLED_PASS) != 0u;
    const uint texel_flag = P.counts.x + texel.y * P.grid.x + texel.x;
    for (uint slot = range.x; slot < range.x + range.y; ++slot) {
#if PENUMBRA_SBS_WEDGES
        // SoftSkips::wedges, first (a rejected sample is not near T either: see SoftSkips).
        if (penumbraSbsWedgeRejects(wedges, penumbraSampleListsPosition(slot).xyz, wedge_mu2)) {
            ++wedged;
            continue;
        }
#endif
        const dvec3 p = dvec3(penumbraSampleListsPosition(slot));
        const uint id = penumbraSampleListsId(slot);
        const uvec2 selection = penumbraSbsSelection(P, id);
        const uint set = selection.x, turn_step = selection.y;
        const uint mask_base = id * words, sample_base = (set * P.reserved.x + turn_step) * n;
#if PENUMBRA_SBS_CLOSED_CASTERS
        if (culled_pass) {
            if (penumbraSbsNear[id] == 0u) continue;
            ++recovered;
        }
#endif
        // The oracle's scale (rules 2/3) for this pair lies in [scale_lo, scale_hi] over the samples;
        // its segment term min(|s - p|_inf, E) (E = P.center.w) between the capped s_min and s_max
        // (min(., E) is monotone). s_far: uncapped, for the rounding term of margin_reach.
        const double scale_v = max(penumbraSbsMaxAbs(v0 - p), max(penumbraSbsMaxAbs(v1 - p), penumbraSbsMaxAbs(v2 - p)));
        const double centre_reach = penumbraSbsMaxAbs(P.center.xyz - p);
        const double s_far = centre_reach + P.bounds.x;
        const double s_min = min(max(0.0LF, centre_reach - P.bounds.x), P.center.w), s_max = min(s_far, P.center.w);
        const double scale_lo = max(scale_v, s_min), scale_hi = max(scale_v, s_max);
        double distance2 = -1.0LF;  // p to T, squared: computed once, where first needed
#if PENUMBRA_SBS_CLOSED_CASTERS
        if (closed_first) {
            distance2 = penumbraAfhPointTriangleDistance2(p, v0, v1, v2);
            precise double reach_c = P.epsilon.x * scale_hi;
            if (distance2 <= reach_c * reach_c * (1.0LF + 1e-9LF) && !penumbraSbsCasterPlaneOutside(caster, p)) {
                penumbraSbsNear[id] = 1u;
                penumbraSbsNear[texel_flag] = 1u;
            }
        }
#endif
        precise double cut_reach = 2.0LF * P.epsilon.z * scale_hi;
        if (plane_cut && penumbraSbsCasterPlaneCuts(caster, p, cut_reach)) {
            ++cut;  // SoftSkips::plane_cut: p and the whole light on one side of T's plane
            continue;
        }
        ++pairs;
        bool all_exact = mode == PENUMBRA_SBS_MODE_BRUTE;
        bool positive = false;  // det > 0: the planes' orientation
        PenumbraSbsPlane planes[4];
        if (hard_texel) {
            // SoftSkips::silhouettes: one exact test from the light centre, at the exact-test site
            // below. It shares that site rather than having its own branch: SIMD drivers that run
            // every branch under lane masks (llvmpipe) would pay for a separate test on every pair.
            ++hard;
        } else if (!all_exact) {
            if (distance2 < 0.0LF) distance2 = penumbraAfhPointTriangleDistance2(p, v0, v1, v2);
            precise double ignore = P.epsilon.x * scale_lo;
            if (distance2 < ignore * ignore * (1.0LF - 1e-9LF)) {  // the oracle ignores T for every sample
                ++ignored;
                continue;
            }
            precise double reach = 2.0LF * P.epsilon.z * scale_hi;
            // The LUT's margin must exceed the oracle's tie/rounding reach at the light samples (uncapped:
            // its rounding follows |s - p|_inf), and its coplanar reach where the light comes that close
            // to T (the CPU twin's rule).
            precise double light_near = 2.0LF * P.epsilon.x * scale_hi + P.bounds.x;
            const bool light_touches = light_distance2 <= light_near * light_near * (1.0LF + 1e-9LF);
            precise double tie_reach = P.epsilon.y * max(scale_v, s_far);
            precise double margin_reach = 2.0LF * max(light_touches ? P.epsilon.z * scale_hi : 0.0LF, tie_reach);
            const bool near = distance2 <= reach * reach * (1.0LF + 1e-9LF);
            all_exact = exact && (near || !(P.bounds.w > margin_reach));
            const dvec3 a = v0 - p, b = v1 - p, c = v2 - p;
            const double det = penumbraSbsDot(a, penumbraSbsCross(b, c));
            precise double det_bound = 16.0LF * kPenumbraSbsEpsilon * penumbraSbsLength(a) * penumbraSbsLength(b) * penumbraSbsLength(c);
            if (!(abs(det) > det_bound)) {
                if (normal_length < 0.0LF) {
                    const dvec3 normal = penumbraSbsCross(v1 - v0, v2 - v0);
                    normal_length = penumbraSbsLength(normal);
                    if (normal_length > 0.0LF)
                        light_gap = (abs(penumbraSbsDot(normal, P.center.xyz - v0)) / normal_length -
                                     4.0LF * kPenumbraSbsEpsilon * penumbraSbsLength(P.center.xyz - v0)) * (1.0LF - 1e-9LF) -
                                    P.bounds.x;
                }
                // p in T's plane up to rounding, the whole light on one side: T blocks nothing for p
                // (the twin's argument: the segment meets the plane within delta * L / gap of p,
                // outside T).
                precise double delta = (abs(det) + det_bound) / normal_length * (1.0LF + 1e-9LF);
                precise double reach_p = penumbraSbsLength(P.center.xyz - p) + P.bounds.x;
                precise double lhs = (delta * reach_p) * (delta * reach_p);
                precise double rhs = 0.25LF * light_gap * light_gap * distance2;
                if (!near && light_gap > 0.0LF && normal_length > 0.0LF && lhs <= rhs) {
                    ++ignored;
                    continue;
                }
                if (exact) all_exact = true;
            }
            positive = det > 0.0LF;
            planes[0] = penumbraSbsLocalPlane(p, a, b, positive);
            planes[1] = penumbraSbsLocalPlane(p, b, c, positive);
            planes[2] = penumbraSbsLocalPlane(p, c, a, positive);
            planes[3] = support;  // T's plane, p in front
            if (positive) planes[3].plane = -planes[3].plane;
            if (turn_step != 0u) {
                // Rotated samples are behind a plane when the LUT's (unrotated) ones are behind it
                // rotated back: penumbraLutRotate's arithmetic in fp64 (the twin's lightLutRotate).
                const dvec2 turn = penumbraSbsSamples[P.config.z * P.reserved.x * n + turn_step].xy;
                for (int i = 0; i < 4; ++i) {
                    const dvec4 q = planes[i].plane;
                    precise double x = turn.x * q.x + turn.y * q.y;
                    precise double y = turn.x * q.y - turn.y * q.x;
                    planes[i].plane = dvec4(x, y, q.z, q.w);
                }
            }
            if (all_exact) {
                ++unproven_pairs;
                uncertain_bits += n;
            }
        }
        // Exact/Brute: the words of the sample's mask with light samples left to the exact test
        // (an all-exact pair: every word, every sample).
        uint pending = hard_texel ? 1u : all_exact ? (words >= 32u ? 0xFFFFFFFFu : (1u << words) - 1u) : 0u;
        uvec4 undecided[PENUMBRA_SBS_MAX_WORDS / 4u];  // the uncertain bits of pending words, per table
#if PENUMBRA_SBS_MODE != PENUMBRA_SBS_MODE_BRUTE_ID
        if (!all_exact && !hard_texel) {
            // Each plane's LUT cell is the same in every table of the set: located once per pair,
            // not once per 128-sample block (N = 1024: 4 locations instead of 32).
            PenumbraLutCell cells[4];
            for (int i = 0; i < 4; ++i) cells[i] = penumbraLutLocate(P.lut, vec4(planes[i].plane));
            // The whole light in front of one plane (a trivial cell: no sample behind it, in every
            // table; in Exact that plane must be proven, else its cell is not trusted): T blocks
            // nothing for p. Every table would AND in a zero mask and leave no bit uncertain, so the
            // pair ends here, with the same bits, before 4 x tables lookups (the CPU twin likewise).
            if ((cells[0].trivial < 0 && (!exact || planes[0].proven)) || (cells[1].trivial < 0 && (!exact || planes[1].proven)) ||
                (cells[2].trivial < 0 && (!exact || planes[2].proven)) || (cells[3].trivial < 0 && (!exact || planes[3].proven))) {
                ++front;
                continue;
            }
#if PENUMBRA_SBS_TABLES_HANDED_ON
            // The tables in their own pass, densely packed: here a group of lanes would run them as
            // long as one of its pairs needs them (most end above), and llvmpipe would run them even
            // where none does: this pass holds no table loop at all.
            const uint entry = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SAMPLES], 1u);
            if (entry < uint(penumbraSbsTableWork.length())) penumbraSbsTableWork[entry] = penumbraSbsPairIndex;  // always
            continue;
#else
#if PENUMBRA_SBS_MODE == PENUMBRA_SBS_MODE_EXACT_ID
            // The planes that decide the LUT's uncertain bits (penumbraSbsSidePlane) with the LUT's
            // own separation, which this pair passed: P.bounds.w above the oracle's reach at the light.
            const PenumbraSbsSidePlane side0 = penumbraSbsSidePlane(p, v0 - p, v1 - p, positive, P, P.bounds.w);
            const PenumbraSbsSidePlane side1 = penumbraSbsSidePlane(p, v1 - p, v2 - p, positive, P, P.bounds.w);
            const PenumbraSbsSidePlane side2 = penumbraSbsSidePlane(p, v2 - p, v0 - p, positive, P, P.bounds.w);
            const PenumbraSbsSidePlane side3 = penumbraSbsSidePlane(v0, v1 - v0, v2 - v0, positive, P, P.bounds.w);
#endif
            for (uint block = 0u; block < tables; ++block) {
                const uint table = set * tables + block;
#if PENUMBRA_SBS_MODE == PENUMBRA_SBS_MODE_LUT_ID
                const uvec4 m = penumbraLutCentreCell(cells[0], table) & penumbraLutCentreCell(cells[1], table) &
                                penumbraLutCentreCell(cells[2], table) & penumbraLutCentreCell(cells[3], table);
                penumbraSbsOrTable(mask_base + block * 4u, words - block * 4u, m);
#else
                const uvec4 valid = penumbraLutValidMask(P.lut, table);
                // The four planes, unrolled (constant indices: no per-lane arrays on SIMD drivers).
                uvec4 u0 = valid, u1 = valid, u2 = valid, u3 = valid;
                uvec4 c0 = uvec4(0u), c1 = uvec4(0u), c2 = uvec4(0u), c3 = uvec4(0u);
                if (planes[0].proven) c0 = penumbraLutLookupCell(cells[0], table, u0) & ~u0;  // penumbraLutBehindCertified
                if (planes[1].proven) c1 = penumbraLutLookupCell(cells[1], table, u1) & ~u1;
                if (planes[2].proven) c2 = penumbraLutLookupCell(cells[2], table, u2) & ~u2;
                if (planes[3].proven) c3 = penumbraLutLookupCell(cells[3], table, u3) & ~u3;
                unproven_planes += (planes[0].proven ? 0u : 1u) + (planes[1].proven ? 0u : 1u) + (planes[2].proven ? 0u : 1u) +
                                   (planes[3].proven ? 0u : 1u);
                uvec4 certain = c0, uncertain = u0;
                penumbraLutCombine(certain, uncertain, c1, u1);
                penumbraLutCombine(certain, uncertain, c2, u2);
                penumbraLutCombine(certain, uncertain, c3, u3);
                uncertain &= valid;
                const uvec4 counts = uvec4(bitCount(uncertain));
                uncertain_bits += (counts.x + counts.y) + (counts.z + counts.w);
                // The uncertain bits the pair's planes decide (nearly all): no exact test for them.
                uvec4 left = uncertain;
                while (any(notEqual(left, uvec4(0u)))) {
                    const uint k = left.x != 0u ? 0u : left.y != 0u ? 1u : left.z != 0u ? 2u : 3u;
                    const uint word = left[k], bit = uint(findLSB(word));
                    left[k] = word & (word - 1u);
                    const int side = penumbraSbsSideVerdict(penumbraSbsSamples[sample_base + 128u * block + 32u * k + bit].xyz, p,
                                                            v0, side0, side1, side2, side3);
                    if (side != 0) uncertain[k] &= ~(1u << bit);
                    if (side < 0) certain[k] |= 1u << bit;
                }
                penumbraSbsOrTable(mask_base + block * 4u, words - block * 4u, certain);
                undecided[block] = uncertain;  // every bit certain (nearly always): nothing pending
                pending |= uint(uncertain.x != 0u) << (4u * block) | uint(uncertain.y != 0u) << (4u * block + 1u) |
                           uint(uncertain.z != 0u) << (4u * block + 2u) | uint(uncertain.w != 0u) << (4u * block + 3u);
#endif
            }
#endif
        }
#endif
#if PENUMBRA_SBS_DEFER_TESTS && PENUMBRA_SBS_MODE != PENUMBRA_SBS_MODE_LUT_ID
        // The compute pass of deferred pairs hands its pending words to the exact-test pass
        // (light_pass_tests.comp.glsl: one invocation per word, densely packed) when they fit its
        // buffer; else they stay pending for the loop below. A hard texel's one test stays here.
        if (pending != 0u && !hard_texel) {
            const uint count = uint(bitCount(pending));
            const uint first = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_TESTS], count);
            const uint capacity = uint(penumbraSbsTests.length());
            if (first + count <= capacity) {
                for (uint k = first; pending != 0u; ++k) {
                    const uint w = uint(findLSB(pending));
                    pending &= pending - 1u;
                    const uint bits = all_exact ? penumbraSbsWordBits(w, n) : undecided[w >> 2u][w & 3u];
                    tests += uint(bitCount(bits));
                    penumbraSbsTests[k] = uvec4(slot, penumbraSbsTestTriangle, w, bits);
                }
            } else {
                // Past the capacity: the entries below it that this request took get no bits.
                for (uint k = first; k < capacity; ++k) penumbraSbsTests[k] = uvec4(0u);
            }
        }
#endif
#if PENUMBRA_SBS_MODE != PENUMBRA_SBS_MODE_LUT_ID || PENUMBRA_SBS_SILHOUETTES
        // One exact-test site for every pending word: bit b of word w is light sample 32 w + b (a
        // hard texel's pair: word 0, bit 0, the light centre standing for every sample).
        uint w = 0u, bits = 0u, m = 0u;
        while (pending != 0u) {
            if (bits == 0u) {
                w = uint(findLSB(pending));
#if PENUMBRA_SBS_MODE == PENUMBRA_SBS_MODE_LUT_ID
                bits = 1u;  // Lut: only a hard texel's pair has a pending word
#else
                bits = hard_texel ? 1u : all_exact ? penumbraSbsWordBits(w, n) : undecided[w >> 2u][w & 3u];
#endif
                m = 0u;
            }
            const uint bit = uint(findLSB(bits));
            bits &= bits - 1u;
            ++tests;
            const dvec3 l = hard_texel ? P.center.xyz : penumbraSbsSamples[sample_base + 32u * w + bit].xyz;
            if (penumbraAfhBlocks(v0, v1, v2, p, l, P.epsilon.x, 0.0LF, P.center.w)) m |= 1u << bit;  // w: E
            if (bits == 0u) {
                if (m != 0u && !hard_texel) atomicOr(penumbraSbsMasks[mask_base + w], m);
                pending &= ~(1u << w);
            }
        }
#if PENUMBRA_SBS_SILHOUETTES
        // A hard texel's pair where T blocks the centre: every light sample shares the centre's
        // verdict there (some caster blocks each), so T sets them all.
        if (hard_texel && m != 0u)
            for (uint k = 0u; k < words; ++k) atomicOr(penumbraSbsMasks[mask_base + k], penumbraSbsWordBits(k, n));
#endif
#endif
    }
#if PENUMBRA_SBS_COUNT_WORK
#if PENUMBRA_SBS_STAGE == 2
    // The tables pass counts what it adds: uncertain bits, unproven planes, exact tests. The pair's
    // compute pass counted the fragment and the pair (it ran the same steps up to the tables).
    pairs = ignored = unproven_pairs = cut = hard = recovered = front = wedged = 0u;
#elif PENUMBRA_SBS_STAGE == 1
    // The pairs' compute pass works one sample of a fragment's block per invocation: the fragment
    // is counted with its first.
    if (penumbraSbsFragmentPairs != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_FRAGMENTS], 1u);
#else
    atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_FRAGMENTS], 1u);
#endif
    if (pairs != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS], pairs);
    if (ignored != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_IGNORED], ignored);
    if (unproven_pairs != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_UNPROVEN], unproven_pairs);
    if (uncertain_bits != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_UNCERTAIN_BITS], uncertain_bits);
    if (tests != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_EXACT_TESTS], tests);
    if (unproven_planes != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PLANES_UNPROVEN], unproven_planes);
    if (cut != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_CUT], cut);
    if (hard != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_HARD], hard);
    if (recovered != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_RECOVERED], recovered);
    if (front != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_FRONT], front);
    if (wedged != 0u) atomicAdd(penumbraSbsWork[PENUMBRA_SBS_WORK_PAIRS_WEDGED], wedged);
#endif
    penumbraSbsWedged = wedged;
}
#endif
