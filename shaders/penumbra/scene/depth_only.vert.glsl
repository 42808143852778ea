// penumbra scene helper — depth-only vertex stage (shadow-map baselines). Attribute 0 = world
// position; uniform 0 = the light's view-projection.
layout(location = 0) in vec3 penumbraSceneInPosition;
layout(location = 0) uniform mat4 penumbraSceneViewProjection;

void main() {
    gl_Position = penumbraSceneViewProjection * vec4(penumbraSceneInPosition, 1.0);
}
