#version 450
// penumbra — fragment stage for conservative rasterization, a ready entry for tests and a template
// for integrators.
//
// Default: writes triangle id + 1 to an R32UI colour target at location 0 (a coverage/id buffer).
// PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=1 discards fragments outside the triangle's pixel-expanded
// bounding box (conservative_raster_clip.glsl).
// PENUMBRA_CONSERVATIVE_RECORD=1 records coverage instead of writing colour: per triangle a 32 x 32
// tile bitset at the tile origin read from binding PENUMBRA_CONSERVATIVE_RECORD_TILES_BINDING
// (ivec2 per triangle, window pixels) plus fragment counters, all in
// PENUMBRA_CONSERVATIVE_RECORD_WORDS words at binding PENUMBRA_CONSERVATIVE_RECORD_WORDS_BINDING
// (layout in conservative_raster_shared.h).
// PENUMBRA_CONSERVATIVE_PLAIN=1: no geometry stage in front (the plain, non-conservative baseline);
// the triangle id is uniform location 8 + gl_PrimitiveID.
// penumbra-permutation: PENUMBRA_CONSERVATIVE_RECORD=0
// penumbra-permutation: PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_PLAIN=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_RECORD=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_RECORD=1 PENUMBRA_CONSERVATIVE_CLIP_TO_BOX=1
// penumbra-permutation: PENUMBRA_CONSERVATIVE_RECORD=1 PENUMBRA_CONSERVATIVE_PLAIN=1
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/conservative_raster/conservative_raster_clip.glsl"

#ifndef PENUMBRA_CONSERVATIVE_RECORD
#define PENUMBRA_CONSERVATIVE_RECORD 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_CLIP_TO_BOX
#define PENUMBRA_CONSERVATIVE_CLIP_TO_BOX 0
#endif
#ifndef PENUMBRA_CONSERVATIVE_PLAIN
#define PENUMBRA_CONSERVATIVE_PLAIN 0
#endif
#if PENUMBRA_CONSERVATIVE_PLAIN && PENUMBRA_CONSERVATIVE_CLIP_TO_BOX
#error PENUMBRA_CONSERVATIVE_PLAIN has no geometry stage, hence no box to clip to
#endif

#if PENUMBRA_CONSERVATIVE_PLAIN
layout(location = 8) uniform uint penumbraConservativeFirstTriangle;
#else
layout(location = 0) flat in vec4 penumbraConservativeBox;
layout(location = 1) flat in uint penumbraConservativeTriangle;
#endif

#if PENUMBRA_CONSERVATIVE_RECORD
layout(std430, binding = PENUMBRA_CONSERVATIVE_RECORD_WORDS_BINDING) buffer PenumbraConservativeRecordWords {
    uint penumbraConservativeRecordWords[];
};
layout(std430, binding = PENUMBRA_CONSERVATIVE_RECORD_TILES_BINDING) readonly buffer PenumbraConservativeRecordTiles {
    ivec2 penumbraConservativeRecordTiles[];
};
#else
layout(location = 0) out uint penumbraConservativeMark;
#endif

void main() {
#if PENUMBRA_CONSERVATIVE_CLIP_TO_BOX
    if (!penumbraConservativeInsideBox(gl_FragCoord.xy, penumbraConservativeBox)) discard;
#endif
#if PENUMBRA_CONSERVATIVE_PLAIN
    uint triangle = penumbraConservativeFirstTriangle + uint(gl_PrimitiveID);
#else
    uint triangle = penumbraConservativeTriangle;
#endif
#if PENUMBRA_CONSERVATIVE_RECORD
    uint base = triangle * uint(PENUMBRA_CONSERVATIVE_RECORD_WORDS);
    ivec2 local = ivec2(floor(gl_FragCoord.xy)) - penumbraConservativeRecordTiles[triangle];
    atomicAdd(penumbraConservativeRecordWords[base + uint(PENUMBRA_CONSERVATIVE_RECORD_FRAGMENTS)], 1u);
    if (all(greaterThanEqual(local, ivec2(0))) && all(lessThan(local, ivec2(PENUMBRA_CONSERVATIVE_RECORD_TILE)))) {
        atomicOr(penumbraConservativeRecordWords[base + uint(local.y)], 1u << uint(local.x));
    } else {
        atomicAdd(penumbraConservativeRecordWords[base + uint(PENUMBRA_CONSERVATIVE_RECORD_OUTSIDE)], 1u);
    }
#else
    penumbraConservativeMark = triangle + 1u;
#endif
}
