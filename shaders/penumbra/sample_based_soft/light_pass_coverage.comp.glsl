// penumbra — sample-based soft shadows, deferred pairs, the coverage pass
// (SampleBasedSoftGpuOptions::coverage_texels, and every region with SoftLightPass::Compute): the
// light pass's geometry stage (light_pass.geom.glsl) or the compute light pass's caster setup
// (light_pass_setup.comp.glsl) hands it influence regions as records (triangle slot, polygon)
// instead of emitting them; it visits every texel the polygon reaches and does what the fragment
// stage does for a fragment there (empty list blocks skipped, deferral_append.glsl: the block's
// pairs appended). On llvmpipe the strips' setup and rasterisation cost more than these loops.
// Coverage: a texel is visited when its centre lies within PENUMBRA_SBS_COVERAGE_SLACK (1/64)
// pixel of the polygon in x and in y (the polygon grown by that square): every texel GL's rule
// rasterizes, with vertices snapped to 1/128 pixel or finer, and a few more on the boundary. The
// region is already the conservatively dilated one, so the visited texels hold every pair the
// influence region needs (SoftMode::Exact and Brute: the same bits; an extra texel's pairs find
// nothing to block).
// Work items (bounded work per invocation: llvmpipe ends every loop of an invocation once all its
// loops together ran 65 535 iterations, silently; GPUs balance better too): a record's texels are
// cut into tiles of PENUMBRA_SBS_TILE_ROWS x PENUMBRA_SBS_TILE_COLUMNS texels of the grid (the
// columns divide 32: one occupancy word per tile row). Four programs, per run of the deferred passes:
//   PENUMBRA_SBS_COVERAGE_COUNT=1: one invocation per record appended writes the tile box of its
//     rows and columns and its tile count; PENUMBRA_SBS_COVERAGE_SCAN=1 (one workgroup) turns the
//     counts into each record's first item (an exclusive scan: its cost follows the records);
//   the default: one invocation per (record, tile) item (the record found by binary search over
//     the first items) visits the tile's texels of the polygon;
//   PENUMBRA_SBS_COVERAGE_INLINE=1 (SoftLightPass::Compute): workgroups of at most 64 texels of an
//     item's tile, one invocation per texel, works the texel's block itself, as the per-fragment
//     program does (light_pass.comp.glsl), counting straight into the work counters; its group counts are 0
//     unless the deferred pairs and fragments overflowed (the compute twin of the raster pass's
//     redraw);
//   PENUMBRA_SBS_COVERAGE_BITS=1: the occupancy bits, one invocation per word, after the lists.
// Dispatched indirectly with the group counts light_pass_args.comp.glsl wrote (kind 3: the
// records, for the count program; kind 5: the items' groups, kind 4: one group per item, folded
// into x and y), but the scan
// (one workgroup) and bits programs (direct).
// Defines: light_pass_work.glsl's, PENUMBRA_INFLUENCE_SIDES, PENUMBRA_SBS_REGION_BASE (the records'
// first word in the triangles buffer) and _CAPACITY, PENUMBRA_SBS_OCCUPANCY_BASE / _ROW (the
// occupancy bits' first word and words per grid row), PENUMBRA_SBS_TILE_BASE (the tile counts'
// first word: then 2 box words per record, then the first items), PENUMBRA_SBS_TILE_ROWS and
// _COLUMNS, PENUMBRA_SBS_STENCIL_BLOCKS (the list blocks the occupancy stencil would cover: 255
// with SoftSkips::empty_blocks and the raster pass, 2^32 - 1 with the compute light pass: its
// empty texels are skipped by the occupancy bits and not counted, else 0).
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_COUNT_WORK=0 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_CLOSED_CASTERS=1 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=12 PENUMBRA_SBS_TILE_ROWS=2u PENUMBRA_SBS_TILE_COLUMNS=8u
// penumbra-permutation: PENUMBRA_SBS_COVERAGE_BITS=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_COVERAGE_SCAN=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_COVERAGE_COUNT=1 PENUMBRA_SBS_COVERAGE_WINDOWS=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_COVERAGE_INLINE=1 PENUMBRA_SBS_WEDGES=1 PENUMBRA_SBS_CLOSED_CASTERS=1 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_SBS_COVERAGE_INLINE=1 PENUMBRA_SBS_MODE=2 PENUMBRA_SBS_COUNT_WORK=0 PENUMBRA_SBS_REGION_BASE=0u PENUMBRA_SBS_REGION_CAPACITY=64u PENUMBRA_SBS_OCCUPANCY_BASE=0u PENUMBRA_SBS_OCCUPANCY_ROW=8u PENUMBRA_SBS_TILE_BASE=0u PENUMBRA_INFLUENCE_SIDES=6
#ifndef PENUMBRA_SBS_COVERAGE_INLINE
#define PENUMBRA_SBS_COVERAGE_INLINE 0
#endif
#ifndef PENUMBRA_SBS_COVERAGE_COUNT
#define PENUMBRA_SBS_COVERAGE_COUNT 0
#endif
#ifndef PENUMBRA_SBS_COVERAGE_SCAN
#define PENUMBRA_SBS_COVERAGE_SCAN 0
#endif
#if PENUMBRA_SBS_COVERAGE_INLINE
#define PENUMBRA_SBS_STAGE 1         // exact tests to light_pass_tests.comp.glsl, as far as they fit
#define PENUMBRA_SBS_PER_FRAGMENT 1  // a texel's whole block per visit, the tables included
#endif
#include "penumbra/sample_based_soft/light_pass_work.glsl"
#include "penumbra/influence_region/influence_region_shared.h"

