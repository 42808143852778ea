// penumbra — alias-free hard shadows, list-block predicate (sintorn2008 §3.1 multi-pass, decided
// on the GPU): before the light pass the pipeline draws one point per list block b, glDrawArrays(
// GL_POINTS, b, 1) inside an occlusion query; the point survives only when some list is longer
// than b blocks (the header's max_list_length from the statistics pass), and the light pass of
// block b is drawn under glBeginConditionalRender on that query. No read-back: the number of
// passes never reaches the CPU. The host draws the points in a 1 x 1 viewport, so the NDC origin
// is that pixel's centre (in an even-sized viewport it would be a pixel corner: a tie).
layout(location = 0) flat out uint penumbraAfhBlock;

void main() {
    penumbraAfhBlock = uint(gl_VertexID);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
    gl_PointSize = 1.0;
}
