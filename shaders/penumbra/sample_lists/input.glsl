// penumbra — reading view samples (sintorn2008 §3: "the scene is rendered from the eye into a
// view texture to find points (view-samples) for which shadow computation is needed").
//
// Define PENUMBRA_SAMPLE_LISTS_INPUT to PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER or _DEPTH, and the
// hooks of that input before including this file:
//   buffer: PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION(id) -> vec4 (xyz world position; w == 0
//           marks "no sample"), PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(id) -> vec3 world normal;
//   depth:  PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH(pixel) -> float window depth at uvec2 pixel,
//           PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(pixel) -> vec3 world normal at uvec2 pixel.
// Sample ids: the buffer index, or y * view width + x for the depth input. Normals are read only
// when the cull flag is set, so their resource may be unbound otherwise.
#ifndef PENUMBRA_SAMPLE_LISTS_INPUT_GLSL
#define PENUMBRA_SAMPLE_LISTS_INPUT_GLSL

#include "penumbra/sample_lists/project.glsl"

#ifndef PENUMBRA_SAMPLE_LISTS_INPUT
#error "penumbra/sample_lists/input.glsl: define PENUMBRA_SAMPLE_LISTS_INPUT (PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER or PENUMBRA_SAMPLE_LISTS_INPUT_DEPTH)"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL
#error "penumbra/sample_lists/input.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(index_or_pixel) -> vec3"
#endif

#if PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION
#error "penumbra/sample_lists/input.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION(id) -> vec4"
#endif
#elif PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_DEPTH
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH
#error "penumbra/sample_lists/input.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH(pixel) -> float"
#endif
#else
#error "penumbra/sample_lists/input.glsl: PENUMBRA_SAMPLE_LISTS_INPUT must be PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER (0) or PENUMBRA_SAMPLE_LISTS_INPUT_DEPTH (1)"
#endif

// The view pixel of a sample id (depth input).
uvec2 penumbraSampleListsPixel(PenumbraSampleListsParams params, uint id) {
    return uvec2(id % params.view.x, id / params.view.x);
}

// The sample's world position (w = 1), or w = 0 for "no sample".
vec4 penumbraSampleListsLoadPosition(PenumbraSampleListsParams params, uint id) {
#if PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER
    return PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION(id);
#else
    uvec2 pixel = penumbraSampleListsPixel(params, id);
    return penumbraSampleListsViewPosition(params.view_inverse, pixel, params.view.xy,
                                           PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH(pixel),
                                           (params.grid.w & PENUMBRA_SAMPLE_LISTS_FLAG_VIEW_DEPTH_ZERO_TO_ONE) != 0u);
#endif
}

// The sample's normal when the cull flag is set, else vec3(0) without reading anything.
vec3 penumbraSampleListsLoadNormal(PenumbraSampleListsParams params, uint id) {
    if ((params.grid.w & PENUMBRA_SAMPLE_LISTS_FLAG_CULL_BACK_FACING) == 0u) return vec3(0.0);
#if PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER
    return PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(id);
#else
    return PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(penumbraSampleListsPixel(params, id));
#endif
}

#endif