#if !defined(PENUMBRA_SBS_REGION_BASE) || !defined(PENUMBRA_SBS_REGION_CAPACITY) || !defined(PENUMBRA_SBS_TILE_BASE)
#error light_pass_coverage.comp.glsl needs PENUMBRA_SBS_REGION_BASE, PENUMBRA_SBS_REGION_CAPACITY and PENUMBRA_SBS_TILE_BASE
#endif
#ifndef PENUMBRA_INFLUENCE_SIDES
#error light_pass_coverage.comp.glsl needs PENUMBRA_INFLUENCE_SIDES
#endif
#ifndef PENUMBRA_SBS_TILE_ROWS
#define PENUMBRA_SBS_TILE_ROWS 8u
#endif
#ifndef PENUMBRA_SBS_TILE_COLUMNS
#define PENUMBRA_SBS_TILE_COLUMNS 32u  // divides 32
#endif
#define PENUMBRA_SBS_COVERAGE_SLACK 0.015625LF  // 1/64 pixel
#define PENUMBRA_SBS_TILE_COUNTS uint(PENUMBRA_SBS_TILE_BASE)
#define PENUMBRA_SBS_TILE_BOXES (PENUMBRA_SBS_TILE_COUNTS + uint(PENUMBRA_SBS_REGION_CAPACITY))
#define PENUMBRA_SBS_TILE_FIRSTS (PENUMBRA_SBS_TILE_BOXES + 2u * uint(PENUMBRA_SBS_REGION_CAPACITY))
// Per tile of the grid (row-major, tiles per row = ceil(W / columns)): its longest list (the bits
// program's atomicMax; the host clears them each frame).
#define PENUMBRA_SBS_TILE_LONGEST (PENUMBRA_SBS_TILE_FIRSTS + uint(PENUMBRA_SBS_REGION_CAPACITY))
#define PENUMBRA_SBS_TILES_PER_ROW ((penumbraSbsParams.grid.x + PENUMBRA_SBS_TILE_COLUMNS - 1u) / PENUMBRA_SBS_TILE_COLUMNS)

#ifndef PENUMBRA_SBS_OCCUPANCY_BASE
#error light_pass_coverage.comp.glsl needs PENUMBRA_SBS_OCCUPANCY_BASE and PENUMBRA_SBS_OCCUPANCY_ROW (the occupancy bits' first word and words per row)
#endif
#ifndef PENUMBRA_SBS_STENCIL_BLOCKS
#define PENUMBRA_SBS_STENCIL_BLOCKS 0u  // list blocks the occupancy stencil covers (SoftSkips::empty_blocks: 255)
#endif
#ifndef PENUMBRA_SBS_COVERAGE_BITS
#define PENUMBRA_SBS_COVERAGE_BITS 0
#endif

