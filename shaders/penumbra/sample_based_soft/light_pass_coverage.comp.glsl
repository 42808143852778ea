// penumbra — sample-based soft shadows, deferred pairs, the coverage pass
// (SampleBasedSoftGpuOptions::coverage_texels): the light pass's geometry stage (light_pass.geom.glsl)
// hands it the influence regions whose bounding box spans at most coverage_texels texels, as
// records (triangle slot, polygon), instead of emitting them; one invocation per record visits
// every texel the polygon reaches and does what the fragment stage does for a fragment there
// (empty list blocks skipped, deferral_append.glsl: the block's pairs appended). On llvmpipe the
// strips' setup and rasterisation cost more than this loop over the polygon's rows.
// Coverage: a texel is visited when its centre lies within PENUMBRA_SBS_COVERAGE_SLACK (1/64)
// pixel of the polygon in x and in y (the polygon grown by that square): every texel GL's rule
// rasterizes, with vertices snapped to 1/128 pixel or finer, and a few more on the boundary. The
// region is already the conservatively dilated one, so the visited texels hold every pair the
// influence region needs (SoftMode::Exact and Brute: the same bits; an extra texel's pairs find
// nothing to block).
// Dispatched indirectly with the group counts light_pass_args.comp.glsl (kind 3) wrote.
// Defines: light_pass_work.glsl's, PENUMBRA_INFLUENCE_SIDES, PENUMBRA_SBS_REGION_BASE (the records'
// first word in the triangles buffer), PENUMBRA_SBS_OCCUPANCY_BASE / _ROW (the occupancy bits' first
// word and words per grid row), PENUMBRA_SBS_STENCIL_BLOCKS (the list blocks the occupancy stencil
// would cover: 255 with SoftSkips::empty_blocks, else 0), PENUMBRA_SBS_COVERAGE_BITS=1: the program
// that sets the occupancy bits instead (one invocation per word, after the lists).
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=0 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_CLOSED_CASTERS=1 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_INFLUENCE_SIDES=12
// penumbra-permutation: PENUMBRA_SBS_COVERAGE_BITS=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_INFLUENCE_SIDES=6
#include "penumbra/sample_based_soft/light_pass_work.glsl"
#include "penumbra/influence_region/influence_region_shared.h"

#ifndef PENUMBRA_SBS_REGION_BASE
#error light_pass_coverage.comp.glsl needs PENUMBRA_SBS_REGION_BASE (the records' first word in the triangles buffer)
#endif
#ifndef PENUMBRA_INFLUENCE_SIDES
#error light_pass_coverage.comp.glsl needs PENUMBRA_INFLUENCE_SIDES
#endif
#define PENUMBRA_SBS_COVERAGE_SLACK 0.015625LF  // 1/64 pixel

#ifndef PENUMBRA_SBS_OCCUPANCY_BASE
#error light_pass_coverage.comp.glsl needs PENUMBRA_SBS_OCCUPANCY_BASE and PENUMBRA_SBS_OCCUPANCY_ROW (the occupancy bits' first word and words per row)
#endif
#ifndef PENUMBRA_SBS_STENCIL_BLOCKS
#define PENUMBRA_SBS_STENCIL_BLOCKS 0u  // list blocks the occupancy stencil covers (SoftSkips::empty_blocks: 255)
#endif
#ifndef PENUMBRA_SBS_COVERAGE_BITS
#define PENUMBRA_SBS_COVERAGE_BITS 0
#endif

layout(local_size_x = PENUMBRA_SBS_COVERAGE_GROUP) in;

#if PENUMBRA_SBS_COVERAGE_BITS
// The occupancy bits, once per frame after the lists: bit x % 32 of word y * ROW + x / 32 set
// where texel (x, y)'s list is not empty.
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) writeonly buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };

