// penumbra — alias-free hard shadows, the compute light pass's tiles pass (AfhLightPass::Compute):
// what the raster light pass's fragment stage (light_pass.frag.glsl) does, for the texels of one
// tile of one triangle's box. Item = one (triangle, 8 x 8 tile of its box) of the chunk; a work
// group works penumbraAfhItemsPerGroup consecutive items in turn (one work group per item costs
// llvmpipe more in launches than the items' work), invocation = one texel of the tile: it applies
// the fragment stage's box test (the emitter's pixel-expanded box, conservative_raster_clip.glsl)
// and, for unclipped triangles that are not thin, the exact hull's edge test to the texel's
// centre, walks list block b (params pass.x) of the texel's list and sets the shadow bit of every
// sample the triangle blocks: the same blocker test on the same bits. Every texel whose square
// touches the triangle passes both tests (conservative_raster_test checks the twins on 10^5
// triangles), so every texel that can hold a blocked sample is visited.
// The items of a chunk: the setup pass's tile counts, scanned inclusively in place (the scanner),
// so item i belongs to the first triangle whose scan exceeds i (a binary search).
// PENUMBRA_AFH_TILES_ARGS=1 builds the one-invocation args program instead: it writes each list
// block's group counts (0 past the longest list, the raster pass's predicates) from the scan's
// last entry and the lists' header.
// penumbra-permutation: PENUMBRA_AFH_TILES_ARGS=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_AFH_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_AFH_EXACT=1 PENUMBRA_AFH_FILTERED=0 PENUMBRA_AFH_SKIP_SHADOWED=0
// penumbra-permutation: PENUMBRA_AFH_EXACT=0 PENUMBRA_AFH_COUNT_WORK=0
#include "penumbra/common/common_shared.h"
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

#ifndef PENUMBRA_AFH_TILES_ARGS
#define PENUMBRA_AFH_TILES_ARGS 0
#endif
#ifndef PENUMBRA_AFH_COUNT_WORK
#define PENUMBRA_AFH_COUNT_WORK 0
#endif

layout(std430, binding = PENUMBRA_AFH_ITEMS_BINDING) readonly buffer PenumbraAfhItems { uint penumbraAfhItems[]; };
layout(std430, binding = PENUMBRA_AFH_WORK_BINDING) buffer PenumbraAfhWork { uint penumbraAfhWork[]; };
layout(location = 0) uniform uint penumbraAfhChunkTriangles;  // records in this chunk

#if PENUMBRA_AFH_TILES_ARGS
layout(local_size_x = 1) in;
layout(std430, binding = PENUMBRA_AFH_HEADER_BINDING) readonly buffer PenumbraAfhHeaderBlock {
    PenumbraSampleListsHeader penumbraAfhHeader;
};
layout(std430, binding = PENUMBRA_AFH_ARGS_BINDING) writeonly buffer PenumbraAfhArgs { uint penumbraAfhArgs[]; };
layout(location = 1) uniform uvec2 penumbraAfhBlocks;  // x = list block size, y = list blocks the pass may walk
layout(location = 2) uniform uint penumbraAfhItemsPerGroup;  // consecutive items one work group of the tiles pass works

void main() {
    const uint n = penumbraAfhChunkTriangles;
    const uint items = n > 0u ? penumbraAfhItems[n - 1u] : 0u;
    const uint length = penumbraAfhHeader.max_list_length, size = penumbraAfhBlocks.x;
    const uint needed = length / size + ((length % size) != 0u ? 1u : 0u);
    // 1D item counts folded into (x, y) with x <= PENUMBRA_MAX_GROUPS_PER_DIMENSION
    // (penumbra::detail::foldDispatch; the last row's extra groups find no item).
    const uint groups = items / penumbraAfhItemsPerGroup + ((items % penumbraAfhItemsPerGroup) != 0u ? 1u : 0u);
    const uint x = min(groups, uint(PENUMBRA_MAX_GROUPS_PER_DIMENSION));
    const uint y = x > 0u ? (groups + x - 1u) / x : 0u;
    for (uint b = 0u; b < penumbraAfhBlocks.y; ++b) {
        const bool run = b < needed && items > 0u;
        penumbraAfhArgs[4u * b] = run ? x : 0u;
        penumbraAfhArgs[4u * b + 1u] = run ? y : 0u;
        penumbraAfhArgs[4u * b + 2u] = run ? 1u : 0u;
        penumbraAfhArgs[4u * b + 3u] = items;
    }
    atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_ITEMS], items);
}
#else
layout(local_size_x = PENUMBRA_AFH_TILE_WIDTH, local_size_y = PENUMBRA_AFH_TILE_HEIGHT) in;

layout(std430, binding = PENUMBRA_AFH_TRIANGLES_BINDING) readonly buffer PenumbraAfhTriangles { uint penumbraAfhTriangles[]; };
#include "penumbra/alias_free_hard/light_pass_lists.glsl"
#include "penumbra/common/dispatch.glsl"