#if PENUMBRA_SBS_COVERAGE_SCAN
layout(local_size_x = PENUMBRA_SBS_COVERAGE_SCAN_GROUP) in;
#elif PENUMBRA_SBS_COVERAGE_INLINE
// One invocation per texel (its loops within llvmpipe's bound, as the per-fragment program's), at
// most 64 per workgroup: a texel's work holds arrays in private memory (spilled on GPUs, allocated
// per workgroup by llvmpipe: 1.7 kB a texel), so a whole tile's workgroup (256 texels) asked for 4x
// the other programs' scratch.
#define PENUMBRA_SBS_TILE_TEXELS (PENUMBRA_SBS_TILE_ROWS * PENUMBRA_SBS_TILE_COLUMNS)
layout(local_size_x = PENUMBRA_SBS_INLINE_GROUP(PENUMBRA_SBS_TILE_TEXELS)) in;
#else
layout(local_size_x = PENUMBRA_SBS_COVERAGE_GROUP) in;
#endif

// The texel indices [first, last] on an axis of `size` texels whose centres (index + 0.5) lie
// within the slack of [lo, hi] (none: first > last).
ivec2 penumbraSbsCoverageRange(double lo, double hi, int size) {
    const double first = ceil(clamp(lo - PENUMBRA_SBS_COVERAGE_SLACK - 0.5LF, -1.0LF, double(size)));
    const double last = floor(clamp(hi + PENUMBRA_SBS_COVERAGE_SLACK - 0.5LF, -1.0LF, double(size)));
    return ivec2(max(0, int(first)), min(size - 1, int(last)));
}

#if PENUMBRA_SBS_COVERAGE_BITS || PENUMBRA_SBS_COVERAGE_COUNT || PENUMBRA_SBS_COVERAGE_SCAN
layout(std430, binding = PENUMBRA_SBS_TRIANGLES_BINDING) buffer PenumbraSbsTriangles { uint penumbraSbsTriangles[]; };
#else
#include "penumbra/sample_based_soft/triangle_slots.glsl"
#endif

vec2 penumbraSbsRegion[PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)];

// Record r's polygon into penumbraSbsRegion (its vertex count; its box in lo, hi) and its slot.
int penumbraSbsLoadRecord(uint r, out uint slot, out vec2 lo, out vec2 hi) {
    const uint base = uint(PENUMBRA_SBS_REGION_BASE) + PENUMBRA_SBS_REGION_WORDS(PENUMBRA_INFLUENCE_SIDES) * r;
    slot = penumbraSbsTriangles[base];
    const int n = int(min(penumbraSbsTriangles[base + 1u], uint(PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES))));
    lo = vec2(3.0e38);
    hi = vec2(-3.0e38);
    for (int j = 0; j < n; ++j) {
        penumbraSbsRegion[j] = uintBitsToFloat(uvec2(penumbraSbsTriangles[base + 2u + 2u * uint(j)],
                                                     penumbraSbsTriangles[base + 3u + 2u * uint(j)]));
        lo = min(lo, penumbraSbsRegion[j]);
        hi = max(hi, penumbraSbsRegion[j]);
    }
    return n;
}

#if PENUMBRA_SBS_COVERAGE_BITS
// The occupancy bits, once per frame after the lists: bit x % 32 of word y * ROW + x / 32 set
// where texel (x, y)'s list is not empty; and each tile's longest list.
void main() {
    const uint k = gl_GlobalInvocationID.x;
    const uint width = penumbraSbsParams.grid.x;
    if (k >= penumbraSbsParams.grid.y * uint(PENUMBRA_SBS_OCCUPANCY_ROW)) return;
    const uint y = k / uint(PENUMBRA_SBS_OCCUPANCY_ROW), first = 32u * (k % uint(PENUMBRA_SBS_OCCUPANCY_ROW));
    uint bits = 0u, longest = 0u;
    for (uint i = 0u; i < 32u && first + i < width; ++i) {
        const uint length = penumbraSampleListsRange(ivec2(first + i, y)).y;
        if (length != 0u) bits |= 1u << i;
        longest = max(longest, length);
        if ((i + 1u) % PENUMBRA_SBS_TILE_COLUMNS == 0u || first + i + 1u == width) {  // the tile's last column here
            if (longest != 0u)
                atomicMax(penumbraSbsTriangles[PENUMBRA_SBS_TILE_LONGEST + (y / PENUMBRA_SBS_TILE_ROWS) * PENUMBRA_SBS_TILES_PER_ROW +
                                               (first + i) / PENUMBRA_SBS_TILE_COLUMNS],
                          longest);
            longest = 0u;
        }
    }
    penumbraSbsTriangles[uint(PENUMBRA_SBS_OCCUPANCY_BASE) + k] = bits;
}
#elif PENUMBRA_SBS_COVERAGE_COUNT
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) readonly buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };

