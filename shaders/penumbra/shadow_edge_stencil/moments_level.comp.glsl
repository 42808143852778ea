// penumbra — shadow-edge stencil, Chebyshev moment map: PENUMBRA_AA_PASS 0 writes level 0 from
// the atomics (E(x) = the least depth d as a float, E(x^2) = d * d in double rounded once; the
// cover value); 1 writes level moments.w from the level above: the mean of its 2x2 (odd sizes
// repeat the last row or column; sums in double, rounded once) and the largest cover value. The
// twin: conservativeMomentMapCpu. One invocation per texel of the level written.
// penumbra-permutation: PENUMBRA_AA_PASS=0
// penumbra-permutation: PENUMBRA_AA_PASS=1
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"

#ifndef PENUMBRA_AA_PASS
#error penumbra/shadow_edge_stencil/moments_level.comp.glsl needs PENUMBRA_AA_PASS (0 level 0, 1 a mip level)
#endif

layout(local_size_x = PENUMBRA_AA_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_MIN_DEPTH) readonly buffer PenumbraAaMinDepth { uint penumbraAaMinDepth[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_MIN_COVER) readonly buffer PenumbraAaMinCover { uint penumbraAaMinCover[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_MOMENTS) buffer PenumbraAaMoments { vec2 penumbraAaMoments[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_COVERS) buffer PenumbraAaCovers { float penumbraAaCovers[]; };

uint penumbraAaLevelWidth(uint l) { return max(1u, penumbraAaParams.grid.x >> l); }
uint penumbraAaLevelHeight(uint l) { return max(1u, penumbraAaParams.grid.y >> l); }
uint penumbraAaLevelOffset(uint l) {
    uint offset = 0u;
    for (uint j = 0u; j < l; ++j) offset += penumbraAaLevelWidth(j) * penumbraAaLevelHeight(j);
    return offset;
}

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
#if PENUMBRA_AA_PASS == 0
    if (i >= penumbraAaParams.grid.x * penumbraAaParams.grid.y) return;
    float d = penumbraAaFromOrderedBits(penumbraAaMinDepth[i]);
    precise double dd = double(d) * double(d);
    penumbraAaMoments[i] = vec2(d, float(dd));
    penumbraAaCovers[i] = penumbraAaFromOrderedBits(penumbraAaMinCover[i]);
#else
    uint l = penumbraAaParams.moments.w;
    uint w = penumbraAaLevelWidth(l), h = penumbraAaLevelHeight(l), pw = penumbraAaLevelWidth(l - 1u), ph = penumbraAaLevelHeight(l - 1u);
    if (i >= w * h) return;
    uint x = i % w, y = i / w, from = penumbraAaLevelOffset(l - 1u);
    double sx = 0.0lf, sy = 0.0lf;
    float covered = uintBitsToFloat(0xff800000u);  // -inf
    for (uint k = 0u; k < 4u; ++k) {
        uint tx = min(pw - 1u, 2u * x + (k & 1u)), ty = min(ph - 1u, 2u * y + (k >> 1u));
        vec2 m = penumbraAaMoments[from + ty * pw + tx];
        precise double nx = sx + double(m.x);
        precise double ny = sy + double(m.y);
        sx = nx;
        sy = ny;
        covered = max(covered, penumbraAaCovers[from + ty * pw + tx]);
    }
    precise double mx = sx * 0.25lf;
    precise double my = sy * 0.25lf;
    uint to = penumbraAaLevelOffset(l);
    penumbraAaMoments[to + i] = vec2(float(mx), float(my));
    penumbraAaCovers[to + i] = covered;
#endif
}
