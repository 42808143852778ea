// penumbra — a trivial fragment stage for the full-screen triangle, writing its UV; used by the
// harness tests to check the vertex stage and by integrators as a starting point for resolves.
layout(location = 0) in vec2 penumbraFullscreenUv;
layout(location = 0) out vec4 penumbraFullscreenColor;

void main() {
    penumbraFullscreenColor = vec4(penumbraFullscreenUv, 0.0, 1.0);
}
