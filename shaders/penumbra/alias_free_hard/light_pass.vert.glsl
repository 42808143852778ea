// penumbra — alias-free hard shadows, light pass, vertex stage (sintorn2008 §3.2). Draw the casters
// with attribute 0 = world-space position (vec3); uniform location 0 = the light's (fitted)
// view-projection, the same matrix the sample lists were built with.
layout(location = 0) in vec3 penumbraAfhInPosition;
layout(location = 0) uniform mat4 penumbraAfhLightViewProjection;
layout(location = 0) out vec3 penumbraAfhWorld;

void main() {
    penumbraAfhWorld = penumbraAfhInPosition;
    gl_Position = penumbraAfhLightViewProjection * vec4(penumbraAfhInPosition, 1.0);
}
