// penumbra — bent-normal shading: bindings and the parameter block of bent_normals.comp.glsl,
// shared by C++ (include/penumbra/bent_normals.hpp, tests) and GLSL. Valid as both.
#ifndef PENUMBRA_BENT_NORMALS_SHARED_H
#define PENUMBRA_BENT_NORMALS_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

#define PENUMBRA_BENT_GROUP_SIZE 64

// Default bindings of bent_normals.comp.glsl (override the defines before assembling).
#ifndef PENUMBRA_BENT_BINDING_POSITIONS
#define PENUMBRA_BENT_BINDING_POSITIONS 0     // vec4 per input vertex (xyz; w unused)
#endif
#ifndef PENUMBRA_BENT_BINDING_SOURCE
#define PENUMBRA_BENT_BINDING_SOURCE 5        // uint per bent vertex: its input vertex (BentNormalMesh::source)
#endif
#ifndef PENUMBRA_BENT_BINDING_OFFSETS
#define PENUMBRA_BENT_BINDING_OFFSETS 1       // uint, bent vertices + 1 (BentNormalMesh::offsets)
#endif
#ifndef PENUMBRA_BENT_BINDING_FACES
#define PENUMBRA_BENT_BINDING_FACES 2         // uint (BentNormalMesh::faces)
#endif
#ifndef PENUMBRA_BENT_BINDING_FACE_NORMALS
#define PENUMBRA_BENT_BINDING_FACE_NORMALS 3  // vec4 (BentNormalMesh::face_normals)
#endif
#ifndef PENUMBRA_BENT_BINDING_OUTPUT
#define PENUMBRA_BENT_BINDING_OUTPUT 4        // float per bent vertex: l_bend
#endif
#ifndef PENUMBRA_BENT_BINDING_PARAMS
#define PENUMBRA_BENT_BINDING_PARAMS 0        // uniform block PenumbraBentParamsBlock
#endif

// std140 == std430: 32 bytes.
struct PenumbraBentParams {
    vec4 light;         // xyz: light centre, w: bounding radius (0: toward the centre only)
    uint vertex_count;  // bent vertices: BentNormalMesh::bentVertexCount()
    uint reserved0;
    uint reserved1;
    uint reserved2;
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
