// penumbra — standard shadow-map lookup, the baseline the alias-free pipeline is measured against
// (benchmarks/alias_free_hard_bench.cpp; sintorn2008 §5 compares with shadow maps of growing
// size). One invocation per view sample: project the world position with the light-texture
// matrix (lightTextureMatrix(): bias * light view-projection, so x, y, z in [0, w] inside),
// fetch the nearest texel of the depth map (no filtering, no PCF) and compare. The depth bias is
// applied when the map is rendered (polygon offset), not here: the comparison is plain `>`.
// States are the alias-free pipeline's (alias_free_hard_shared.h) so the two compare directly:
//   PENUMBRA_AFH_NO_SAMPLE  position.w == 0 (background)
//   PENUMBRA_AFH_UNTESTED   behind the light (w <= 0), outside the map, or non-finite
//   PENUMBRA_AFH_SHADOWED   sample depth > map depth (depths above 1 are clamped to 1, as the
//                           map's casters are under GL_DEPTH_CLAMP)
//   PENUMBRA_AFH_LIT        otherwise
// Bindings: SSBO 0 = vec4 positions, SSBO 1 = uint states, texture unit 0 = the depth map
// (GL_DEPTH_COMPONENT*, compare mode NONE). Uniform locations: 0 = light-texture matrix,
// 1 = sample count. Dispatch foldDispatch(divUp(count, 256)).
#include "penumbra/common/dispatch.glsl"
#include "penumbra/alias_free_hard/alias_free_hard_shared.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer PenumbraShadowMapPositions { vec4 penumbraShadowMapPositions[]; };
layout(std430, binding = 1) writeonly buffer PenumbraShadowMapStates { uint penumbraShadowMapStates[]; };
layout(binding = 0) uniform sampler2D penumbraShadowMapDepth;
layout(location = 0) uniform mat4 penumbraShadowMapLightTexture;
layout(location = 1) uniform uint penumbraShadowMapSampleCount;

void main() {
    const uint id = penumbraLinearGroup() * 256u + gl_LocalInvocationID.x;
    if (id >= penumbraShadowMapSampleCount) return;
    const vec4 p = penumbraShadowMapPositions[id];
    if (p.w == 0.0) {
        penumbraShadowMapStates[id] = PENUMBRA_AFH_NO_SAMPLE;
        return;
    }
    const vec4 t = penumbraShadowMapLightTexture * vec4(p.xyz, 1.0);
    const vec3 q = t.xyz / t.w;
    const ivec2 size = textureSize(penumbraShadowMapDepth, 0);
    // Written so that NaN fails every comparison and lands in UNTESTED.
    if (!(t.w > 0.0) || !(q.x >= 0.0 && q.x <= 1.0 && q.y >= 0.0 && q.y <= 1.0) || !(abs(q.z) < 1e30)) {
        penumbraShadowMapStates[id] = PENUMBRA_AFH_UNTESTED;
        return;
    }
    const ivec2 texel = min(ivec2(q.xy * vec2(size)), size - 1);
    const float stored = texelFetch(penumbraShadowMapDepth, texel, 0).r;
    penumbraShadowMapStates[id] = min(q.z, 1.0) > stored ? PENUMBRA_AFH_SHADOWED : PENUMBRA_AFH_LIT;
}
