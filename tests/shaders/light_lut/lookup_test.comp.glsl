// Test- and benchmark-only entry (tests/light_lut_gl_test.cpp, benchmarks/light_lut_bench.cpp):
// runs penumbra/light_lut/lookup.glsl through its hooks the way an integrator's shader would. One
// invocation per (plane, table), e = plane * tables + table, on a folded 2D grid.
//   PENUMBRA_LUT_TEST_MODE 0 (identity check): 9 uvec4 at 9e: penumbraLutBehind; certain and
//       uncertain of penumbraLutBehindCertified; penumbraExactBehind; penumbraLutResolve of the
//       certified answer; penumbraLutCombine of the certified answers of this plane and the next
//       (plane + 1 mod count; certain, uncertain); penumbraLutLocate (texel, flip, trivial + 1, 0);
//       the bits of penumbraLutRotate(plane, rotation.x, rotation.y).
//   1: one uvec4 at e, penumbraLutBehind (seed mode; the timed lookup);
//   2: penumbraLutResolve of penumbraLutBehindCertified (exact answers from a certified LUT);
//   3: penumbraExactBehind (the ground truth, every sample).
// penumbra-permutation: PENUMBRA_LUT_TEST_MODE=0
// penumbra-permutation: PENUMBRA_LUT_TEST_MODE=1
// penumbra-permutation: PENUMBRA_LUT_TEST_MODE=2
// penumbra-permutation: PENUMBRA_LUT_TEST_MODE=3
//
// Bindings: uniform block 0 = PenumbraLutParams; SSBO 1 the LUT (uvec4), 2 samples (vec4, 128 per
// table, float), 3 planes (vec4), 4 rotations (vec2: cos, sin; mode 0), 5 results. Uniforms:
// location 0 = plane count, 1 = tables.
#ifndef PENUMBRA_LUT_TEST_MODE
#error "PENUMBRA_LUT_TEST_MODE must be defined (0: identity check, 1: seed lookup, 2: certified + resolve, 3: exact)"
#endif
#include "penumbra/light_lut/light_lut_shared.h"
#include "penumbra/common/dispatch.glsl"

layout(local_size_x = 64) in;

layout(std140, binding = 0) uniform LutTestParamsBlock { PenumbraLutParams lutTestParams; };
layout(std430, binding = 1) readonly buffer LutTestTable { uvec4 lutTestTable[]; };
layout(std430, binding = 2) readonly buffer LutTestSamples { vec4 lutTestSamples[]; };
layout(std430, binding = 3) readonly buffer LutTestPlanes { vec4 lutTestPlanes[]; };
layout(std430, binding = 4) readonly buffer LutTestRotations { vec2 lutTestRotations[]; };
layout(std430, binding = 5) writeonly buffer LutTestResults { uvec4 lutTestResults[]; };

layout(location = 0) uniform uint lutTestPlaneCount;
layout(location = 1) uniform uint lutTestTables;

#define PENUMBRA_LUT_PARAMS lutTestParams
#define PENUMBRA_LUT_LOAD(index) lutTestTable[index]
#define PENUMBRA_LUT_SAMPLE(table, bit) lutTestSamples[(table) * 128u + (bit)].xyz
#include "penumbra/light_lut/lookup.glsl"

void main() {
    const uint e = penumbraLinearGroup() * 64u + gl_LocalInvocationID.x;
    if (e >= lutTestPlaneCount * lutTestTables) return;
    const uint plane_index = e / lutTestTables, table = e % lutTestTables;
    const vec4 plane = lutTestPlanes[plane_index];
#if PENUMBRA_LUT_TEST_MODE == 0
    uvec4 uncertain;
    const uvec4 certain = penumbraLutBehindCertified(plane, table, uncertain);
    lutTestResults[9u * e + 0u] = penumbraLutBehind(plane, table);
    lutTestResults[9u * e + 1u] = certain;
    lutTestResults[9u * e + 2u] = uncertain;
    lutTestResults[9u * e + 3u] = penumbraExactBehind(plane, table);
    lutTestResults[9u * e + 4u] = penumbraLutResolve(plane, table, certain, uncertain);
    uvec4 uncertain2;
    const uvec4 certain2 = penumbraLutBehindCertified(lutTestPlanes[(plane_index + 1u) % lutTestPlaneCount], table, uncertain2);
    uvec4 c = certain, u = uncertain;
    penumbraLutCombine(c, u, certain2, uncertain2);
    lutTestResults[9u * e + 5u] = c;
    lutTestResults[9u * e + 6u] = u;
    const PenumbraLutCell cell = penumbraLutLocate(lutTestParams, plane);
    lutTestResults[9u * e + 7u] = uvec4(cell.texel, cell.flip ? 1u : 0u, uint(cell.trivial + 1), 0u);
    const vec2 r = lutTestRotations[plane_index];
    lutTestResults[9u * e + 8u] = floatBitsToUint(penumbraLutRotate(plane, r.x, r.y));
#elif PENUMBRA_LUT_TEST_MODE == 1
    lutTestResults[e] = penumbraLutBehind(plane, table);
#elif PENUMBRA_LUT_TEST_MODE == 2
    uvec4 uncertain;
    const uvec4 certain = penumbraLutBehindCertified(plane, table, uncertain);
    lutTestResults[e] = penumbraLutResolve(plane, table, certain, uncertain);
#else
    lutTestResults[e] = penumbraExactBehind(plane, table);
#endif
}
