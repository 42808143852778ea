// penumbra — constants and the parameter block shared by the alias-free hard-shadow pipeline's
// host code (include/penumbra/pipelines/alias_free_hard.hpp, gl/pipelines/alias_free_hard.hpp)
// and its shaders. Valid GLSL and C++.
#ifndef PENUMBRA_ALIAS_FREE_HARD_SHARED_H
#define PENUMBRA_ALIAS_FREE_HARD_SHARED_H

// Bindings of the light pass and the resolve: the defaults of penumbra::AfhBindings, injected as
// defines by the pipeline (each overridable). The conservative emitter's parameter block uses its
// own binding, PENUMBRA_CONSERVATIVE_PARAMS_BINDING (0).
#ifndef PENUMBRA_AFH_PARAMS_BINDING
#define PENUMBRA_AFH_PARAMS_BINDING 1    // uniform block: PenumbraAfhParams (one slot per draw)
#endif
#ifndef PENUMBRA_AFH_FRUSTUM_BINDING
#define PENUMBRA_AFH_FRUSTUM_BINDING 2   // uniform block: PenumbraSampleListsFrustum (the lists' light matrix)
#endif
#ifndef PENUMBRA_AFH_COUNTS_BINDING
#define PENUMBRA_AFH_COUNTS_BINDING 0
#endif
#ifndef PENUMBRA_AFH_OFFSETS_BINDING
#define PENUMBRA_AFH_OFFSETS_BINDING 1
#endif
#ifndef PENUMBRA_AFH_POSITIONS_BINDING
#define PENUMBRA_AFH_POSITIONS_BINDING 2
#endif
#ifndef PENUMBRA_AFH_SHADOW_BINDING
#define PENUMBRA_AFH_SHADOW_BINDING 3
#endif
#ifndef PENUMBRA_AFH_WORK_BINDING
#define PENUMBRA_AFH_WORK_BINDING 4      // work counters (+ the overflow count, always)
#endif
#ifndef PENUMBRA_AFH_HEADER_BINDING
#define PENUMBRA_AFH_HEADER_BINDING 5    // the lists' header (block predicate pass)
#endif
// Fixed-6 two-pass light pass (penumbra/conservative_raster's spill plan): the direct pass's
// geometry stage appends triangles that need clipping to the spill buffer and their world-space
// vertices to the spill-world buffer; the spill pass reads both. Light pass only (the predicate
// pass and the resolve use 5 and 7 for other buffers); the caster-position hook must not use them.
#ifndef PENUMBRA_AFH_SPILL_BINDING
#define PENUMBRA_AFH_SPILL_BINDING 5        // PenumbraConservativeSpillHeader + triangles
#endif
#ifndef PENUMBRA_AFH_SPILL_WORLD_BINDING
#define PENUMBRA_AFH_SPILL_WORLD_BINDING 7  // PenumbraAfhSpillWorldHeader + PenumbraAfhSpillWorld[]
#endif
// Compute light pass (AfhLightPass::Compute): the caster setup reads the casters (CasterBuffer)
// and writes one record and one tile count per triangle of the chunk; the count array is scanned
// (inclusive, in place) into each triangle's last item + 1; the tiles pass reads records, scan
// and lists. Storage bindings above the light pass's, so that none is rebound between passes.
#ifndef PENUMBRA_AFH_CASTER_POSITIONS_BINDING
#define PENUMBRA_AFH_CASTER_POSITIONS_BINDING 8  // float[]: CasterBuffer::positions
#endif
#ifndef PENUMBRA_AFH_CASTER_INDICES_BINDING
#define PENUMBRA_AFH_CASTER_INDICES_BINDING 9    // uint[]: CasterBuffer::indices
#endif
#ifndef PENUMBRA_AFH_TRIANGLES_BINDING
#define PENUMBRA_AFH_TRIANGLES_BINDING 10  // uint[PENUMBRA_AFH_TRIANGLE_WORDS * chunk]: per-triangle records
#endif
#ifndef PENUMBRA_AFH_ITEMS_BINDING
#define PENUMBRA_AFH_ITEMS_BINDING 11      // uint[chunk]: tiles per triangle, then their inclusive scan
#endif
#ifndef PENUMBRA_AFH_ARGS_BINDING
#define PENUMBRA_AFH_ARGS_BINDING 12       // uint[PENUMBRA_AFH_ARGS_WORDS]: the tiles pass's dispatch
#endif
// The compute light pass's work items: one work group per (triangle, tile of its texel box), a
// tile PENUMBRA_AFH_TILE_WIDTH x PENUMBRA_AFH_TILE_HEIGHT texels, one invocation per texel.
#define PENUMBRA_AFH_TILE_WIDTH 8
#define PENUMBRA_AFH_TILE_HEIGHT 8
#define PENUMBRA_AFH_SETUP_GROUP 64
// A triangle record: words 0-8 the world vertices (float bits, as read from the caster hook),
// 9 = first texel (x | y << 16), 10 = last texel (x | y << 16), 11 = tiles per row of its box,
// 12-15 the emitter's pixel-expanded box (float bits: xmin, ymin, xmax, ymax), 16-21 the
// unclipped triangle in pixels (float bits, counter-clockwise), 22 = the dilation h (float bits;
// 0 = no triangle test: clipped or thin, the box alone), 23 unused.
#define PENUMBRA_AFH_TRIANGLE_WORDS 24
// The args buffer: per list block b (< 64) words 4 b .. 4 b + 2 = the x, y, z groups of block b's
// tiles pass (glDispatchComputeIndirect; 0 groups where no list reaches block b), 4 b + 3 = the
// chunk's items.
#define PENUMBRA_AFH_ARGS_WORDS 256

