// penumbra scene helper — G-buffer fragment stage. Writes
//   location 0: world position (xyz) and 1 (w marks covered pixels; the clear value has w = 0),
//   location 1: the triangle's geometric normal (xyz, unit, from the face-normal SSBO, so the
//               light-facing test of sintorn2008 Fig. 2 sees the triangle itself) and the
//               triangle id in w (as float bits),
//   location 2: the interpolated shading normal (xyz) for lighting.
// SSBO binding 0 = vec4 face normals by triangle; uniform 1 = first triangle id of this draw.
layout(location = 0) in vec3 penumbraSceneWorld;
layout(location = 1) in vec3 penumbraSceneNormal;
layout(location = 0) out vec4 penumbraSceneOutPosition;
layout(location = 1) out vec4 penumbraSceneOutFace;
layout(location = 2) out vec4 penumbraSceneOutShading;

layout(std430, binding = 0) readonly buffer PenumbraSceneFaceNormals { vec4 penumbraSceneFaceNormals[]; };
layout(location = 1) uniform uint penumbraSceneFirstTriangle;

void main() {
    uint triangle = penumbraSceneFirstTriangle + uint(gl_PrimitiveID);
    vec3 face = penumbraSceneFaceNormals[triangle].xyz;
    vec3 shading = normalize(penumbraSceneNormal);
    // Open meshes are seen from both sides: report the side facing the camera.
    if (!gl_FrontFacing) {
        face = -face;
        shading = -shading;
    }
    penumbraSceneOutPosition = vec4(penumbraSceneWorld, 1.0);
    penumbraSceneOutFace = vec4(face, uintBitsToFloat(triangle));
    penumbraSceneOutShading = vec4(shading, 0.0);
}
