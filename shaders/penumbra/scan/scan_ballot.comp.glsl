// penumbra — scan.comp.glsl with the workgroup scan on GL_ARB_shader_ballot (readInvocationARB),
// for drivers without GL_KHR_shader_subgroup arithmetic but with ballot — llvmpipe among them,
// where a subgroup is one 8-wide SIMD vector and this path saves most shared-memory traffic. Only
// the top pass has a workgroup scan; penumbra::Scanner builds only its top-pass programs from here.
//
// penumbra::Scanner uses this entry when the driver lists GL_ARB_shader_ballot, then checks it on
// a small scan (full subgroups of consecutive invocations are assumed) and falls back to the
// shared-memory path if the result is wrong. Where the extension is missing the line below only
// draws a compiler warning and the kernel is the shared-memory one.
//
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=1
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=0
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=32 PENUMBRA_SCAN_ITEMS_PER_THREAD=4 PENUMBRA_SCAN_VEC4=0
#extension GL_ARB_shader_ballot : enable

#include "penumbra/scan/scan_shared.h"
#ifdef GL_ARB_shader_ballot
#define PENUMBRA_SCAN_SUBGROUPS PENUMBRA_SCAN_SUBGROUPS_BALLOT
#endif
#include "penumbra/scan/scan.comp.glsl"