#ifndef PENUMBRA_SBS_COVERAGE_WINDOWS
#define PENUMBRA_SBS_COVERAGE_WINDOWS 0  // 1: the compute light pass's windows (light_pass_args.comp.glsl)
#endif
#if PENUMBRA_SBS_COVERAGE_WINDOWS
layout(location = 0) uniform uint penumbraSbsWindow;  // 0 or ~0u: a run; k + 1: window k of the last run
#endif

// Record r's tile box (first tile column | first tile row << 16, tile columns | tile rows << 16)
// and tile count (0 for a polygon that reaches no texel centre, or a record outside the window).
void main() {
    const uint r = gl_GlobalInvocationID.x;
    uint tiles = 0u, first = 0u, size = 0u;
    if (r >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED]) return;
#if PENUMBRA_SBS_COVERAGE_WINDOWS
    const uint split = penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_SPLIT];
    if (penumbraSbsWindow == 0u || penumbraSbsWindow == 0xFFFFFFFFu || r % max(split, 1u) == penumbraSbsWindow - 1u)
#endif
    {
        uint slot;
        vec2 lo, hi;
        penumbraSbsLoadRecord(r, slot, lo, hi);
        const ivec2 rows = penumbraSbsCoverageRange(double(lo.y), double(hi.y), int(penumbraSbsParams.grid.y));
        const ivec2 columns = penumbraSbsCoverageRange(double(lo.x), double(hi.x), int(penumbraSbsParams.grid.x));
        if (rows.x <= rows.y && columns.x <= columns.y) {
            const uvec2 a = uvec2(columns.x, rows.x) / uvec2(PENUMBRA_SBS_TILE_COLUMNS, PENUMBRA_SBS_TILE_ROWS);
            const uvec2 b = uvec2(columns.y, rows.y) / uvec2(PENUMBRA_SBS_TILE_COLUMNS, PENUMBRA_SBS_TILE_ROWS);
            first = a.x | a.y << 16u;
            size = (b.x - a.x + 1u) | (b.y - a.y + 1u) << 16u;
            tiles = (b.x - a.x + 1u) * (b.y - a.y + 1u);
        }
    }
    penumbraSbsTriangles[PENUMBRA_SBS_TILE_COUNTS + r] = tiles;
    penumbraSbsTriangles[PENUMBRA_SBS_TILE_BOXES + 2u * r] = first;
    penumbraSbsTriangles[PENUMBRA_SBS_TILE_BOXES + 2u * r + 1u] = size;
}
#elif PENUMBRA_SBS_COVERAGE_SCAN
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) readonly buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
shared uint penumbraSbsPartial[PENUMBRA_SBS_COVERAGE_SCAN_GROUP];

// The records' first items: an exclusive scan of their tile counts by one workgroup, each
// invocation summing a contiguous run of records, the runs' sums scanned in shared memory.
void main() {
    const uint records = penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED];
    const uint t = gl_LocalInvocationID.x, group = uint(PENUMBRA_SBS_COVERAGE_SCAN_GROUP);
    const uint run = (records + group - 1u) / group;
    const uint begin = min(t * run, records), end = min(begin + run, records);
    uint sum = 0u;
    for (uint r = begin; r < end; ++r) sum += penumbraSbsTriangles[PENUMBRA_SBS_TILE_COUNTS + r];
    penumbraSbsPartial[t] = sum;
    barrier();
    for (uint d = 1u; d < group; d <<= 1u) {  // inclusive, Hillis-Steele
        const uint before = t >= d ? penumbraSbsPartial[t - d] : 0u;
        barrier();
        penumbraSbsPartial[t] += before;
        barrier();
    }
    uint first = penumbraSbsPartial[t] - sum;
    for (uint r = begin; r < end; ++r) {
        penumbraSbsTriangles[PENUMBRA_SBS_TILE_FIRSTS + r] = first;
        first += penumbraSbsTriangles[PENUMBRA_SBS_TILE_COUNTS + r];
    }
}
#else
#if PENUMBRA_SBS_COVERAGE_INLINE
// light_pass_work.glsl declared the deferral buffer; the work is done here, counted at once.
#define PENUMBRA_SBS_COUNT_N(index, n) atomicAdd(penumbraSbsWork[index], n)
#else
layout(std430, binding = PENUMBRA_SBS_DEFERRAL_BINDING) buffer PenumbraSbsDeferral { uint penumbraSbsDeferral[]; };
layout(std430, binding = PENUMBRA_SBS_PAIRS_BINDING) writeonly buffer PenumbraSbsPairs { uvec2 penumbraSbsPairs[]; };
layout(std430, binding = PENUMBRA_SBS_FRAGMENTS_BINDING) writeonly buffer PenumbraSbsFragments { uvec2 penumbraSbsFragments[]; };
// Counters wait in the deferral buffer with the draws' (kept only when the draws did not overflow).
#define PENUMBRA_SBS_COUNT_N(index, n) atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + (index)], n)
#define PENUMBRA_SBS_COUNT(index) PENUMBRA_SBS_COUNT_N(index, 1u)
#include "penumbra/sample_based_soft/deferral_append.glsl"
#endif

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

