// penumbra — what the sample-list entry shaders (count, fit, scatter) share: the parameter and
// frustum blocks, the view-sample input bindings, and the input hooks of input.glsl defined on
// them. Entry shaders own their bindings (binding numbers: PENUMBRA_SAMPLE_LISTS_BINDING_* /
// _UNIT_*, injected by penumbra::SampleListBuilder from SampleListsBindings). An integrator who
// stores view samples differently (packed normals, a G-buffer layout of its own) overrides the
// decoding without forking the entries: define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION /
// _NORMAL / _DEPTH (and PENUMBRA_SAMPLE_LISTS_CUSTOM_INPUT_BINDINGS to declare its own
// resources instead of the default ones) through the builder's extra defines.
#ifndef PENUMBRA_SAMPLE_LISTS_KERNEL_GLSL
#define PENUMBRA_SAMPLE_LISTS_KERNEL_GLSL

#include "penumbra/common/dispatch.glsl"
#include "penumbra/sample_lists/sample_lists_shared.h"

#ifndef PENUMBRA_SAMPLE_LISTS_INPUT
#error "penumbra/sample_lists/kernel.glsl: define PENUMBRA_SAMPLE_LISTS_INPUT (0 = buffer, 1 = depth)"
#endif

layout(local_size_x = PENUMBRA_SAMPLE_LISTS_GROUP_SIZE) in;

layout(std140, binding = PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS) uniform PenumbraSampleListsParamsBlock {
    PenumbraSampleListsParams penumbraSampleListsParams;
};

#ifndef PENUMBRA_SAMPLE_LISTS_CUSTOM_INPUT_BINDINGS
#if PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS) readonly buffer PenumbraSampleListsInputPositionsBlock {
    vec4 penumbraSampleListsInputPositions[];
};
layout(std430, binding = PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS) readonly buffer PenumbraSampleListsInputNormalsBlock {
    vec4 penumbraSampleListsInputNormals[];
};
#else
layout(binding = PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH) uniform sampler2D penumbraSampleListsInputDepth;
layout(binding = PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS) uniform sampler2D penumbraSampleListsInputNormals;
#endif
#endif

#if PENUMBRA_SAMPLE_LISTS_INPUT == PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_POSITION(id) penumbraSampleListsInputPositions[id]
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(id) penumbraSampleListsInputNormals[id].xyz
#endif
#else
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_DEPTH(pixel) texelFetch(penumbraSampleListsInputDepth, ivec2(pixel), 0).r
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL
#define PENUMBRA_SAMPLE_LISTS_LOAD_INPUT_NORMAL(pixel) texelFetch(penumbraSampleListsInputNormals, ivec2(pixel), 0).xyz
#endif
#endif
#include "penumbra/sample_lists/input.glsl"

// The sample this invocation handles, or false past the last one. The group index is checked
// before it is scaled, so the idle groups of a folded grid's last row cannot wrap a 32-bit id
// back onto real samples (sample counts go up to kSampleListsMaxSamples = 0xFFFFFF00).
bool penumbraSampleListsSampleId(out uint id) {
    uint group = penumbraLinearGroup();
    id = group * uint(PENUMBRA_SAMPLE_LISTS_GROUP_SIZE) + gl_LocalInvocationID.x;
    return group < penumbraSampleListsParams.view.z && id < penumbraSampleListsParams.grid.z;
}

#endif
