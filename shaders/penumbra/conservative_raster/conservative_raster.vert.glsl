#version 450
// penumbra — vertex stage for conservative rasterization: hands clip-space positions to
// conservative_raster.geom.glsl. Attribute 0 holds clip-space positions (pass-through) or, with
// PENUMBRA_CONSERVATIVE_VS_TRANSFORM=1, object/world positions (xyz) multiplied by the mat4 at
// uniform location 0. Copy it into your engine and replace the transform as needed; keep world
// coordinates camera-relative when they are large (a float matrix applied to 1e5-sized coordinates
// loses ~1e5 * 2^-24 before the emitter ever sees the triangle).
// penumbra-permutation: PENUMBRA_CONSERVATIVE_VS_TRANSFORM=0
// penumbra-permutation: PENUMBRA_CONSERVATIVE_VS_TRANSFORM=1
#ifndef PENUMBRA_CONSERVATIVE_VS_TRANSFORM
#define PENUMBRA_CONSERVATIVE_VS_TRANSFORM 0
#endif

layout(location = 0) in vec4 penumbraConservativeVertexPosition;
#if PENUMBRA_CONSERVATIVE_VS_TRANSFORM
layout(location = 0) uniform mat4 penumbraConservativeVertexMatrix;
#endif

void main() {
#if PENUMBRA_CONSERVATIVE_VS_TRANSFORM
    gl_Position = penumbraConservativeVertexMatrix * vec4(penumbraConservativeVertexPosition.xyz, 1.0);
#else
    gl_Position = penumbraConservativeVertexPosition;
#endif
}
