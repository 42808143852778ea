// penumbra — projecting a view sample into the light's grid (sintorn2008 §3, Fig. 2 and §3.1):
// the one place that decides whether a sample enters the lists and in which texel. The host's CPU
// twin (penumbra::detail::classifySample in include/penumbra/sample_lists.hpp) performs the very
// same float32 operations in the same order, and `precise` keeps the driver from fusing them into
// FMAs, so GPU and CPU agree bit for bit on every sample, texel borders included (on drivers whose
// float32 add/mul/div are correctly rounded, as llvmpipe's are; GLSL only promises 2.5 ULP for
// division, so on such hardware a sample within an ULP of a border may land in the neighbour).
//
// No hooks: everything comes in as arguments (PenumbraSampleListsParams fields), so integrators
// can classify samples in their own passes too.
#ifndef PENUMBRA_SAMPLE_LISTS_PROJECT_GLSL
#define PENUMBRA_SAMPLE_LISTS_PROJECT_GLSL

#include "penumbra/sample_lists/sample_lists_shared.h"

// NaN or +-Inf, decided on the bits so no fast-math assumption can fold it away.
bool penumbraSampleListsNonFinite(float x) {
    return (floatBitsToUint(x) & 0x7F800000u) == 0x7F800000u;
}

bool penumbraSampleListsNonFinite(vec3 v) {
    return penumbraSampleListsNonFinite(v.x) || penumbraSampleListsNonFinite(v.y) ||
           penumbraSampleListsNonFinite(v.z);
}

// m * vec4(p, 1) as ((m0 x + m1 y) + m2 z) + m3, never fused (the host does the same).
vec4 penumbraSampleListsTransform(mat4 m, vec3 p) {
    precise vec4 c = m[0] * p.x;
    c = c + m[1] * p.y;
    c = c + m[2] * p.z;
    c = c + m[3];
    return c;
}

// The world position of view pixel `pixel` from its window depth (glDepthRange(0, 1)); w = 0
// marks background (depth == 1.0, the cleared far plane). `viewInverse` = inverse of the view's
// view-projection; `depthZeroToOne` selects clip z in [0, w] instead of GL's [-w, w].
vec4 penumbraSampleListsViewPosition(mat4 viewInverse, uvec2 pixel, uvec2 viewSize, float depth,
                                     bool depthZeroToOne) {
    if (depth == 1.0) return vec4(0.0);
    precise float x = (float(pixel.x) + 0.5) / float(viewSize.x) * 2.0 - 1.0;
    precise float y = (float(pixel.y) + 0.5) / float(viewSize.y) * 2.0 - 1.0;
    precise float z = depthZeroToOne ? depth : depth * 2.0 - 1.0;
    precise vec4 h = viewInverse[0] * x;
    h = h + viewInverse[1] * y;
    h = h + viewInverse[2] * z;
    h = h + viewInverse[3];
    precise vec3 p = h.xyz / h.w;
    return vec4(p, 1.0);
}

// Light-texture coordinates `t` of an accepted sample (inside: 0 <= t.x, t.y, t.z <= t.w).
// Returns the list (texel) index y * W + x, or PENUMBRA_SAMPLE_LISTS_REJECTED + reason, the
// first of these that applies:
//   BACKGROUND  position.w == 0 (no surface)
//   NON_FINITE  a position component (or, when culling, a normal component) is NaN or Inf
//   OUTSIDE     t not finite, t.w <= 0, or x or y outside [0, t.w] (the side planes, closed)
//   DEPTH       (clip-depth flag) z outside [0, t.w]: in front of the near / beyond the far plane
//   BACK_FACING (cull flag) !(dot(n, to_light) > 0): light-back-facing samples are dark anyway
//               and must not be inserted (Fig. 2); to_light = light.xyz - p, or light.xyz when
//               light.w == 0 (directional)
// Texel rule: u = t.x / t.w in [0, 1], x = min(floor(u * W), W - 1), so a sample on an inner
// border belongs to the texel on its right/top, and u == 1 to the last texel.
uint penumbraSampleListsClassify(mat4 lightTexture, vec4 light, uvec4 grid, vec4 position, vec3 normal,
                                 out vec4 t) {
    t = vec4(0.0);
    if (position.w == 0.0) return PENUMBRA_SAMPLE_LISTS_REJECTED + PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND;
    const bool cull = (grid.w & PENUMBRA_SAMPLE_LISTS_FLAG_CULL_BACK_FACING) != 0u;
    vec3 p = position.xyz;
    if (penumbraSampleListsNonFinite(p) || (cull && penumbraSampleListsNonFinite(normal))) {
        return PENUMBRA_SAMPLE_LISTS_REJECTED + PENUMBRA_SAMPLE_LISTS_REASON_NON_FINITE;
    }
    t = penumbraSampleListsTransform(lightTexture, p);
    if (penumbraSampleListsNonFinite(t.xyz) || penumbraSampleListsNonFinite(t.w) || !(t.w > 0.0) ||
        !(t.x >= 0.0 && t.x <= t.w) || !(t.y >= 0.0 && t.y <= t.w)) {
        return PENUMBRA_SAMPLE_LISTS_REJECTED + PENUMBRA_SAMPLE_LISTS_REASON_OUTSIDE;
    }
    if ((grid.w & PENUMBRA_SAMPLE_LISTS_FLAG_CLIP_DEPTH) != 0u && !(t.z >= 0.0 && t.z <= t.w)) {
        return PENUMBRA_SAMPLE_LISTS_REJECTED + PENUMBRA_SAMPLE_LISTS_REASON_DEPTH;
    }
    if (cull) {
        precise vec3 toLight = light.w == 0.0 ? light.xyz : light.xyz - p;
        precise float facing = normal.x * toLight.x + normal.y * toLight.y;
        facing = facing + normal.z * toLight.z;
        if (!(facing > 0.0)) return PENUMBRA_SAMPLE_LISTS_REJECTED + PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING;
    }
    precise float gx = (t.x / t.w) * float(grid.x);
    precise float gy = (t.y / t.w) * float(grid.y);
    uint x = min(uint(floor(gx)), grid.x - 1u);
    uint y = min(uint(floor(gy)), grid.y - 1u);
    return y * grid.x + x;
}

// Order-preserving key of a float: a < b (as floats, -0 < +0) <=> key(a) < key(b) (as uints),
// so atomicMin / atomicMax on keys reduce floats (§4.3 fitting). penumbra::detail::orderKey twin.
uint penumbraSampleListsOrderKey(float f) {
    uint bits = floatBitsToUint(f);
    return (bits & 0x80000000u) != 0u ? ~bits : (bits | 0x80000000u);
}

#endif
