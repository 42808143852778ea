// Test-only entry: scan_workgroup_test.comp.glsl on GL_KHR_shader_subgroup_arithmetic where the
// compiler has it (glslangValidator always; a driver only if it lists the extension, elsewhere the
// line below draws a warning and the shared-memory path runs).
//
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=256
#extension GL_KHR_shader_subgroup_arithmetic : enable

#include "penumbra/scan/scan_shared.h"
#ifdef GL_KHR_shader_subgroup_arithmetic
#define PENUMBRA_SCAN_SUBGROUPS PENUMBRA_SCAN_SUBGROUPS_KHR
#endif
#include "scan_workgroup_test.comp.glsl"
