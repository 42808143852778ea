// Test- and benchmark-only entry (tests/blocker_filter_test.cpp, benchmarks/blocker_test_bench.cpp):
// runs penumbra/alias_free_hard/blocker_test.glsl through its light-pass call the way the light
// pass walks a list: one invocation per "fragment" (triangle, first slot, slot count) tests the
// triangle against every sample of its slot range and writes one word per slot.
//   PENUMBRA_AFH_FILTER_TEST_MODE 0: word = filter state (bits 0-1: PENUMBRA_AFH_FILTER_*) |
//       filtered verdict << 2 | fp64-only verdict << 3 (the GPU identity check).
//   1: word = penumbraAfhBlocksLight verdict (PENUMBRA_AFH_FILTERED as defined: 1 = filtered,
//       0 = fp64-only), the two timed variants.
//   2: word = the filtered verdict with the fallback deferred: the walk goes in windows of 32
//       slots, uncertain ones are marked in a bit mask and their double tests run together at the
//       window's end, so the lanes of a SIMD group do not each take the double path at a
//       different iteration of the walk.
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=0
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=1 PENUMBRA_AFH_FILTERED=1
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=1 PENUMBRA_AFH_FILTERED=0
// penumbra-permutation: PENUMBRA_AFH_FILTER_TEST_MODE=2
#ifndef PENUMBRA_AFH_FILTER_TEST_MODE
#error "PENUMBRA_AFH_FILTER_TEST_MODE must be defined (0: identity check, 1: timed light-pass call, 2: deferred fallback)"
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

#if PENUMBRA_AFH_FILTER_TEST_MODE == 2
// The double tests of the slots of `mask` (bit k: slot base + k), run together.
void afhFilterTestFallbacks(uint base, uint mask, vec3 a, vec3 b, vec3 c) {
    const bool point_light = afhFilterTestLight.w != 0.0;
    while (mask != 0u) {
        const uint slot = base + uint(findLSB(mask));
        mask &= mask - 1u;
        const vec3 p = afhFilterTestSamples[slot].xyz;
        const bool blocked = penumbraAfhBlocks(dvec3(a), dvec3(b), dvec3(c), dvec3(p),
                                               penumbraAfhLightPoint(dvec3(p), dvec3(afhFilterTestLight.xyz),
                                                                     double(afhFilterTestReach), point_light),
                                               afhFilterTestEpsilon, afhFilterTestOffset);
        afhFilterTestResults[slot] = blocked ? 1u : 0u;
    }
}
#endif

void main() {
    const uint f = gl_GlobalInvocationID.x;
    if (f >= afhFilterTestFragmentCount) return;
    const uvec4 fragment = afhFilterTestFragments[f];
    const vec3 a = afhFilterTestTriangles[3u * fragment.x].xyz;
    const vec3 b = afhFilterTestTriangles[3u * fragment.x + 1u].xyz;
    const vec3 c = afhFilterTestTriangles[3u * fragment.x + 2u].xyz;
#if PENUMBRA_AFH_FILTER_TEST_MODE == 2
    uint base = fragment.y, pending = 0u;
#endif
    for (uint slot = fragment.y; slot < fragment.y + fragment.z; ++slot) {
        const vec3 p = afhFilterTestSamples[slot].xyz;
#if PENUMBRA_AFH_FILTER_TEST_MODE == 0 || PENUMBRA_AFH_FILTER_TEST_MODE == 2
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
#endif
#if PENUMBRA_AFH_FILTER_TEST_MODE == 2
        if (state == PENUMBRA_AFH_FILTER_UNCERTAIN) pending |= 1u << (slot - base);
        else afhFilterTestResults[slot] = state == PENUMBRA_AFH_FILTER_TRUE ? 1u : 0u;
        if (slot - base == 31u) {
            afhFilterTestFallbacks(base, pending, a, b, c);
            base = slot + 1u;
            pending = 0u;
        }
#elif PENUMBRA_AFH_FILTER_TEST_MODE == 0
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
#if PENUMBRA_AFH_FILTER_TEST_MODE == 2
    afhFilterTestFallbacks(base, pending, a, b, c);
#endif
}
