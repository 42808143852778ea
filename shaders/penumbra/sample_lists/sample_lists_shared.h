// penumbra — view-sample lists (sintorn2008 §3.1): constants and structs seen by C++ and GLSL
// alike (valid as both). Host code includes it through include/penumbra/sample_lists.hpp, which
// includes penumbra/detail/shared.hpp first (GLSL type names -> GLM) and static_asserts the sizes.
// std140/std430-safe: only mat4/vec4/uvec4/uint members, no vec3, no bool, explicit padding.
#ifndef PENUMBRA_SAMPLE_LISTS_SHARED_H
#define PENUMBRA_SAMPLE_LISTS_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

// Work-group size of every sample-list kernel (one invocation per view sample or per texel).
#define PENUMBRA_SAMPLE_LISTS_GROUP_SIZE 256

// Largest light-grid side: integrators rasterize the light pass into the W x H grid, and GL
// guarantees viewports / framebuffers of 16384 only on current hardware (GL_MAX_VIEWPORT_DIMS).
#define PENUMBRA_SAMPLE_LISTS_MAX_GRID_SIDE 16384u

// Per-sample slot of a rejected sample (sample_slots[id]); never a valid slot.
#define PENUMBRA_SAMPLE_LISTS_NO_SLOT 0xFFFFFFFFu

// sample_texels[id] holds the list (texel) index y * W + x of an accepted sample, or
// PENUMBRA_SAMPLE_LISTS_REJECTED + reason for a rejected one. Reasons are tested in this order
// and the first that applies is the one counted (see sample_lists.hpp, "Rules").
#define PENUMBRA_SAMPLE_LISTS_REJECTED 0xFFFFFFF0u
#define PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND 0u   // no surface: position w == 0 / depth == 1
#define PENUMBRA_SAMPLE_LISTS_REASON_NON_FINITE 1u   // NaN/Inf position (or normal when culling)
#define PENUMBRA_SAMPLE_LISTS_REASON_OUTSIDE 2u      // outside the light frustum's side planes
#define PENUMBRA_SAMPLE_LISTS_REASON_DEPTH 3u        // in front of the near / beyond the far plane
#define PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING 4u  // dot(n, to_light) <= 0 (Fig. 2)
#define PENUMBRA_SAMPLE_LISTS_REASON_COUNT 5u

// PenumbraSampleListsParams::grid.w flags.
#define PENUMBRA_SAMPLE_LISTS_FLAG_CULL_BACK_FACING 1u
#define PENUMBRA_SAMPLE_LISTS_FLAG_CLIP_DEPTH 2u
#define PENUMBRA_SAMPLE_LISTS_FLAG_VIEW_DEPTH_ZERO_TO_ONE 4u  // depth input: view clip z in [0, w]

// Entry-shader permutation PENUMBRA_SAMPLE_LISTS_INPUT: where view samples come from.
#define PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER 0  // vec4 positions + vec4 normals (SSBOs)
#define PENUMBRA_SAMPLE_LISTS_INPUT_DEPTH 1   // depth texture + inverse view-projection, normal texture

// PenumbraSampleListsParams::grid.w flags set by the host for the §4.3 fit-resolve pass.
#define PENUMBRA_SAMPLE_LISTS_FLAG_FIT_FAR 8u                // fit the far plane too
#define PENUMBRA_SAMPLE_LISTS_FLAG_LIGHT_DEPTH_ZERO_TO_ONE 16u  // the light's clip z is in [0, w]

// Binding points of the library's own kernels: the defaults of penumbra::SampleListsBindings.
// The executor injects the integrator's choice as defines, so each is overridable (#ifndef).
// Binding 3 is the offsets in the scatter pass and the header in the other passes, binding 2 the
// counts and, in the fit-resolve pass, the frustum it writes: no pass needs both, and GL
// guarantees only 8 SSBO bindings per stage.
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS
#define PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS 0          // uniform block: PenumbraSampleListsParams
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM
#define PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM 1         // uniform block: PenumbraSampleListsFrustum
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS
#define PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS 0       // SSBO, buffer input
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS
#define PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS 1         // SSBO, buffer input
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS
#define PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS 2
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT
#define PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT 2     // SSBO, fit-resolve pass
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS
#define PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS 3         // scatter pass
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_HEADER
#define PENUMBRA_SAMPLE_LISTS_BINDING_HEADER 3          // count, fit, fit-resolve and statistics passes
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS
#define PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS 4
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS
#define PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS 5
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS
#define PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS 6
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS
#define PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS 7
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH
#define PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH 0              // texture unit, depth input
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS
#define PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS 1            // texture unit, depth input
#endif

