// Test-only entry (for a GL test of penumbra/light_volume/airlight.glsl): one invocation per query,
// A(t) by penumbraAirlight (the setup's method) and by the quadrature, through the hooks the way an
// integrator's shader would define them.
//   default: PENUMBRA_AIRLIGHT_TABLE(uv) on a sampler2D (hardware bilinear);
//   AIRLIGHT_TEST_FETCH: PENUMBRA_AIRLIGHT_TABLE_FETCH(texel) from an SSBO (filtered like the CPU);
//   AIRLIGHT_TEST_QUADRATURE_ONLY: no table at all.
// penumbra-permutation: PENUMBRA_AIRLIGHT_NODES=16
// penumbra-permutation: PENUMBRA_AIRLIGHT_NODES=8 AIRLIGHT_TEST_FETCH=1
// penumbra-permutation: PENUMBRA_AIRLIGHT_NODES=32 AIRLIGHT_TEST_QUADRATURE_ONLY=1
//
// Bindings: texture unit 0 = the table (R32F, W x H, GL_LINEAR, GL_CLAMP_TO_EDGE); SSBO 0 the table
// as floats (FETCH), 1 queries (3 vec4 each: eye.xyz + t, dir.xyz, light.xyz), 2 results (vec2:
// penumbraAirlight, penumbraAirlightQuadrature). Uniforms: location 0 = medium
// (AirlightSetup::shaderMedium), 1 = params (shaderParams), 2 = query count.
layout(local_size_x = 64) in;

layout(std430, binding = 1) readonly buffer AirlightTestQueries { vec4 airlightTestQueries[]; };
layout(std430, binding = 2) writeonly buffer AirlightTestResults { vec2 airlightTestResults[]; };
layout(location = 0) uniform vec4 airlightTestMedium;
layout(location = 1) uniform vec4 airlightTestParams;
layout(location = 2) uniform uint airlightTestCount;

#if defined(AIRLIGHT_TEST_QUADRATURE_ONLY)
#define PENUMBRA_AIRLIGHT_QUADRATURE_ONLY
#elif defined(AIRLIGHT_TEST_FETCH)
layout(std430, binding = 0) readonly buffer AirlightTestTable { float airlightTestTable[]; };
#define PENUMBRA_AIRLIGHT_TABLE_FETCH(texel) airlightTestTable[(texel).y * int(airlightTestParams.x) + (texel).x]
#else
layout(binding = 0) uniform sampler2D airlightTestTexture;
#define PENUMBRA_AIRLIGHT_TABLE(uv) texture(airlightTestTexture, uv).r
#endif
#include "penumbra/light_volume/airlight.glsl"

void main() {
    const uint i = gl_GlobalInvocationID.x;
    if (i >= airlightTestCount) return;
    const vec4 a = airlightTestQueries[3u * i], b = airlightTestQueries[3u * i + 1u], c = airlightTestQueries[3u * i + 2u];
    airlightTestResults[i] =
        vec2(penumbraAirlight(airlightTestMedium, airlightTestParams, a.xyz, b.xyz, c.xyz, a.w),
             penumbraAirlightQuadrature(airlightTestMedium, airlightTestParams, a.xyz, b.xyz, c.xyz, a.w));
}
