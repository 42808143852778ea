// Test-only entry: scan_workgroup_test.comp.glsl on GL_ARB_shader_ballot where the compiler has
// it (elsewhere the line below draws a warning and the shared-memory path runs).
//
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=256
// penumbra-permutation: PENUMBRA_SCAN_GROUP_SIZE=64 PENUMBRA_SCAN_TEST_2D
#extension GL_ARB_shader_ballot : enable

#include "penumbra/scan/scan_shared.h"
#ifdef GL_ARB_shader_ballot
#define PENUMBRA_SCAN_SUBGROUPS PENUMBRA_SCAN_SUBGROUPS_BALLOT
#endif
#include "scan_workgroup_test.comp.glsl"
