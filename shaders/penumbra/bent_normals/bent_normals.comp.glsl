// penumbra — l_bend per bent vertex (sintorn2008 §4.3) into a float buffer: one dispatch of
// ceil(bent vertices / 64) groups whenever the light moves; the vertex stage, drawing with
// BentNormalMesh::indices, then reads it as an attribute. Positions stay per input vertex (source
// maps a bent vertex to its). Bindings: PENUMBRA_BENT_BINDING_* of bent_normals_shared.h.
#include "penumbra/bent_normals/bent_normals_shared.h"

layout(local_size_x = PENUMBRA_BENT_GROUP_SIZE) in;

layout(std140, binding = PENUMBRA_BENT_BINDING_PARAMS) uniform PenumbraBentParamsBlock {
    PenumbraBentParams penumbraBentParams;
};
layout(std430, binding = PENUMBRA_BENT_BINDING_POSITIONS) readonly buffer PenumbraBentPositions {
    vec4 penumbraBentPositions[];
};
layout(std430, binding = PENUMBRA_BENT_BINDING_SOURCE) readonly buffer PenumbraBentSource {
    uint penumbraBentSource[];
};
layout(std430, binding = PENUMBRA_BENT_BINDING_OFFSETS) readonly buffer PenumbraBentOffsets {
    uint penumbraBentOffsets[];
};
layout(std430, binding = PENUMBRA_BENT_BINDING_FACES) readonly buffer PenumbraBentFaces {
    uint penumbraBentFaces[];
};
layout(std430, binding = PENUMBRA_BENT_BINDING_FACE_NORMALS) readonly buffer PenumbraBentFaceNormals {
    vec4 penumbraBentFaceNormals[];
};
layout(std430, binding = PENUMBRA_BENT_BINDING_OUTPUT) writeonly buffer PenumbraBentOutput {
    float penumbraBentOutput[];
};

#define PENUMBRA_BENT_OFFSET(v) penumbraBentOffsets[v]
#define PENUMBRA_BENT_FACE(i) penumbraBentFaces[i]
#define PENUMBRA_BENT_FACE_NORMAL(f) penumbraBentFaceNormals[f].xyz
#include "penumbra/bent_normals/bent_normals.glsl"

void main() {
    const uint v = gl_GlobalInvocationID.x;
    if (v >= penumbraBentParams.vertex_count) return;
    const vec3 position = penumbraBentPositions[penumbraBentSource[v]].xyz;
    penumbraBentOutput[v] = penumbraBentLight(v, position, penumbraBentParams.light.xyz, penumbraBentParams.light.w);
}
