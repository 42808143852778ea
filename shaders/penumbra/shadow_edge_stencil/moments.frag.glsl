// penumbra — shadow-edge stencil, Chebyshev moment map, fragment stage: one fragment per (caster
// triangle, texel of its conservative hull); where the triangle overlaps the texel
// (penumbraAaDepthTexel, the twin detail::aaDepthTexel) the texel keeps the least depth and the
// least cover value over all triangles (atomicMin on order-preserving bits of the floats).
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h"
#include "penumbra/shadow_edge_stencil/shadow_edge_stencil.glsl"

layout(std140, binding = PENUMBRA_AA_BINDING_PARAMS) uniform PenumbraAaParamsBlock { PenumbraAaParams penumbraAaParams; };
layout(std430, binding = PENUMBRA_AA_BINDING_MIN_DEPTH) buffer PenumbraAaMinDepth { uint penumbraAaMinDepth[]; };
layout(std430, binding = PENUMBRA_AA_BINDING_MIN_COVER) buffer PenumbraAaMinCover { uint penumbraAaMinCover[]; };

layout(location = 0) flat in dvec2 penumbraAaS0;
layout(location = 1) flat in dvec2 penumbraAaS1;
layout(location = 2) flat in dvec2 penumbraAaS2;
layout(location = 3) flat in dvec2 penumbraAaS3;
layout(location = 4) flat in dvec4 penumbraAaPlane;
layout(location = 6) flat in dvec4 penumbraAaRange;
layout(location = 8) flat in dvec4 penumbraAaBox;

void main() {
    uint gw = penumbraAaParams.grid.x, gh = penumbraAaParams.grid.y;
    int x = int(gl_FragCoord.x), y = int(gl_FragCoord.y);
    if (x < 0 || y < 0 || x >= int(gw) || y >= int(gh)) return;
    PenumbraAaDepthTriangle t;
    t.s[0] = dvec3(penumbraAaS0, 0.0lf);
    t.s[1] = dvec3(penumbraAaS1, 0.0lf);
    t.s[2] = dvec3(penumbraAaS2, 0.0lf);
    t.s[3] = dvec3(penumbraAaS3, 0.0lf);
    t.ga = penumbraAaPlane.x;
    t.gb = penumbraAaPlane.y;
    t.g0 = penumbraAaPlane.z;
    t.dmin = penumbraAaPlane.w;
    t.dmax = penumbraAaRange.x;
    t.orientation = penumbraAaRange.y;
    t.count = int(penumbraAaRange.z);
    t.lo = penumbraAaBox.xy;
    t.hi = penumbraAaBox.zw;
    double d, c;
    if (!penumbraAaDepthTexel(t, x, y, d, c)) return;
    uint texel = uint(y) * gw + uint(x);
    atomicMin(penumbraAaMinDepth[texel], penumbraAaOrderedBits(float(d)));
    if (!isinf(c)) atomicMin(penumbraAaMinCover[texel], penumbraAaOrderedBits(float(c)));
}