// Work item i's record (the last whose first item is at most i: records of no tiles share their
// successor's first) and its tile (x, y) in tiles of the grid; false past the items.
bool penumbraSbsItem(uint i, out uint r, out uvec2 tile) {
    r = 0u;
    tile = uvec2(0u);
    if (i >= penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_ITEMS_DISPATCHED]) return false;
    uint lo = 0u, hi = penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_REGIONS_DISPATCHED];
    while (hi - lo > 1u) {  // firsts[lo] <= i < firsts[hi] (hi: the end)
        const uint mid = (lo + hi) >> 1u;
        if (penumbraSbsTriangles[PENUMBRA_SBS_TILE_FIRSTS + mid] <= i) lo = mid;
        else hi = mid;
    }
    r = lo;
    const uint j = i - penumbraSbsTriangles[PENUMBRA_SBS_TILE_FIRSTS + r];
    const uint first = penumbraSbsTriangles[PENUMBRA_SBS_TILE_BOXES + 2u * r];
    const uint columns = penumbraSbsTriangles[PENUMBRA_SBS_TILE_BOXES + 2u * r + 1u] & 0xFFFFu;
    tile = uvec2(first & 0xFFFFu, first >> 16u) + uvec2(j % columns, j / columns);
    return true;
}

#if PENUMBRA_SBS_COVERAGE_INLINE
// The inline program: PENUMBRA_SBS_INLINE_PARTS workgroups per (record, tile) item, each a run
// of the tile's texels (row-major), one invocation per texel. The item's lookup (a binary search)
// and the spans of the rows the run meets are computed once per workgroup, by the first
// invocation and one invocation per row, and shared: a texel whose list block is empty costs a
// few reads. Each texel the coverage rule visits whose block is not empty is worked
// whole (the per-fragment program's work, light_pass.comp.glsl), counted at once.
shared uint penumbraSbsItemRecord, penumbraSbsItemTile, penumbraSbsItemLive;
shared ivec2 penumbraSbsRowSpan[PENUMBRA_SBS_TILE_ROWS];