layout(location = 1) uniform uint penumbraAfhItemsPerGroup;  // consecutive items one work group works

void main() {
    const uint n = penumbraAfhChunkTriangles;
    const uint items = n > 0u ? penumbraAfhItems[n - 1u] : 0u;
    uint texels = 0u, tests = 0u, fallbacks = 0u, skipped = 0u;
    const uint first_item = penumbraLinearGroup() * penumbraAfhItemsPerGroup;
    const uint end_item = min(first_item + penumbraAfhItemsPerGroup, items);
    for (uint item = first_item; item < end_item; ++item) {
        // The first record whose inclusive scan exceeds the item (records of 0 tiles are skipped:
        // their scan equals the previous one). The same search in every invocation: one address.
        uint lo = 0u, hi = n;
        while (lo < hi) {
            const uint mid = (lo + hi) / 2u;
            if (penumbraAfhItems[mid] > item) hi = mid;
            else lo = mid + 1u;
        }
        const uint base = lo * uint(PENUMBRA_AFH_TRIANGLE_WORDS);
        const uint k = item - (lo > 0u ? penumbraAfhItems[lo - 1u] : 0u);
        const uint tiles_x = penumbraAfhTriangles[base + 11u];
        const uint first = penumbraAfhTriangles[base + 9u], last = penumbraAfhTriangles[base + 10u];
        const ivec2 tile = ivec2(first & 0xFFFFu, first >> 16) +
                           ivec2(k % tiles_x, k / tiles_x) * ivec2(PENUMBRA_AFH_TILE_WIDTH, PENUMBRA_AFH_TILE_HEIGHT);
        const ivec2 texel = tile + ivec2(gl_LocalInvocationID.xy);
        const float h = uintBitsToFloat(penumbraAfhTriangles[base + 22u]);
        const vec2 p0 = uintBitsToFloat(uvec2(penumbraAfhTriangles[base + 16u], penumbraAfhTriangles[base + 17u]));
        const vec2 p1 = uintBitsToFloat(uvec2(penumbraAfhTriangles[base + 18u], penumbraAfhTriangles[base + 19u]));
        const vec2 p2 = uintBitsToFloat(uvec2(penumbraAfhTriangles[base + 20u], penumbraAfhTriangles[base + 21u]));
        // The whole tile first (the same value for every invocation: a long thin triangle's box
        // is mostly tiles its hull misses), then this texel. The grid's viewport is (0, 0).
        const vec2 tile_lo = vec2(tile) + 0.5, tile_hi = tile_lo + vec2(PENUMBRA_AFH_TILE_WIDTH - 1, PENUMBRA_AFH_TILE_HEIGHT - 1);
        if (h > 0.0 && !penumbraConservativeRectMeetsDilatedTriangle(tile_lo, tile_hi, p0, p1, p2, h)) continue;
        if (texel.x > int(last & 0xFFFFu) || texel.y > int(last >> 16)) continue;
        const vec4 box = uintBitsToFloat(uvec4(penumbraAfhTriangles[base + 12u], penumbraAfhTriangles[base + 13u],
                                               penumbraAfhTriangles[base + 14u], penumbraAfhTriangles[base + 15u]));
        // The fragment stage's test, at the centre gl_FragCoord would have, and the exact hull's
        // edges (a superset of the pixels the triangle touches).
        const vec2 centre = vec2(texel) + 0.5;
        if (!penumbraConservativeInsideBox(centre, box)) continue;
        if (h > 0.0 && !penumbraConservativeInsideDilatedTriangle(centre, p0, p1, p2, h)) continue;
        const uvec2 range = penumbraSampleListsBlock(texel, penumbraAfhParams.pass.x, penumbraAfhParams.grid.z);
        if (range.y == 0u) continue;
        ++texels;
        const vec3 v0 = uintBitsToFloat(uvec3(penumbraAfhTriangles[base], penumbraAfhTriangles[base + 1u], penumbraAfhTriangles[base + 2u]));
        const vec3 v1 = uintBitsToFloat(uvec3(penumbraAfhTriangles[base + 3u], penumbraAfhTriangles[base + 4u], penumbraAfhTriangles[base + 5u]));
        const vec3 v2 = uintBitsToFloat(uvec3(penumbraAfhTriangles[base + 6u], penumbraAfhTriangles[base + 7u], penumbraAfhTriangles[base + 8u]));
        penumbraAfhWalk(range, v0, v1, v2, tests, fallbacks, skipped);
    }
#if PENUMBRA_AFH_COUNT_WORK
    if (texels > 0u) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_FRAGMENTS], texels);
    if (tests > 0u) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TESTS], tests);
    if (fallbacks > 0u) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_FALLBACKS], fallbacks);
    if (skipped > 0u) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TESTS_SKIPPED], skipped);
#endif
}
#endif
