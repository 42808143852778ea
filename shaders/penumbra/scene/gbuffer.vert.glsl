// penumbra scene helper — G-buffer vertex stage: world-space positions in, camera clip out.
// Attribute 0 = position (vec3, world), 1 = shading normal (vec3). Uniform 0 = view-projection.
layout(location = 0) in vec3 penumbraSceneInPosition;
layout(location = 1) in vec3 penumbraSceneInNormal;
layout(location = 0) uniform mat4 penumbraSceneViewProjection;

layout(location = 0) out vec3 penumbraSceneWorld;
layout(location = 1) out vec3 penumbraSceneNormal;

void main() {
    penumbraSceneWorld = penumbraSceneInPosition;
    penumbraSceneNormal = penumbraSceneInNormal;
    gl_Position = penumbraSceneViewProjection * vec4(penumbraSceneInPosition, 1.0);
}
