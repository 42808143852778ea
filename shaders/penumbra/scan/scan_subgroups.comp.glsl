// penumbra — scan.comp.glsl with the workgroup scan on GL_KHR_shader_subgroup_arithmetic (only the
// top pass has one; penumbra::Scanner builds only its top-pass programs from this entry).
//
// penumbra::Scanner uses this entry only when the driver lists GL_KHR_shader_subgroup with the
// basic and arithmetic features in compute shaders and the group size is a multiple of
// GL_SUBGROUP_SIZE_KHR, and keeps it only if a small check scan comes out right. Elsewhere the extension line below only draws a compiler warning and the
// kernel falls back to the shared-memory path, so the file compiles everywhere (the shader tests
// compile it on every driver; glslangValidator checks the subgroup code itself).
//
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=1
// penumbra-permutation: PENUMBRA_SCAN_PASS=PENUMBRA_SCAN_PASS_TOP PENUMBRA_SCAN_GROUP_SIZE=256 PENUMBRA_SCAN_ITEMS_PER_THREAD=16 PENUMBRA_SCAN_VEC4=0
#extension GL_KHR_shader_subgroup_arithmetic : enable

#include "penumbra/scan/scan_shared.h"
#ifdef GL_KHR_shader_subgroup_arithmetic
#define PENUMBRA_SCAN_SUBGROUPS PENUMBRA_SCAN_SUBGROUPS_KHR
#endif
#include "penumbra/scan/scan.comp.glsl"
