#version 450
// penumbra — geometry stage rasterizing each caster triangle's influence region into the light
// grid (sintorn2008 §4.1, Fig. 5): a ready entry for tests and a template for the soft-shadow light
// pass. Render into a viewport of exactly the grid (glViewport(x0, y0, W, H)); the fragments are the
// texels whose view samples the triangle may shadow.
//
// Inputs: triangles whose gl_in[i].gl_Position.xyz are WORLD positions (float; w ignored), e.g. from
// penumbra/conservative_raster/conservative_raster.vert.glsl (pass-through of attribute 0). Uniform
// block at binding PENUMBRA_INFLUENCE_PARAMS_BINDING: PenumbraInfluenceParams from
// penumbra::influenceRegionSetup (std140). Uniform location 8 = id of the draw's first triangle.
// Defines: the setup's (PENUMBRA_INFLUENCE_SIDES, PENUMBRA_INFLUENCE_CUT).
// Outputs per vertex: gl_Position (z = 0, w = 1), flat location 0 = triangle id.
// PENUMBRA_INFLUENCE_RECORD=1 also stores kind, fallback bits, count and the emitted polygon per
// triangle (PENUMBRA_INFLUENCE_RECORD_WORDS uints at binding PENUMBRA_INFLUENCE_RECORD_BINDING):
// tests compare them with the CPU twin bit for bit.
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=4 PENUMBRA_INFLUENCE_RECORD=1
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=6 PENUMBRA_INFLUENCE_RECORD=1
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=8 PENUMBRA_INFLUENCE_CUT=1
// penumbra-permutation: PENUMBRA_INFLUENCE_SIDES=12 PENUMBRA_INFLUENCE_CUT=1 PENUMBRA_INFLUENCE_RECORD=1
#include "penumbra/influence_region/influence_region_shared.h"

#ifndef PENUMBRA_INFLUENCE_SIDES
#define PENUMBRA_INFLUENCE_SIDES PENUMBRA_INFLUENCE_DEFAULT_SIDES
#endif
#ifndef PENUMBRA_INFLUENCE_RECORD
#define PENUMBRA_INFLUENCE_RECORD 0
#endif

layout(triangles) in;
layout(triangle_strip, max_vertices = PENUMBRA_INFLUENCE_MAX_VERTICES(PENUMBRA_INFLUENCE_SIDES)) out;

layout(std140, binding = PENUMBRA_INFLUENCE_PARAMS_BINDING) uniform PenumbraInfluenceParamsBlock {
    PenumbraInfluenceParams penumbraInfluenceParams;
};
layout(location = 8) uniform uint penumbraInfluenceFirstTriangle;

layout(location = 0) flat out uint penumbraInfluenceTriangle;

#if PENUMBRA_INFLUENCE_RECORD
layout(std430, binding = PENUMBRA_INFLUENCE_RECORD_BINDING) writeonly buffer PenumbraInfluenceRecordBlock {
    uint penumbraInfluenceRecord[];
};
#endif

#include "penumbra/influence_region/influence_region.glsl"

void main() {
    uint triangle = penumbraInfluenceFirstTriangle + uint(gl_PrimitiveIDIn);
    int count = penumbraInfluenceRegion(gl_in[0].gl_Position.xyz, gl_in[1].gl_Position.xyz, gl_in[2].gl_Position.xyz,
                                        penumbraInfluenceParams);
#if PENUMBRA_INFLUENCE_RECORD
    uint base = triangle * uint(PENUMBRA_INFLUENCE_RECORD_WORDS);
    penumbraInfluenceRecord[base + 0u] = uint(penumbraInfluenceKind);
    penumbraInfluenceRecord[base + 1u] = penumbraInfluenceFallback;
    penumbraInfluenceRecord[base + 2u] = uint(count);
    penumbraInfluenceRecord[base + 3u] = 0u;
    for (int i = 0; i < count; ++i) {
        penumbraInfluenceRecord[base + 4u + 2u * uint(i)] = floatBitsToUint(penumbraInfluenceOut[i].x);
        penumbraInfluenceRecord[base + 5u + 2u * uint(i)] = floatBitsToUint(penumbraInfluenceOut[i].y);
    }
#endif
    vec2 half_grid = 0.5 * penumbraInfluenceParams.grid.xy;
    // The convex polygon as a zig-zag strip: 0, 1, n-1, 2, n-2, ... (counter-clockwise throughout).
    for (int j = 0; j < count; ++j) {
        int index = (j & 1) != 0 ? (j + 1) >> 1 : (count - (j >> 1)) % count;
        gl_Position = vec4(penumbraInfluenceOut[index] / half_grid - 1.0, 0.0, 1.0);
        penumbraInfluenceTriangle = triangle;
        EmitVertex();
    }
    EndPrimitive();
}
