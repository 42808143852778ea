// penumbra — the ray-march baseline of the light-volume render (what an engine would run instead of
// billeter2010's volume): per pixel, the stretch of its ray inside the spot's frustum and in front of
// the scene, cut into `march.x` steps; a step whose midpoint is no deeper than the shadow map's
// nearest texel adds A(t_end) - A(t_begin) (the airlight integrated exactly over the step). Adds
// colour * airlight to the engine's image like the composite. The twin of
// reference::rayMarchExact with ShadowMapLookup::Nearest. One invocation per pixel.
// penumbra-permutation: PENUMBRA_LV_LIT_FORMAT=rgba32f
#include "penumbra/light_volume/render.glsl"

#ifndef PENUMBRA_LV_LIT_FORMAT
#define PENUMBRA_LV_LIT_FORMAT rgba32f
#endif

layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = PENUMBRA_LV_SHADOW_MAP_UNIT) uniform sampler2D penumbraLvShadowMap;
layout(PENUMBRA_LV_LIT_FORMAT, binding = PENUMBRA_LV_LIT_IMAGE) uniform image2D penumbraLvLit;

void main() {
    const ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (pixel.x >= int(penumbraLvRender.size.y) || pixel.y >= int(penumbraLvRender.size.z)) return;
    const vec3 dir = penumbraLvPixelRay(pixel);
    // The frustum's six clip planes, a + b t >= 0 (and w > 0), clip the ray to [lo, hi].
    const vec4 c0 = penumbraLvRender.eye_to_light * vec4(0.0, 0.0, 0.0, 1.0), c1 = penumbraLvRender.eye_to_light * vec4(dir, 0.0);
    float lo = 0.0, hi = min(penumbraLvSceneDistance(pixel), 1e6);
    const float a[7] = float[7](c0.w + c0.x, c0.w - c0.x, c0.w + c0.y, c0.w - c0.y, c0.w + c0.z, c0.w - c0.z, c0.w);
    const float b[7] = float[7](c1.w + c1.x, c1.w - c1.x, c1.w + c1.y, c1.w - c1.y, c1.w + c1.z, c1.w - c1.z, c1.w);
    for (int k = 0; k < 7; ++k) {
        if (b[k] == 0.0) {
            if (a[k] < 0.0) hi = -1.0;
        } else if (b[k] > 0.0) {
            lo = max(lo, -a[k] / b[k]);
        } else {
            hi = min(hi, -a[k] / b[k]);
        }
    }
    float airlight = 0.0;
    if (hi > lo) {
        const uint steps = max(penumbraLvRender.march.x, 1u);
        const uint r = penumbraLvRender.size.x;
        const float dt = (hi - lo) / float(steps);
        float before = penumbraLvAirlight(dir, lo);
        for (uint k = 0u; k < steps; ++k) {
            const float after = penumbraLvAirlight(dir, lo + float(k + 1u) * dt);
            const vec4 clip = penumbraLvRender.eye_to_light * vec4((lo + (float(k) + 0.5) * dt) * dir, 1.0);
            const vec3 ndc = clip.xyz / clip.w;
            const ivec2 texel = clamp(ivec2((ndc.xy * 0.5 + 0.5) * float(r)), ivec2(0), ivec2(int(r) - 1));
            if (ndc.z * 0.5 + 0.5 <= texelFetch(penumbraLvShadowMap, texel, 0).r) airlight += after - before;
            before = after;
        }
    }
    const vec4 lit = imageLoad(penumbraLvLit, pixel);
    imageStore(penumbraLvLit, pixel, vec4(lit.rgb + penumbraLvRender.colour.rgb * airlight, lit.a));
}
