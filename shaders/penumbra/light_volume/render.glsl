// penumbra — the light-volume render's shared pieces (billeter2010): the constants block, the
// airlight table hook on its texture unit, the pixel ray and the scene depth along it.
#ifndef PENUMBRA_LIGHT_VOLUME_RENDER_GLSL
#define PENUMBRA_LIGHT_VOLUME_RENDER_GLSL

#include "penumbra/light_volume/light_volume_shared.h"

layout(std140, binding = PENUMBRA_LV_BINDING_RENDER_PARAMS) uniform PenumbraLvRenderBlock { PenumbraLightVolumeRenderParams penumbraLvRender; };
layout(binding = PENUMBRA_LV_AIRLIGHT_UNIT) uniform sampler2D penumbraLvAirlightTable;
layout(binding = PENUMBRA_LV_SCENE_DEPTH_UNIT) uniform sampler2D penumbraLvSceneDepth;
#define PENUMBRA_AIRLIGHT_TABLE(uv) texture(penumbraLvAirlightTable, (uv)).r
#include "penumbra/light_volume/airlight.glsl"

/// The unit ray through pixel `pixel` (integer coordinates), relative to the eye.
vec3 penumbraLvPixelRay(ivec2 pixel) {
    const vec2 ndc = (vec2(pixel) + 0.5) / vec2(penumbraLvRender.size.yz) * 2.0 - 1.0;
    const vec4 far_point = penumbraLvRender.camera_inverse * vec4(ndc, 1.0, 1.0);
    return normalize(far_point.xyz / far_point.w);
}

/// The scene's distance along that ray from the camera's depth buffer (background: the airlight's
/// largest distance, i.e. the whole ray).
float penumbraLvSceneDistance(ivec2 pixel) {
    const float depth = texelFetch(penumbraLvSceneDepth, pixel, 0).r;
    if (depth >= 1.0) return penumbraAirlightMaxDistance;
    const vec2 ndc = (vec2(pixel) + 0.5) / vec2(penumbraLvRender.size.yz) * 2.0 - 1.0;
    const vec4 p = penumbraLvRender.camera_inverse * vec4(ndc, depth * 2.0 - 1.0, 1.0);
    return length(p.xyz / p.w);
}

/// A(t) along the pixel's ray (positions relative to the eye).
float penumbraLvAirlight(vec3 dir, float t) {
    return penumbraAirlight(penumbraLvRender.medium, penumbraLvRender.airlight, vec3(0.0), dir, penumbraLvRender.light.xyz, t);
}

#endif
