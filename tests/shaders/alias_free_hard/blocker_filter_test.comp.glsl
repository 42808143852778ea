// Test- and benchmark-only entry (tests/blocker_filter_test.cpp, benchmarks/blocker_test_bench.cpp):
// runs penumbra/alias_free_hard/blocker_test.glsl through its light-pass call the way the light
// pass walks a list: one invocation per "fragment" (triangle, first slot, slot count) tests the
// triangle against every sample of its slot range and writes one word per slot.
//   PENUMBRA_AFH_FILTER_TEST_MODE 0: word = filter state (bits 0-1: PENUMBRA_AFH_FILTER_*) |
//       filtered verdict << 2 | fp64-only verdict << 3 (the GPU identity check).
//   1: word = penumbraAfhBlocksLight verdict (PENUMBRA_AFH_FILTERED as defined: 1 = filtered,
//       0 = fp64-only), the two timed variants.
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=0
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=1 PENUMBRA_AFH_FILTERED=1
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=1 PENUMBRA_AFH_FILTERED=0
#ifndef PENUMBRA_AFH_FILTER_TEST_MODE
#error "PENUMBRA_AFH_FILTER_TEST_MODE must be defined (0: identity check, 1: timed light-pass call)"
#endif
#define PENUMBRA_AFH_EXACT 1
#include "penumbra/alias_free_hard/blocker_test.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer AfhFilterTestTriangles { vec4 afhFilterTestTriangles[]; };   // 3 per triangle
layout(std430, binding = 1) readonly buffer AfhFilterTestFragments { uvec4 afhFilterTestFragments[]; };  // tri, first, count, -
layout(std430, binding = 2) readonly buffer AfhFilterTestSamples { vec4 afhFilterTestSamples[]; };       // per slot
layout(std430, binding = 3) writeonly buffer AfhFilterTestResults { uint afhFilterTestResults[]; };      // per slot

layout(location = 0) uniform vec4 afhFilterTestLight;
layout(location = 1) uniform float afhFilterTestReach;
layout(location = 2) uniform double afhFilterTestEpsilon;
layout(location = 3) uniform double afhFilterTestOffset;
layout(location = 4) uniform uint afhFilterTestFragmentCount;

void main() {
    const uint f = gl_GlobalInvocationID.x;
    if (f >= afhFilterTestFragmentCount) return;
    const uvec4 fragment = afhFilterTestFragments[f];
    const vec3 a = afhFilterTestTriangles[3u * fragment.x].xyz;
    const vec3 b = afhFilterTestTriangles[3u * fragment.x + 1u].xyz;
    const vec3 c = afhFilterTestTriangles[3u * fragment.x + 2u].xyz;
    for (uint slot = fragment.y; slot < fragment.y + fragment.z; ++slot) {
        const vec3 p = afhFilterTestSamples[slot].xyz;
#if PENUMBRA_AFH_FILTER_TEST_MODE == 0
        const bool point_light = afhFilterTestLight.w != 0.0;
        vec3 l = afhFilterTestLight.xyz;
        float l_error = 0.0;
        if (!point_light) {
            precise vec3 t = afhFilterTestLight.xyz * afhFilterTestReach;
            precise vec3 ld = p + t;
            precise float e = penumbraAfhFilterLightRel * (penumbraAfhFilterMaxAbs(t) + penumbraAfhFilterMaxAbs(ld));
            l = ld;
            l_error = e + penumbraAfhFilterTiny;
        }
        const int state = penumbraAfhBlocksFilter(a, b, c, p, l, l_error, afhFilterTestEpsilon, afhFilterTestOffset);
        const bool filtered = penumbraAfhBlocksFiltered(a, b, c, p, afhFilterTestLight, afhFilterTestReach,
                                                        afhFilterTestEpsilon, afhFilterTestOffset);
        const bool fp64 = penumbraAfhBlocks(dvec3(a), dvec3(b), dvec3(c), dvec3(p),
                                            penumbraAfhLightPoint(dvec3(p), dvec3(afhFilterTestLight.xyz),
                                                                  double(afhFilterTestReach), point_light),
                                            afhFilterTestEpsilon, afhFilterTestOffset);
        afhFilterTestResults[slot] = uint(state) | (filtered ? 4u : 0u) | (fp64 ? 8u : 0u);
#else
        afhFilterTestResults[slot] = penumbraAfhBlocksLight(a, b, c, p, afhFilterTestLight, afhFilterTestReach,
                                                            afhFilterTestEpsilon, afhFilterTestOffset) ? 1u : 0u;
#endif
    }
}
