// penumbra — the light volume's composite: per pixel airlight = red + green * A(D) of the
// accumulation target (volume.frag.glsl), then lit += colour * airlight in the engine's image
// (rgba16f or rgba32f: PENUMBRA_LV_LIT_FORMAT). One invocation per pixel.
// penumbra-permutation: PENUMBRA_LV_LIT_FORMAT=rgba16f
// penumbra-permutation: PENUMBRA_LV_LIT_FORMAT=rgba32f
#include "penumbra/light_volume/render.glsl"

#ifndef PENUMBRA_LV_LIT_FORMAT
#error penumbra/light_volume/composite.comp.glsl needs PENUMBRA_LV_LIT_FORMAT (rgba16f or rgba32f)
#endif

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = PENUMBRA_LV_ACCUMULATION_UNIT) uniform sampler2D penumbraLvAccumulation;
layout(PENUMBRA_LV_LIT_FORMAT, binding = PENUMBRA_LV_LIT_IMAGE) uniform image2D penumbraLvLit;

void main() {
    const ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(penumbraLvRender.size.y) || pixel.y >= int(penumbraLvRender.size.z)) return;
    const vec2 sum = texelFetch(penumbraLvAccumulation, pixel, 0).rg;
    float airlight = sum.x;
    if (sum.y != 0.0) airlight += sum.y * penumbraLvAirlight(penumbraLvPixelRay(pixel), penumbraLvSceneDistance(pixel));
    const vec4 lit = imageLoad(penumbraLvLit, pixel);
    imageStore(penumbraLvLit, pixel, vec4(lit.rgb + penumbraLvRender.colour.rgb * airlight, lit.a));
}