// Resolve bindings.
#ifndef PENUMBRA_AFH_SLOTS_BINDING
#define PENUMBRA_AFH_SLOTS_BINDING 5
#endif
#ifndef PENUMBRA_AFH_TEXELS_BINDING
#define PENUMBRA_AFH_TEXELS_BINDING 6
#endif
#ifndef PENUMBRA_AFH_STATES_BINDING
#define PENUMBRA_AFH_STATES_BINDING 7
#endif

// Per-view-sample result of the resolve (one uint per sample id).
#define PENUMBRA_AFH_LIT 0u
#define PENUMBRA_AFH_SHADOWED 1u
#define PENUMBRA_AFH_BACK_FACING 2u  // light-back-facing: dark by shading (sintorn2008 Fig. 2)
#define PENUMBRA_AFH_NO_SAMPLE 3u    // background pixel
#define PENUMBRA_AFH_UNTESTED 4u     // outside the light frustum, non-finite, or beyond the list blocks
                                     // the light pass walks (AliasFreeHardOptions::max_list_blocks)

// Light-pass flags (params.grid.w).
#define PENUMBRA_AFH_FLAG_CLOSED 1u  // the draw's casters are closed meshes: only light-back-facing cast
#define PENUMBRA_AFH_FLAG_CLOSED_LIGHT_FACING 2u  // closed meshes: triangles with the light strictly behind are culled

// Work counters (words of the work buffer). OVERFLOW is always counted (by the resolve).
#define PENUMBRA_AFH_WORK_FRAGMENTS 0
#define PENUMBRA_AFH_WORK_TESTS 1
#define PENUMBRA_AFH_WORK_TRIANGLES 2
#define PENUMBRA_AFH_WORK_OVERFLOW 3  // samples left untested past the last list block
#define PENUMBRA_AFH_WORK_FALLBACKS 4 // filtered exact test: sign decisions that needed fp64
// Fixed-6 two-pass light pass, always (copied from list block 0's spill header on the GPU):
#define PENUMBRA_AFH_WORK_SPILL_COUNT 5     // header.count = 3 * triangles the spill pass drew
#define PENUMBRA_AFH_WORK_SPILL_OVERFLOW 6  // header.overflow = triangles lost (spill array full)
// What the skips removed (count_work): samples skip_shadowed did not retest, fragments clip_to_box
// discarded, closed casters' triangles culled (back_faces_only / light_facing_only; list block 0).
#define PENUMBRA_AFH_WORK_TESTS_SKIPPED 7
#define PENUMBRA_AFH_WORK_FRAGMENTS_SKIPPED 8
#define PENUMBRA_AFH_WORK_TRIANGLES_CULLED 9
// Compute light pass (always counted): caster triangles naming a vertex past their range's
// positions (they cast nothing), and the (triangle, tile) items the tiles pass ran.
#define PENUMBRA_AFH_WORK_CASTER_INDICES_OUT_OF_RANGE 10
#define PENUMBRA_AFH_WORK_ITEMS 11
#define PENUMBRA_AFH_WORK_WORDS 12

#ifdef __cplusplus
namespace penumbra::shared {
#endif

// std140 == std430 layout: 80 bytes (the dvec2 sits at offset 64, 16-aligned).
struct PenumbraAfhParams {
    vec4 light;      // w = 1: xyz = point light position; w = 0: xyz = unit direction towards the light
    vec4 tolerance;  // x = unused (see exact.x), y = supporting-plane offset toward the light (world
                     // units), z = directional reach (world units), w = unused. The sample is moved
                     // by the offset toward the light: it must lie farther than that behind a
                     // caster's supporting plane to be blocked (0 = exact geometry)
    uvec4 grid;      // x = W, y = H, z = list block (samples per fragment per pass), w = flags
    uvec4 pass;      // x = block index of this pass, y = sample count (resolve), z = samples per
                     // list the light pass walks (max_list_blocks * list block; resolve), w = unused
    dvec2 exact;     // x = coplanar epsilon (relative), y = scene extent E capping the segment's
                     // length in the coplanar scale (> 0, +inf = uncapped); double as the oracle's
};

// The spill-world buffer of the Fixed-6 two-pass light pass (std430): a 16-byte header, then one
// entry per spill slot. The direct pass takes entry `count++` for each triangle it spills, writes
// the triangle's world-space vertices there and stores the entry's index in the spill payload's x
// (y = the draw's flags); a triangle that finds every entry taken is not appended (header.overflow
// of the spill buffer counts it), so the two arrays always hold the same triangles.
struct PenumbraAfhSpillWorldHeader {
    uint count;  // entries handed out (may exceed the capacity: the excess overflowed)
    uint reserved0;
    uint reserved1;
    uint reserved2;
};
struct PenumbraAfhSpillWorld {
    vec4 v0;  // xyz = world-space vertex 0 as the vertex stage produced it, bit for bit; w = 0
    vec4 v1;
    vec4 v2;
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