// Uniform block of every kernel (256 bytes; identical in std140 and std430). The host writes it
// once per build; nothing in it depends on GPU results.
struct PenumbraSampleListsParams {
    mat4 light_texture;          // world -> homogeneous light texture space of the light's own
                                 // view-projection: bias * light_view_projection (0 <= x, y, z <= w
                                 // inside); the fit pass projects with it
    mat4 light_view_projection;  // the light's view-projection as the integrator gave it
    mat4 view_inverse;           // depth input: inverse of the view's view-projection (clip -> world)
    vec4 light;                  // xyz = position (w = 1, point light) or direction towards the light (w = 0)
    uvec4 grid;                  // x = W, y = H, z = sample count, w = PENUMBRA_SAMPLE_LISTS_FLAG_* bits
    uvec4 view;                  // x, y = view width, height (depth input); z = sample work groups; w = 0
    vec4 fit;                    // x = margin, y = min_margin (LightFrustumFitOptions); z, w = 0
};

// What the count and scatter passes project with, and the light pass draws with (240 bytes,
// std140 == std430). Written by the host (no fit) or by the fit-resolve pass on the GPU (§4.3),
// so the fitted frustum never travels through the CPU.
struct PenumbraSampleListsFrustum {
    mat4 light_texture;    // bias * view_projection
    mat4 view_projection;  // the light view-projection the lists were built for (fitted or not)
    mat4 crop;             // fitted NDC crop (identity without a fit)
    vec4 box;              // fitted box of the samples in the original light texture: min u, min v, max u, max v
    vec4 extent;           // x = max light-texture depth, y = far distance (§4.3), z, w = 0
    uvec4 info;            // x = 1 when fitted, y = samples that entered the fit, z, w = 0
};

// The header buffer (96 bytes; an SSBO, std430 only: `rejected[8]` would have a 16-byte stride
// under std140): counters of the count pass, §4.3 fit keys, Fig. 9 statistics.
// Fit keys are order-preserving encodings of floats (penumbraSampleListsOrderKey), so atomicMin /
// atomicMax on uints reduce floats.
struct PenumbraSampleListsHeader {
    uint accepted;               // samples inserted into the lists (count pass)
    uint header_reserved0;
    uint header_reserved1;
    uint header_reserved2;
    uint rejected[8];            // [PENUMBRA_SAMPLE_LISTS_REASON_*] (count pass); 5..7 stay 0
    uint fit_min_u;              // fit pass: keys, initialised to 0xFFFFFFFFu (min) / 0 (max)
    uint fit_min_v;
    uint fit_max_u;
    uint fit_max_v;
    uint fit_max_depth;          // light-texture depth z / w
    uint fit_max_distance;       // point light: squared distance; directional: -dot(p, light.xyz)
    uint fit_samples;            // samples that entered the fit (plain count)
    uint fit_reserved;
    uint occupied_lists;         // statistics pass: lists with count > 0
    uint max_list_length;
    uint listed_samples;         // sum of all list lengths
    uint statistics_reserved;
};

// Word offsets inside PenumbraSampleListsHeader (the host clears these ranges).
#define PENUMBRA_SAMPLE_LISTS_HEADER_COUNTERS_WORD 0u   // accepted .. rejected[7]: 12 words
#define PENUMBRA_SAMPLE_LISTS_HEADER_COUNTERS_WORDS 12u
#define PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MIN_WORD 12u   // fit_min_u, fit_min_v
#define PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MAX_WORD 14u   // fit_max_u .. fit_reserved: 6 words
#define PENUMBRA_SAMPLE_LISTS_HEADER_STATISTICS_WORD 20u  // occupied .. statistics_reserved: 4 words
#define PENUMBRA_SAMPLE_LISTS_HEADER_WORDS 24u

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
