// penumbra — conservative raster: constants and the parameter block shared by C++ and GLSL
// (valid as both; host code includes penumbra/detail/shared.hpp first, which maps vec4 to GLM).
// std140/std430-safe: vec4 members only, sizes static_asserted in conservative_raster.hpp.
#ifndef PENUMBRA_CONSERVATIVE_RASTER_SHARED_H
#define PENUMBRA_CONSERVATIVE_RASTER_SHARED_H

// Largest polygon the emitter handles: a triangle clipped by the near plane, w >= min_w and the
// four guard-band planes (each plane adds at most one vertex).
#define PENUMBRA_CONSERVATIVE_MAX_POLYGON 9
// Largest emitted triangle strip: the exact hull of an n-gon dilated by an axis-aligned square has
// at most n + 4 vertices (7 for a triangle; GPU Gems 2 ch. 42 budgets 9 because it emits 3 per
// corner, duplicates included). The fixed variant emits 6 for every unclipped triangle (sintorn2008
// §3.2) and the exact hull for clipped polygons, so one bound serves both.
#define PENUMBRA_CONSERVATIVE_MAX_VERTICES 13

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

#endif
