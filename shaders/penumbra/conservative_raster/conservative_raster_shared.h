// penumbra — conservative raster: constants and the parameter block shared by C++ and GLSL
// (valid as both; host code includes penumbra/detail/shared.hpp first, which maps vec4 to GLM).
// std140/std430-safe: vec4 members only, sizes static_asserted in conservative_raster.hpp.
#ifndef PENUMBRA_CONSERVATIVE_RASTER_SHARED_H
#define PENUMBRA_CONSERVATIVE_RASTER_SHARED_H

// Largest polygon the emitter handles: a triangle clipped by the near plane, w >= min_w and the
// four guard-band planes (each plane adds at most one vertex).
#define PENUMBRA_CONSERVATIVE_MAX_POLYGON 9
// Largest emitted triangle strip of the single-pass emitter (and of the spill pass): the exact hull
// of an n-gon dilated by an axis-aligned square has at most n + 4 vertices (7 for a triangle; GPU
// Gems 2 ch. 42 budgets 9 because it emits 3 per corner, duplicates included). The clipping path
// emits the exact hull of the clipped polygon, so one bound serves both variants.
#define PENUMBRA_CONSERVATIVE_MAX_VERTICES 13
// The Fixed-6 direct pass (PENUMBRA_CONSERVATIVE_DIRECT=1) declares the seed's 6 (sintorn2008 §3.2:
// the declared GS output size sets GS throughput): an unclipped triangle emits 6, a thin one a
// hexagon (6) or a square (4); every triangle that needs clipping (near plane, w >= min_w, guard
// band) is appended to the spill buffer instead and drawn by the spill pass.
#define PENUMBRA_CONSERVATIVE_FIXED6_MAX_VERTICES 6

// Coverage recorder used by the tests, the benchmark and integrators checking their driver: each
// triangle owns a 32 x 32 pixel tile (one uint per row, bit x = column x) followed by two
// counters: all fragments, and fragments that fell outside the tile.
#define PENUMBRA_CONSERVATIVE_RECORD_TILE 32
#define PENUMBRA_CONSERVATIVE_RECORD_WORDS 34
#define PENUMBRA_CONSERVATIVE_RECORD_FRAGMENTS 32
#define PENUMBRA_CONSERVATIVE_RECORD_OUTSIDE 33

// Default binding points of the entry shaders (the snippets themselves bind nothing).
#define PENUMBRA_CONSERVATIVE_PARAMS_BINDING 0
#define PENUMBRA_CONSERVATIVE_RECORD_WORDS_BINDING 0
#define PENUMBRA_CONSERVATIVE_RECORD_TILES_BINDING 1
#define PENUMBRA_CONSERVATIVE_RECORD_CLIP_BINDING 2
#define PENUMBRA_CONSERVATIVE_SPILL_BINDING 3

/// Everything the emitter needs to know about one viewport; fill it with
/// penumbra::conservativeRasterSetup() (never by hand: the margins follow from the viewport).
struct PenumbraConservativeParams {
    vec4 viewport;    // x0, y0, width, height in window pixels (what glViewport was given)
    vec4 near_plane;  // clip-space half-space that is kept: dot(near_plane, clip) >= 0
    vec4 expansion;   // x: half size h = 0.5 + margin, y: margin, z: thin threshold tau0 (px),
                      // w: thin threshold per pixel of triangle diameter
    vec4 clipping;    // x: guard band G (px), y: 1 + 2G/width, z: 1 + 2G/height, w: min_w
    vec4 depth;       // x, y: NDC z range GL clips to (-1, 1; or 0, 1 under GL_ZERO_TO_ONE); z, w: 0
};

/// The spill buffer's header (std430, at the start of the spill range; 32 bytes). Its first four
/// words ARE the DrawArraysIndirectCommand of the spill pass, so the pass needs no compute step:
/// glDrawArraysIndirect(GL_TRIANGLES, offset of the header). Write
/// penumbra::ConservativeSpillPlan::reset here before every direct pass.
struct PenumbraConservativeSpillHeader {
    uint count;           // 3 * stored triangles (an append that overflows adds 3 and takes it back)
    uint instance_count;  // 1
    uint first;           // 0
    uint base_instance;   // 0
    uint capacity;        // triangles the array after the header holds (from the setup)
    uint overflow;        // triangles that needed the spill pass but found the array full (lost)
    uint reserved0;       // 0
    uint reserved1;       // 0
};

/// One spilled triangle (std430, 64 bytes): the clip coordinates the direct pass's geometry stage
/// received, bit for bit, and a payload the integrator chooses (the ready entries: x = the
/// triangle id; y, z, w = 0). The array starts 32 bytes after the header.
struct PenumbraConservativeSpillTriangle {
    vec4 clip0;
    vec4 clip1;
    vec4 clip2;
    uvec4 payload;
};

#endif
