// penumbra — deep shadow map build, fragment stage: one fragment per (caster triangle, light texel
// its conservative hull touches); tests the texel's S sub-samples against the triangle (the twin:
// buildDsmFragmentsCpu). PENUMBRA_DSM_PASS 0 counts fragments per sub-sample list (atomicAdd), 1
// scatters them to offsets[list] + cursor (the sample-list pattern: count, scan, scatter). Opacity
// per mesh, per triangle, per vertex or from the hook (opacity_hook.glsl). No colour output: bind a
// framebuffer with no attachments, R x R.
// penumbra-permutation: PENUMBRA_DSM_PASS=0 PENUMBRA_DSM_CHANNELS=1
// penumbra-permutation: PENUMBRA_DSM_PASS=1 PENUMBRA_DSM_CHANNELS=1
// penumbra-permutation: PENUMBRA_DSM_PASS=1 PENUMBRA_DSM_CHANNELS=3
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"
#include "penumbra/deep_shadow_map/deep_shadow_map.glsl"
#include "penumbra/deep_shadow_map/opacity_hook.glsl"

#ifndef PENUMBRA_DSM_PASS
#error penumbra/deep_shadow_map/raster.frag.glsl needs PENUMBRA_DSM_PASS (0 count, 1 scatter)
#endif
#ifndef PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_CHANNELS 1
#endif

layout(std140, binding = PENUMBRA_DSM_BINDING_PARAMS) uniform PenumbraDsmParamsBlock { PenumbraDsmParams penumbraDsmParams; };
layout(std430, binding = PENUMBRA_DSM_BINDING_PATTERNS) readonly buffer PenumbraDsmPatterns { vec2 penumbraDsmPatterns[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_COUNTS) buffer PenumbraDsmCounts { uint penumbraDsmCounts[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_CURSOR) buffer PenumbraDsmCursor { uint penumbraDsmCursor[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_RECORDS) writeonly buffer PenumbraDsmRecords { uvec4 penumbraDsmRecords[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_TRIANGLE_OPACITY) readonly buffer PenumbraDsmTriangleOpacity { vec4 penumbraDsmTriangleOpacity[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_STATUS) buffer PenumbraDsmStatus { uint penumbraDsmStatus[]; };

layout(location = 0) flat in vec3 penumbraDsmN0;
layout(location = 1) flat in vec3 penumbraDsmN1;
layout(location = 2) flat in vec3 penumbraDsmN2;
layout(location = 3) flat in vec3 penumbraDsmD;
layout(location = 4) flat in uint penumbraDsmTriangleId;
layout(location = 5) flat in vec3 penumbraDsmA0;
layout(location = 6) flat in vec3 penumbraDsmA1;
layout(location = 7) flat in vec3 penumbraDsmA2;

void main() {
    uint R = penumbraDsmParams.size.x, S = penumbraDsmParams.size.y;
    uint x = uint(gl_FragCoord.x), y = uint(gl_FragCoord.y);
    if (x >= R || y >= R) return;
    uint pattern = penumbraDsmPattern(x, y);
    float scale = penumbraDsmParams.numbers.x;
    uint source = penumbraDsmParams.flags.x;
    for (uint j = 0u; j < S; ++j) {
        vec2 o = penumbraDsmPatterns[pattern * S + j];
        precise float sx = float(x) + o.x;
        precise float sy = float(y) + o.y;
        precise float px = sx * scale - 1.0;
        precise float py = sy * scale - 1.0;
        float e0 = penumbraDsmEdge(penumbraDsmN0, px, py);
        float e1 = penumbraDsmEdge(penumbraDsmN1, px, py);
        float e2 = penumbraDsmEdge(penumbraDsmN2, px, py);
        precise float sum = (e0 + e1) + e2;
        if (!penumbraDsmEdgeCovers(e0, penumbraDsmN0) || !penumbraDsmEdgeCovers(e1, penumbraDsmN1) ||
            !penumbraDsmEdgeCovers(e2, penumbraDsmN2) || !(sum > 0.0))
            continue;
        uint list = (y * R + x) * S + j;
#if PENUMBRA_DSM_PASS == 0
        atomicAdd(penumbraDsmCounts[list], 1u);
#else
        float z = penumbraDsmInterpolate(e0, e1, e2, penumbraDsmD.x, penumbraDsmD.y, penumbraDsmD.z);
        vec3 a;
        if (source == uint(PENUMBRA_DSM_OPACITY_HOOK)) {
            vec3 coordinates = vec3(penumbraDsmInterpolate(e0, e1, e2, penumbraDsmA0.x, penumbraDsmA1.x, penumbraDsmA2.x),
                                  penumbraDsmInterpolate(e0, e1, e2, penumbraDsmA0.y, penumbraDsmA1.y, penumbraDsmA2.y),
                                  penumbraDsmInterpolate(e0, e1, e2, penumbraDsmA0.z, penumbraDsmA1.z, penumbraDsmA2.z));
            a = penumbraDsmOpacityHook(penumbraDsmTriangleId, coordinates);
            // [0, 1] per channel, NaN -> 0 (the twin's detail::dsmClampOpacity).
            for (int c = 0; c < 3; ++c) a[c] = a[c] >= 0.0 ? min(a[c], 1.0) : 0.0;
        } else if (source == uint(PENUMBRA_DSM_OPACITY_VERTEX)) {
            a = vec3(penumbraDsmInterpolate(e0, e1, e2, penumbraDsmA0.x, penumbraDsmA1.x, penumbraDsmA2.x),
                     penumbraDsmInterpolate(e0, e1, e2, penumbraDsmA0.y, penumbraDsmA1.y, penumbraDsmA2.y),
                     penumbraDsmInterpolate(e0, e1, e2, penumbraDsmA0.z, penumbraDsmA1.z, penumbraDsmA2.z));
        } else if (source == uint(PENUMBRA_DSM_OPACITY_TRIANGLE)) {
            a = penumbraDsmTriangleOpacity[penumbraDsmTriangleId].xyz;
        } else {
            a = penumbraDsmParams.opacity.xyz;
        }
        uint slot = penumbraDsmCounts[list] + atomicAdd(penumbraDsmCursor[list], 1u);
        if (slot >= penumbraDsmParams.capacity.x) {
            atomicAdd(penumbraDsmStatus[PENUMBRA_DSM_STATUS_FRAGMENT_OVERFLOW], 1u);
            continue;
        }
#if PENUMBRA_DSM_CHANNELS == 3
        penumbraDsmRecords[2u * slot] = uvec4(floatBitsToUint(z), penumbraDsmTriangleId, floatBitsToUint(a.x), floatBitsToUint(a.y));
        penumbraDsmRecords[2u * slot + 1u] = uvec4(floatBitsToUint(a.z), 0u, 0u, 0u);
#else
        penumbraDsmRecords[slot] = uvec4(floatBitsToUint(z), penumbraDsmTriangleId, floatBitsToUint(a.x), 0u);
#endif
#endif
    }
}