void main() {
    const uint k = gl_GlobalInvocationID.x;
    const uint width = penumbraSbsParams.grid.x;
    if (k >= penumbraSbsParams.grid.y * uint(PENUMBRA_SBS_OCCUPANCY_ROW)) return;
    const uint y = k / uint(PENUMBRA_SBS_OCCUPANCY_ROW), first = 32u * (k % uint(PENUMBRA_SBS_OCCUPANCY_ROW));
    uint bits = 0u;
    for (uint i = 0u; i < 32u && first + i < width; ++i)
        if (penumbraSampleListsRange(ivec2(first + i, y)).y != 0u) bits |= 1u << i;
    penumbraSbsTriangles[uint(PENUMBRA_SBS_OCCUPANCY_BASE) + k] = bits;
}
#else
#include "penumbra/sample_based_soft/triangle_slots.glsl"
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) writeonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };
layout(std430, binding = PENUMBRA_SBS_FRAGMENTS_BINDING) writeonly buffer PenumbraSbsFragments { uvec2 penumbraSbsFragments[]; };
// Counters wait in the deferral buffer with the draws' (kept only when the draws did not overflow).
#define PENUMBRA_SBS_COUNT(index) atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + (index)], 1u)
#include "penumbra/sample_based_soft/deferral_append.glsl"

vec2 penumbraSbsRegion[PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)];

// The texel indices [first, last] on an axis of `size` texels whose centres (index + 0.5) lie
// within the slack of [lo, hi] (none: first > last).
ivec2 penumbraSbsCoverageRange(double lo, double hi, int size) {
    const double first = ceil(clamp(lo - PENUMBRA_SBS_COVERAGE_SLACK - 0.5LF, -1.0LF, double(size)));
    const double last = floor(clamp(hi + PENUMBRA_SBS_COVERAGE_SLACK - 0.5LF, -1.0LF, double(size)));
    return ivec2(max(0, int(first)), min(size - 1, int(last)));
}

// Row y's span of the polygon penumbraSbsRegion[0, n) grown by the slack in x and y: the extent of
// its edges' points within the slack of the row's centre line (the ends of each edge's part in
// that band), in double (pixel coordinates stay within the guard bound, < 2^18: the error is below
// 2^-30 px). GLSL twin of penumbra::influenceCoverageSpan.
ivec2 penumbraSbsCoverageSpan(int n, int y, int width) {
    const double yc = double(y) + 0.5LF;
    double left = 1.0e300LF, right = -1.0e300LF;
    for (int j = 0; j < n; ++j) {
        const dvec2 a = dvec2(penumbraSbsRegion[j]), b = dvec2(penumbraSbsRegion[j + 1 < n ? j + 1 : 0]);
        const double bottom = min(a.y, b.y), top = max(a.y, b.y);
        if (yc < bottom - PENUMBRA_SBS_COVERAGE_SLACK || yc > top + PENUMBRA_SBS_COVERAGE_SLACK) continue;
        if (top > bottom) {
            precise double t0 = clamp((yc - PENUMBRA_SBS_COVERAGE_SLACK - a.y) / (b.y - a.y), 0.0LF, 1.0LF);
            precise double t1 = clamp((yc + PENUMBRA_SBS_COVERAGE_SLACK - a.y) / (b.y - a.y), 0.0LF, 1.0LF);
            precise double x0 = a.x + t0 * (b.x - a.x);
            precise double x1 = a.x + t1 * (b.x - a.x);
            left = min(left, min(x0, x1));
            right = max(right, max(x0, x1));
        } else {
            left = min(left, min(a.x, b.x));
            right = max(right, max(a.x, b.x));
        }
    }
    return penumbraSbsCoverageRange(left, right, width);
}

void main() {
    const uint r = gl_GlobalInvocationID.x;
    if (r >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED]) return;
    const uint base = uint(PENUMBRA_SBS_REGION_BASE) + PENUMBRA_SBS_REGION_WORDS(PENUMBRA_INFLUENCE_SIDES) * r;
    const uint slot = penumbraSbsTriangles[base];
    const int n = int(min(penumbraSbsTriangles[base + 1u], uint(PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES))));
    vec2 lo = vec2(3.0e38), hi = vec2(-3.0e38);
    for (int j = 0; j < n; ++j) {
        penumbraSbsRegion[j] = uintBitsToFloat(uvec2(penumbraSbsTriangles[base + 2u + 2u * uint(j)],
                                                     penumbraSbsTriangles[base + 3u + 2u * uint(j)]));
        lo = min(lo, penumbraSbsRegion[j]);
        hi = max(hi, penumbraSbsRegion[j]);
    }
    const PenumbraSbsParams P = penumbraSbsSlotParams(slot);
