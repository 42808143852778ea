// penumbra — alias-free hard shadows, the compute light pass's caster setup
// (AfhLightPass::Compute): one invocation per caster triangle does what the raster light pass's
// vertex and geometry stages do, without drawing: the culls (cull.glsl), the light's clip
// coordinates, and the conservative emitter's pixel-expanded box (conservative_raster.glsl with
// PENUMBRA_CONSERVATIVE_BOX_ONLY: the same bits as the geometry stage's). It writes the
// triangle's record (world vertices, the texels whose centres the box holds, the box and, for an
// unclipped triangle that is not thin, the triangle in pixels and the hull's dilation) and its
// count of tiles of that texel range for the tiles pass (light_pass_tiles.comp.glsl); a culled or
// dropped triangle counts 0 tiles. The triangles come from the caster hook (caster_buffer.glsl).
// Defines: the conservative emitter's (PENUMBRA_CONSERVATIVE_EXACT does not change the box),
// PENUMBRA_AFH_COUNT_WORK.
// penumbra-permutation: PENUMBRA_AFH_COUNT_WORK=1
// penumbra-permutation: PENUMBRA_AFH_COUNT_WORK=0
#include "penumbra/conservative_raster/conservative_raster_shared.h"
#include "penumbra/sample_lists/sample_lists_shared.h"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"
#include "penumbra/alias_free_hard/cull.glsl"

#ifndef PENUMBRA_AFH_COUNT_WORK
#define PENUMBRA_AFH_COUNT_WORK 0
#endif
#define PENUMBRA_CONSERVATIVE_BOX_ONLY 1
#define PENUMBRA_CONSERVATIVE_DIRECT 0

layout(local_size_x = PENUMBRA_AFH_SETUP_GROUP) in;

layout(std140, binding = PENUMBRA_CONSERVATIVE_PARAMS_BINDING) uniform PenumbraConservativeParamsBlock {
    PenumbraConservativeParams penumbraConservativeParams;
};
layout(std140, binding = PENUMBRA_AFH_PARAMS_BINDING) uniform PenumbraAfhParamsBlock {
    PenumbraAfhParams penumbraAfhParams;
};
layout(std140, binding = PENUMBRA_AFH_FRUSTUM_BINDING) uniform PenumbraAfhFrustumBlock {
    PenumbraSampleListsFrustum penumbraAfhFrustum;
};
layout(std430, binding = PENUMBRA_AFH_WORK_BINDING) buffer PenumbraAfhWork { uint penumbraAfhWork[]; };
layout(std430, binding = PENUMBRA_AFH_TRIANGLES_BINDING) writeonly buffer PenumbraAfhTriangles { uint penumbraAfhTriangles[]; };
layout(std430, binding = PENUMBRA_AFH_ITEMS_BINDING) writeonly buffer PenumbraAfhItems { uint penumbraAfhItems[]; };

// The caster hook is the soft pipeline's (one CasterBuffer format for both exact pipelines), at
// this pipeline's bindings; replace penumbra/sample_based_soft/caster_buffer.glsl in the
// ShaderLibrary for packed, skinned or instanced positions.
#define PENUMBRA_SBS_CASTER_POSITIONS_BINDING PENUMBRA_AFH_CASTER_POSITIONS_BINDING
#define PENUMBRA_SBS_CASTER_INDICES_BINDING PENUMBRA_AFH_CASTER_INDICES_BINDING
#include "penumbra/sample_based_soft/caster_buffer.glsl"
#include "penumbra/conservative_raster/conservative_raster.glsl"
#include "penumbra/conservative_raster/conservative_raster_clip.glsl"

layout(location = 2) uniform uint penumbraAfhChunkBase;  // this dispatch's first record in the chunk

void main() {
    const uint t = gl_GlobalInvocationID.x;
    if (t >= penumbraSbsCasterRange.y) return;
    const uint record = penumbraAfhChunkBase + t;
    penumbraAfhItems[record] = 0u;
    vec3 v[3];
    if (!penumbraSbsCasterTriangle(penumbraSbsCasterRange.x + t, v)) {
        atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_CASTER_INDICES_OUT_OF_RANGE], 1u);
        return;
    }
    const int cull = penumbraAfhCull(v[0], v[1], v[2], penumbraAfhParams.light, penumbraAfhParams.grid.w);
    if (cull != PENUMBRA_AFH_CULL_NONE) {
#if PENUMBRA_AFH_COUNT_WORK
        if (cull == PENUMBRA_AFH_CULL_CLOSED) atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TRIANGLES_CULLED], 1u);
#endif
        return;
    }
    // The vertex stage's projection (light_pass.vert.glsl), then the emitter's box.
    const mat4 m = penumbraAfhFrustum.view_projection;
    if (penumbraConservativeEmit(m * vec4(v[0], 1.0), m * vec4(v[1], 1.0), m * vec4(v[2], 1.0), penumbraConservativeParams) == 0)
        return;
    const vec4 box = penumbraConservativeBoxOut;
    // Texels whose centre the box may hold (the tiles pass applies the fragment stage's box test).
    const ivec4 texels = penumbraConservativeBoxPixels(box, ivec4(0, 0, ivec2(penumbraAfhParams.grid.xy)));
    const ivec2 lo = texels.xy, hi = texels.zw;
    if (any(lessThan(hi, lo))) return;
    const uvec2 tiles = (uvec2(hi - lo) + uvec2(PENUMBRA_AFH_TILE_WIDTH, PENUMBRA_AFH_TILE_HEIGHT)) /
                        uvec2(PENUMBRA_AFH_TILE_WIDTH, PENUMBRA_AFH_TILE_HEIGHT);
    const uint base = record * uint(PENUMBRA_AFH_TRIANGLE_WORDS);
    for (uint i = 0u; i < 3u; ++i) {
        penumbraAfhTriangles[base + 3u * i] = floatBitsToUint(v[i].x);
        penumbraAfhTriangles[base + 3u * i + 1u] = floatBitsToUint(v[i].y);
        penumbraAfhTriangles[base + 3u * i + 2u] = floatBitsToUint(v[i].z);
    }
    penumbraAfhTriangles[base + 9u] = uint(lo.x) | (uint(lo.y) << 16);
    penumbraAfhTriangles[base + 10u] = uint(hi.x) | (uint(hi.y) << 16);
    penumbraAfhTriangles[base + 11u] = tiles.x;
    penumbraAfhTriangles[base + 12u] = floatBitsToUint(box.x);
    penumbraAfhTriangles[base + 13u] = floatBitsToUint(box.y);
    penumbraAfhTriangles[base + 14u] = floatBitsToUint(box.z);
    penumbraAfhTriangles[base + 15u] = floatBitsToUint(box.w);
    for (int i = 0; i < 3; ++i) {
        penumbraAfhTriangles[base + 16u + 2u * uint(i)] = floatBitsToUint(penumbraConservativePolygon[i].x);
        penumbraAfhTriangles[base + 17u + 2u * uint(i)] = floatBitsToUint(penumbraConservativePolygon[i].y);
    }
    penumbraAfhTriangles[base + 22u] = floatBitsToUint(penumbraConservativeBoxTriangle ? penumbraConservativeBoxDilation : 0.0);
    penumbraAfhItems[record] = tiles.x * tiles.y;
#if PENUMBRA_AFH_COUNT_WORK
    atomicAdd(penumbraAfhWork[PENUMBRA_AFH_WORK_TRIANGLES], 1u);
#endif
}
