// Test-only entry (tests/scan_test.cpp): exercises penumbra/scan/workgroup.glsl through its hook
// the way an integrator's kernel would. PENUMBRA_SCAN_GROUP_SIZE comes from the test's defines
// (a missing hook must be a compile error naming it); PENUMBRA_SCAN_TEST_2D shapes the group as
// 8 x (size / 8) to check that invocations are ordered by gl_LocalInvocationIndex.
//
// Per invocation i of group g (element e = g * size + i) it writes six words at 6e:
//   exclusive scan of values, its total, inclusive scan of 3 * values, its total, sum of
//   (values ^ 0x80000000u), exclusive scan of (values + 1) without a total — four back-to-back
//   calls with no barriers between them.
//
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=64
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=100
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=1024
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=64 PENUMBRA_SCAN_TEST_2D
// PENUMBRA_SCAN_TEST_LOCAL_SIZE (tests only) declares a local size that may disagree with the
// hook: the snippet must then fail to compile.
#if defined(PENUMBRA_SCAN_TEST_LOCAL_SIZE)
layout(local_size_x = PENUMBRA_SCAN_TEST_LOCAL_SIZE) in;
#elif defined(PENUMBRA_SCAN_TEST_2D)
layout(local_size_x = 8, local_size_y = PENUMBRA_SCAN_GROUP_SIZE / 8) in;
#else
layout(local_size_x = PENUMBRA_SCAN_GROUP_SIZE) in;
#endif
#include "penumbra/scan/workgroup.glsl"

layout(std430, binding = 0) readonly buffer ScanTestValues { uint scanTestValues[]; };
layout(std430, binding = 1) writeonly buffer ScanTestResults { uint scanTestResults[]; };

void main() {
    uint e = gl_WorkGroupID.x * penumbraScanGroupSize + gl_LocalInvocationIndex;
    uint value = scanTestValues[e];
    uint exclusive_total;
    uint exclusive = penumbraScanWorkgroupExclusive(value, exclusive_total);
    uint inclusive_total;
    uint inclusive = penumbraScanWorkgroupInclusive(3u * value, inclusive_total);
    uint reduced = penumbraScanWorkgroupReduce(value ^ 0x80000000u);
    uint plain = penumbraScanWorkgroupExclusive(value + 1u);
    scanTestResults[6u * e + 0u] = exclusive;
    scanTestResults[6u * e + 1u] = exclusive_total;
    scanTestResults[6u * e + 2u] = inclusive;
    scanTestResults[6u * e + 3u] = inclusive_total;
    scanTestResults[6u * e + 4u] = reduced;
    scanTestResults[6u * e + 5u] = plain;
}