#if PENUMBRA_SBS_WEDGES
    const PenumbraSbsWedges wedges = penumbraSbsSlotWedges(slot);
#else
    const PenumbraSbsWedges wedges = penumbraSbsNoWedges();
#endif
    // The draw's fragments the occupancy stencil would cull (SoftSkips::empty_blocks, list blocks
    // below PENUMBRA_SBS_STENCIL_BLOCKS) are neither visited nor counted here: count_work's
    // complement draw counts them.
    const bool stencil = P.grid.w < uint(PENUMBRA_SBS_STENCIL_BLOCKS);
    const bool skip_empty = (P.reserved.y & PENUMBRA_SBS_FLAG_SKIP_EMPTY) != 0u;
    const bool culled_pass = PENUMBRA_SBS_CLOSED_CASTERS != 0 && (P.reserved.y & PENUMBRA_SBS_FLAG_CULLED_PASS) != 0u;
    // Rows whose centre y + 0.5 lies in [lo.y - slack, hi.y + slack], within the grid.
    const ivec2 rows = penumbraSbsCoverageRange(double(lo.y), double(hi.y), int(P.grid.y));
    for (int y = rows.x; y <= rows.y; ++y) {
        const ivec2 span = penumbraSbsCoverageSpan(n, y, int(P.grid.x));
        const int x0 = span.x, x1 = span.y;
        if (x0 > x1) continue;
        // Only the texels whose list is not empty (the occupancy bits), lowest first.
        uint listed = 0u;  // texels of the span whose block is not empty
        for (int w = x0 >> 5; w <= x1 >> 5; ++w) {
            const uint first_bit = uint(max(x0 - 32 * w, 0)), last_bit = uint(min(x1 - 32 * w, 31));
            uint bits = penumbraSbsTriangles[uint(PENUMBRA_SBS_OCCUPANCY_BASE) + uint(y) * PENUMBRA_SBS_OCCUPANCY_ROW + uint(w)] &
                        (0xFFFFFFFFu << first_bit) & (0xFFFFFFFFu >> (31u - last_bit));
            while (bits != 0u) {
                const int x = 32 * w + findLSB(bits);
                bits &= bits - 1u;
                const uvec2 texel = uvec2(x, y);
                const uvec2 range = penumbraSampleListsBlock(ivec2(texel), P.grid.w, P.grid.z);
                if (range.y == 0u) continue;  // past the list's end
                ++listed;
#if PENUMBRA_SBS_CLOSED_CASTERS
                // The second pass over closed casters: texels without a flagged sample have nothing
                // to do (the stencil culls them, else the fragment stage counts them).
                if (culled_pass && penumbraSbsNear[P.counts.x + texel.y * P.grid.x + texel.x] == 0u) {
#if PENUMBRA_SBS_COUNT_WORK
                    if (!stencil) {
                        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS);
                        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED);
                    }
#endif
                    continue;
                }
#endif
                penumbraSbsAppendBlock(texel, range, slot, wedges);
            }
        }
#if PENUMBRA_SBS_COUNT_WORK
        // Without the stencil the fragment stage counts the empty blocks' fragments too: skipped
        // with SoftSkips::empty_blocks (or in the second pass over closed casters: an empty texel
        // holds no flagged sample).
        if (!stencil) {
            const uint empty = uint(x1 - x0 + 1) - listed;
            atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + PENUMBRA_SBS_WORK_FRAGMENTS], empty);
            if (skip_empty || culled_pass)
                atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED], empty);
        }
#endif
    }
}
#endif
