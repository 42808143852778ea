// penumbra — deep shadow map build: the opacity hook (PENUMBRA_DSM_OPACITY_HOOK). raster.frag.glsl
// calls penumbraDsmOpacityHook(triangle, coordinates) for every covered sub-sample of a build whose
// casters set opacity_hook: `triangle` is the triangle's index within the draw, `coordinates` the
// caster's vertex attribute 1 (DsmCasterBuffers::hook_attribute, vec3 per vertex) interpolated
// like the depth (perspective-correct at the sub-sample). The result is opacity per channel (grey
// maps use .r); the caller clamps it to [0, 1] (NaN -> 0).
//
// Replace this file in your ShaderLibrary (ShaderLibrary::add("penumbra/deep_shadow_map/
// opacity_hook.glsl", ...)) to read your engine's material: an alpha texture with its own
// sampler and filtering, a texture array, bindless handles, a procedural pattern. Keep the
// function's name and signature. The CPU twin of whatever you put here is DsmOpacity::hook.
//
// The default: the 2D texture bound to unit PENUMBRA_DSM_OPACITY_TEXTURE_UNIT
// (DsmCasterBuffers::opacity_texture), read at uv = coordinates.xy with repeat wrapping and nearest
// texels through texelFetch (no sampler state, no filtering: the CPU twin dsmOpacityTexel() gives
// the same texel on any driver, and the same value for float textures), .rgb. A texture with
// fewer than three channels gives 0 in the missing ones: use an RGB(A) texture for colour maps.
#ifndef PENUMBRA_DSM_OPACITY_HOOK_GLSL
#define PENUMBRA_DSM_OPACITY_HOOK_GLSL

layout(binding = PENUMBRA_DSM_OPACITY_TEXTURE_UNIT) uniform sampler2D penumbraDsmOpacityTexture;

vec3 penumbraDsmOpacityHook(uint triangle, vec3 coordinates) {
    const ivec2 size = textureSize(penumbraDsmOpacityTexture, 0);
    if (size.x <= 0 || size.y <= 0) return vec3(0.0);
    // Repeat: the fraction in [0, 1); NaN, Inf and the rounding of a tiny negative u up to 1 read
    // texel 0.
    precise vec2 f = coordinates.xy - floor(coordinates.xy);
    if (!(f.x >= 0.0 && f.x < 1.0)) f.x = 0.0;
    if (!(f.y >= 0.0 && f.y < 1.0)) f.y = 0.0;
    precise vec2 g = f * vec2(size);
    const ivec2 texel = min(ivec2(g), size - 1);
    return texelFetch(penumbraDsmOpacityTexture, texel, 0).rgb;
}

#endif
