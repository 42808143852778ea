// penumbra — influence region (sintorn2008 §4.1, Fig. 5): constants and the parameter block shared
// by C++ and GLSL (valid as both; host code includes penumbra/detail/shared.hpp first, which maps
// vec4/uvec4 to GLM). std140/std430-safe: vec4/uvec4 members only, size static_asserted in
// include/penumbra/influence_region.hpp.
#ifndef PENUMBRA_INFLUENCE_REGION_SHARED_H
#define PENUMBRA_INFLUENCE_REGION_SHARED_H

// Sides k of the regular polygon circumscribing the light's silhouette at each caster vertex:
// 4, 6 (the seed's hexagon, the default), 8 or 12.
#define PENUMBRA_INFLUENCE_MAX_SIDES 12
#define PENUMBRA_INFLUENCE_DEFAULT_SIDES 6
// 3k points per triangle; the hull of 3k points has at most 3k vertices, the supporting-plane cut
// adds at most one, and the dilation by the pixel square at most four (one per quadrant change).
#define PENUMBRA_INFLUENCE_MAX_POINTS(k) (3 * (k))
#define PENUMBRA_INFLUENCE_MAX_POLYGON(k) (3 * (k) + 1)
#define PENUMBRA_INFLUENCE_MAX_VERTICES(k) (3 * (k) + 5)

// What happened to a triangle (PenumbraInfluenceRegion kind; the CPU twin's InfluenceRegionKind).
#define PENUMBRA_INFLUENCE_KIND_DROPPED 0     // NaN/Inf vertex: nothing emitted
#define PENUMBRA_INFLUENCE_KIND_CULLED 1      // beyond the far plane, cut away, or off the grid
#define PENUMBRA_INFLUENCE_KIND_HULL 2        // the dilated convex hull
#define PENUMBRA_INFLUENCE_KIND_BOX 3         // pixel-expanded bounding box (degenerate hull)
#define PENUMBRA_INFLUENCE_KIND_WHOLE_GRID 4  // documented fallback: every texel of the grid

// Why a triangle fell back to the whole grid (bits; several may be set).
#define PENUMBRA_INFLUENCE_FALLBACK_BEYOND_FAR 1u     // a vertex on/beyond the far plane (not all)
#define PENUMBRA_INFLUENCE_FALLBACK_INSIDE_LIGHT 2u   // a vertex inside the light's (inflated) bounding sphere
#define PENUMBRA_INFLUENCE_FALLBACK_VERTEX 4u         // a vertex at/behind the light's eye plane or projecting
                                                      // outside the guard band
#define PENUMBRA_INFLUENCE_FALLBACK_RAY 8u            // a polygon ray does not reach the far plane, heads
                                                      // back towards the eye plane, or its vanishing point
                                                      // lies outside the guard band

// Config bits (PenumbraInfluenceParams::config.y).
#define PENUMBRA_INFLUENCE_CONFIG_CUT 1u

// Default binding points of the entry shaders (the snippet binds nothing).
#define PENUMBRA_INFLUENCE_PARAMS_BINDING 0
#define PENUMBRA_INFLUENCE_COVERAGE_BINDING 0   // frag entry: uint bitset of the grid + counters
#define PENUMBRA_INFLUENCE_RECORD_BINDING 1     // geom entry with PENUMBRA_INFLUENCE_RECORD=1
// Record layout per triangle (uint words): [0] kind, [1] fallback bits, [2] vertex count, [3] 0,
// then PENUMBRA_INFLUENCE_MAX_VERTICES(12) vec2 as uint bit pairs.
#define PENUMBRA_INFLUENCE_RECORD_WORDS (4 + 2 * PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_MAX_SIDES))

/// Everything the snippet needs for one light and one light grid; fill it with
/// penumbra::influenceRegionSetup() (never by hand: the margins follow from the grid).
/// "Local" is the light's normalised space (penumbra::LightFrame): the light lies in the unit ball.
struct PenumbraInfluenceParams {
    vec4 center;            // xyz: light centre (world, float); w: 0
    vec4 to_local[3];       // rows of S^-1 R^T: local = to_local * (world - center); w: 0
    vec4 to_pixel[3];       // rows x, y, w of grid-pixel homogeneous coordinates from local (q, 1):
                            // pixel = (row0 . (q,1), row1 . (q,1)) / row2 . (q,1), in [0, W] x [0, H]
    vec4 cut_lines[3];      // rows of inverse(to_pixel linear part)^T: the cut line of a local plane
                            // normal n is (cut_lines * n) . (x, y, 1)
    vec4 far_plane;         // local far plane: xyz unit normal, w offset; dot(n, q) + w < 0 on the light side
    vec4 grid;              // x: W, y: H, z: guard bound B (|x|, |y| <= B w), w: margin (px)
    vec4 expansion;         // x: h = 0.5 + margin, y: 1 + inflation0, z: inflation per local unit, w: inside threshold^2
    vec4 polygon;           // x: 1 / cos(pi / k), y: cut clearance (local radii), z: cut clearance per unit, w: 0
    vec4 directions[6];     // (cos, sin) of 2 pi j / k, two per vec4 (j = 0..k-1)
    uvec4 config;           // x: k, y: config bits (PENUMBRA_INFLUENCE_CONFIG_*), z, w: 0
};

#endif