void main() {
    // Items' parts folded into x and y (light_pass_args.comp.glsl, kind 4).
    const uint part = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    const uint parts = PENUMBRA_SBS_INLINE_PARTS(PENUMBRA_SBS_TILE_TEXELS);
    const uint i = part / parts;
    const uint k = (part % parts) * gl_WorkGroupSize.x + gl_LocalInvocationID.x;  // the texel of the tile
    const uint row_first = (part % parts) * gl_WorkGroupSize.x / PENUMBRA_SBS_TILE_COLUMNS;
    const uint t = gl_LocalInvocationID.x;
    if (t == 0u) {
        uint r;
        uvec2 tile;
        bool live = penumbraSbsItem(i, r, tile);
        if (live) {
            // A tile whose lists all end before this item's list block has nothing to visit.
            const uint record_slot = penumbraSbsTriangles[uint(PENUMBRA_SBS_REGION_BASE) + PENUMBRA_SBS_REGION_WORDS(PENUMBRA_INFLUENCE_SIDES) * r];
            const uint block = penumbraSbsTriangles[PENUMBRA_SBS_TRIANGLE_WORDS * record_slot + 9u] & 0xFFFFu;
            const uint longest = penumbraSbsTriangles[PENUMBRA_SBS_TILE_LONGEST + tile.y * PENUMBRA_SBS_TILES_PER_ROW + tile.x];
            live = !(block < uint(PENUMBRA_SBS_STENCIL_BLOCKS) && longest <= block * penumbraSbsParams.grid.z);
        }
        penumbraSbsItemRecord = r;
        penumbraSbsItemTile = tile.x | tile.y << 16u;
        penumbraSbsItemLive = live ? 1u : 0u;
    }
    barrier();
    if (penumbraSbsItemLive == 0u) return;  // the whole workgroup (uniform)
    const uint r = penumbraSbsItemRecord;
    const uvec2 tile = uvec2(penumbraSbsItemTile & 0xFFFFu, penumbraSbsItemTile >> 16u);
    const ivec2 tile_origin = ivec2(tile * uvec2(PENUMBRA_SBS_TILE_COLUMNS, PENUMBRA_SBS_TILE_ROWS));
    const uint row = row_first + t;  // the rows this run meets, each an invocation's (rows <= texels)
    if (row < PENUMBRA_SBS_TILE_ROWS && row * PENUMBRA_SBS_TILE_COLUMNS < (part % parts + 1u) * gl_WorkGroupSize.x) {
        // The tile's row: the texels the coverage rule visits (none outside the polygon's rows,
        // the grid, or where no texel of the tile's row is listed).
        uint slot;
        vec2 lo, hi;
        const int n = penumbraSbsLoadRecord(r, slot, lo, hi);
        const int y = tile_origin.y + int(row);
        const ivec2 rows = penumbraSbsCoverageRange(double(lo.y), double(hi.y), int(penumbraSbsParams.grid.y));
        const uint tile_word = uint(tile_origin.x) >> 5u, tile_shift = uint(tile_origin.x) & 31u;
        const uint tile_bits = (PENUMBRA_SBS_TILE_COLUMNS >= 32u ? 0xFFFFFFFFu : (1u << PENUMBRA_SBS_TILE_COLUMNS) - 1u) << tile_shift;
        ivec2 span = ivec2(0, -1);
        if (y >= rows.x && y <= rows.y &&
            (penumbraSbsTriangles[uint(PENUMBRA_SBS_OCCUPANCY_BASE) + uint(y) * PENUMBRA_SBS_OCCUPANCY_ROW + tile_word] & tile_bits) != 0u)
            span = penumbraSbsCoverageSpan(n, y, int(penumbraSbsParams.grid.x));
        penumbraSbsRowSpan[row] = span;
    }
    barrier();
    if (k >= PENUMBRA_SBS_TILE_TEXELS) return;  // past the tile (its last part)
    const ivec2 texel = tile_origin + ivec2(int(k % PENUMBRA_SBS_TILE_COLUMNS), int(k / PENUMBRA_SBS_TILE_COLUMNS));
    const ivec2 span = penumbraSbsRowSpan[k / PENUMBRA_SBS_TILE_COLUMNS];
    if (texel.x < span.x || texel.x > span.y) return;  // outside the polygon, the grid or every listed row
    if ((penumbraSbsTriangles[uint(PENUMBRA_SBS_OCCUPANCY_BASE) + uint(texel.y) * PENUMBRA_SBS_OCCUPANCY_ROW + (uint(texel.x) >> 5u)] &
         (1u << (uint(texel.x) & 31u))) == 0u)
        return;  // an empty list
    const uint slot = penumbraSbsTriangles[uint(PENUMBRA_SBS_REGION_BASE) + PENUMBRA_SBS_REGION_WORDS(PENUMBRA_INFLUENCE_SIDES) * r];
    const PenumbraSbsParams P = penumbraSbsSlotParams(slot);
    if (penumbraSampleListsBlock(texel, P.grid.w, P.grid.z).y == 0u) return;  // past the list's end
#if PENUMBRA_SBS_CLOSED_CASTERS
    // The second pass over closed casters: texels without a flagged sample have nothing to do
    // (uncounted, as the compute light pass counts no texel its occupancy bits skip).
    if ((P.reserved.y & PENUMBRA_SBS_FLAG_CULLED_PASS) != 0u &&
        penumbraSbsNear[P.counts.x + uint(texel.y) * P.grid.x + uint(texel.x)] == 0u)
        return;
#endif
    penumbraSbsFragmentPairs = 1u;  // the visit counts as a fragment
    penumbraSbsSlotWork(slot, uvec2(texel), PENUMBRA_SBS_WHOLE_BLOCK);
}
#else
void main() {
    // Items folded into x and y (light_pass_args.comp.glsl, kind 5).
    const uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * uint(PENUMBRA_SBS_COVERAGE_GROUP) +
                   gl_LocalInvocationID.x;
    uint r;
    uvec2 tile;
    if (!penumbraSbsItem(i, r, tile)) return;
    // A tile whose lists all end before this item's list block has nothing to visit; where its
    // empty blocks are not counted (the stencil's blocks: every block with the compute light
    // pass) the item ends here, before its polygon is read.
    {
        const uint record_slot = penumbraSbsTriangles[uint(PENUMBRA_SBS_REGION_BASE) + PENUMBRA_SBS_REGION_WORDS(PENUMBRA_INFLUENCE_SIDES) * r];
        const uint block = penumbraSbsTriangles[PENUMBRA_SBS_TRIANGLE_WORDS * record_slot + 9u] & 0xFFFFu;
        const uint longest = penumbraSbsTriangles[PENUMBRA_SBS_TILE_LONGEST + tile.y * PENUMBRA_SBS_TILES_PER_ROW + tile.x];
        if (block < uint(PENUMBRA_SBS_STENCIL_BLOCKS) && longest <= block * penumbraSbsParams.grid.z) return;
    }
    uint slot;
    vec2 lo, hi;
    const int n = penumbraSbsLoadRecord(r, slot, lo, hi);
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
    // The tile's rows whose centre y + 0.5 lies in [lo.y - slack, hi.y + slack], within the grid.
    const ivec2 rows = penumbraSbsCoverageRange(double(lo.y), double(hi.y), int(P.grid.y));
    const ivec2 tile_rows = ivec2(tile.y * PENUMBRA_SBS_TILE_ROWS) + ivec2(0, int(PENUMBRA_SBS_TILE_ROWS) - 1);
    const ivec2 tile_columns = ivec2(tile.x * PENUMBRA_SBS_TILE_COLUMNS) + ivec2(0, int(PENUMBRA_SBS_TILE_COLUMNS) - 1);
    const int y_first = max(rows.x, tile_rows.x), y_last = min(rows.y, tile_rows.y);
    const uint tile_word = uint(tile_columns.x) >> 5u, tile_shift = uint(tile_columns.x) & 31u;
    const uint tile_bits = (PENUMBRA_SBS_TILE_COLUMNS >= 32u ? 0xFFFFFFFFu : (1u << PENUMBRA_SBS_TILE_COLUMNS) - 1u) << tile_shift;
    for (int y = y_first; y <= y_last; ++y) {
        if (y < rows.x || y > rows.y) continue;
        // A tile row without a listed texel has nothing to visit, and where the empty texels are
        // not counted (the stencil's blocks; every block with the compute light pass) nothing to
        // count: no span.
        if (stencil && (penumbraSbsTriangles[uint(PENUMBRA_SBS_OCCUPANCY_BASE) + uint(y) * PENUMBRA_SBS_OCCUPANCY_ROW + tile_word] &
                        tile_bits) == 0u)
            continue;
        const ivec2 span = penumbraSbsCoverageSpan(n, y, int(P.grid.x));
        const int x0 = max(span.x, tile_columns.x), x1 = min(span.y, tile_columns.y);
        if (x0 > x1) continue;
        // Only the texels whose list is not empty (the occupancy bits), lowest first: one word
        // (the tile's columns lie in one).
        uint listed = 0u;  // texels of the span whose block is not empty
        const int w = x0 >> 5;
        const uint first_bit = uint(x0 - 32 * w), last_bit = uint(x1 - 32 * w);
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
                    PENUMBRA_SBS_COUNT_N(PENUMBRA_SBS_WORK_FRAGMENTS, 1u);
                    PENUMBRA_SBS_COUNT_N(PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED, 1u);
                }
#endif
                continue;
            }
#endif
            penumbraSbsAppendBlock(texel, range, slot, wedges);
        }
#if PENUMBRA_SBS_COUNT_WORK
        // Without the stencil the fragment stage counts the empty blocks' fragments too: skipped
        // with SoftSkips::empty_blocks (or in the second pass over closed casters: an empty texel
        // holds no flagged sample).
        if (!stencil) {
            const uint empty = uint(x1 - x0 + 1) - listed;
            if (empty != 0u) PENUMBRA_SBS_COUNT_N(PENUMBRA_SBS_WORK_FRAGMENTS, empty);
            if (empty != 0u && (skip_empty || culled_pass)) PENUMBRA_SBS_COUNT_N(PENUMBRA_SBS_WORK_FRAGMENTS_SKIPPED, empty);
        }
#endif
    }
}
#endif
#endif
