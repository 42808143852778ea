// penumbra — a full-screen triangle from gl_VertexID (draw 3 vertices, no buffers). Resolve and
// screen-space passes use it.
layout(location = 0) out vec2 penumbraFullscreenUv;

void main() {
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2);
    penumbraFullscreenUv = p;
    gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
