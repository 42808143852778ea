// penumbra — constants and the parameter block shared by the alias-free hard-shadow pipeline's
// host code (include/penumbra/pipelines/alias_free_hard.hpp) and its shaders. Valid GLSL and C++.
#ifndef PENUMBRA_ALIAS_FREE_HARD_SHARED_H
#define PENUMBRA_ALIAS_FREE_HARD_SHARED_H

// Bindings of the light pass (the conservative emitter's parameter block uses its own binding,
// PENUMBRA_CONSERVATIVE_PARAMS_BINDING).
#define PENUMBRA_AFH_PARAMS_BINDING 1
#define PENUMBRA_AFH_COUNTS_BINDING 0
#define PENUMBRA_AFH_OFFSETS_BINDING 1
#define PENUMBRA_AFH_POSITIONS_BINDING 2
#define PENUMBRA_AFH_SHADOW_BINDING 3
#define PENUMBRA_AFH_WORK_BINDING 4
// Resolve bindings.
#define PENUMBRA_AFH_SLOTS_BINDING 5
#define PENUMBRA_AFH_TEXELS_BINDING 6
#define PENUMBRA_AFH_STATES_BINDING 7

// Per-view-sample result of the resolve (one uint per sample id).
#define PENUMBRA_AFH_LIT 0u
#define PENUMBRA_AFH_SHADOWED 1u
#define PENUMBRA_AFH_BACK_FACING 2u  // light-back-facing: dark by shading (sintorn2008 Fig. 2)
#define PENUMBRA_AFH_NO_SAMPLE 3u    // background pixel
#define PENUMBRA_AFH_UNTESTED 4u     // outside the light frustum or non-finite: not decided

// Light-pass flags (params.grid.w).
#define PENUMBRA_AFH_FLAG_CLOSED 1u  // the draw's casters are closed meshes: only light-back-facing cast

// Work counters (words of the optional work buffer).
#define PENUMBRA_AFH_WORK_FRAGMENTS 0
#define PENUMBRA_AFH_WORK_TESTS 1
#define PENUMBRA_AFH_WORK_TRIANGLES 2
#define PENUMBRA_AFH_WORK_FALLBACKS 3  // exact filtered mode: blocker tests the float filter left to double
#define PENUMBRA_AFH_WORK_WORDS 4

#ifdef __cplusplus
namespace penumbra::shared {
#endif

// std140 == std430 layout: 4 x 16 bytes.
struct PenumbraAfhParams {
    vec4 light;      // w = 1: xyz = point light position; w = 0: xyz = unit direction towards the light
    vec4 tolerance;  // x = coplanar epsilon (relative, exact mode), y = supporting-plane offset toward
                     // the light (world units), z = directional reach (world units), w = unused.
                     // The sample is moved by the offset toward the light: it must lie farther than
                     // that behind a caster's supporting plane to be blocked (0 = exact geometry)
    uvec4 grid;      // x = W, y = H, z = list block (samples per fragment per pass), w = flags
    uvec4 pass;      // x = block index of this pass, y = first triangle id of the draw, z, w = unused
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
