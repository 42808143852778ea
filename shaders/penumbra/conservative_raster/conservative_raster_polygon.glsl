// penumbra — the conservative emitter's sign-exact polygon helpers (sintorn2008 §3.2, Fig. 4c), a
// snippet of its own so that other polygon emitters (the influence region of §4.1,
// penumbra/influence_region/influence_region.glsl) build on the same corner code. No hooks, no
// bindings. CPU twins: penumbra::detail::conservativeFinite / conservativeCorner /
// conservativeEdgeCorner / conservativeCross (penumbra/conservative_raster.hpp).
#ifndef PENUMBRA_CONSERVATIVE_RASTER_POLYGON_GLSL
#define PENUMBRA_CONSERVATIVE_RASTER_POLYGON_GLSL

// True when no component is NaN or +-Inf (bit test: immune to fast-math folding of isnan).
bool penumbraConservativeFinite(vec4 v) {
    return all(notEqual(floatBitsToUint(v) & uvec4(0x7f800000u), uvec4(0x7f800000u)));
}

// Square corner k (in units of h): 0 = (+,-), 1 = (+,+), 2 = (-,+), 3 = (-,-). Corner k supports
// the outward normals in (k * 90° - 90°, k * 90°].
vec2 penumbraConservativeCorner(int k) {
    return vec2(k < 2 ? 1.0 : -1.0, (k == 1 || k == 2) ? 1.0 : -1.0);
}

// The corner that supports a counter-clockwise edge with direction d (outward normal (d.y, -d.x)).
// Only signs are read, and fl(b - a) has the sign of b - a: the choice is exact.
int penumbraConservativeEdgeCorner(vec2 d) {
    if (d.y > 0.0 && d.x >= 0.0) return 0;
    if (d.x < 0.0 && d.y >= 0.0) return 1;
    if (d.y < 0.0 && d.x <= 0.0) return 2;
    return 3;
}

float penumbraConservativeCross(vec2 a, vec2 b) {
    precise float r = a.x * b.y - a.y * b.x;  // precise: the twin rounds both products (no FMA)
    return r;
}

#endif
