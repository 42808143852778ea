// penumbra — light-volume tessellator constants and blocks shared by C++ (include/penumbra/light_volume.hpp,
// include/penumbra/gl/light_volume.hpp) and GLSL (shaders/penumbra/light_volume/*). Valid as both
// (STYLE.md habit 2): std140 == std430, no vec3 members, explicit padding; the host static_asserts
// the size.
#ifndef PENUMBRA_LIGHT_VOLUME_SHARED_H
#define PENUMBRA_LIGHT_VOLUME_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

#define PENUMBRA_LV_MAX_LEVELS 16  // levels 0 .. 14 for R = 16384 (kLightVolumeMaxResolution)
#define PENUMBRA_LV_GROUP_SIZE 64
#define PENUMBRA_LV_APEX 0xffffffffu  // the packed vertex of the light's position

// Default bindings (LightVolumeBindings can move them). Uniform buffer:
#define PENUMBRA_LV_BINDING_PARAMS 1
// Shader storage:
#define PENUMBRA_LV_BINDING_CORNERS 0    // float[(R + 1)^2]: lattice depths, corner (i, j) at j (R + 1) + i
#define PENUMBRA_LV_BINDING_FLAGS 1      // uint per cell of every level, coarsest level first (level_offset)
#define PENUMBRA_LV_BINDING_COUNTS 2     // uint per item (cells, then 4 R border segments) + 1: counts, then offsets
#define PENUMBRA_LV_BINDING_TRIANGLES 3  // uint[3 * triangles]: packed vertices x | y << 16, or PENUMBRA_LV_APEX
#define PENUMBRA_LV_BINDING_INDIRECT 4   // uint[8]: DrawArraysIndirectCommand, floor triangles, triangles
// Texture unit of the shadow map (read with texelFetch through the tessellator's own sampler).
#define PENUMBRA_LV_DEPTH_UNIT 0

/// The constants block of every light-volume kernel (std140 == std430, 112 bytes); one per level.
struct PenumbraLightVolumeParams {
    uvec4 size;          // x: resolution R, y: levels L (= log2 R), z: this dispatch's level k, w: 1 = static
    uvec4 counts;        // x: cells of every level, y: items (cells + 4 R), z: this dispatch's invocations, w: 0
    uvec4 flatness;      // xy: the flatness (double) as (low, high) words, zw: 0
    uvec4 level_offset[PENUMBRA_LV_MAX_LEVELS / 4];  // first cell of level k at [k / 4][k % 4]
};

// The render (LightVolumeRenderer): uniform buffer binding, storage / texture / image units.
#define PENUMBRA_LV_BINDING_RENDER_PARAMS 2
#define PENUMBRA_LV_AIRLIGHT_UNIT 1       // the airlight table (R32F, GL_LINEAR, CLAMP_TO_EDGE)
#define PENUMBRA_LV_SCENE_DEPTH_UNIT 2    // the camera's depth buffer (window depth; 1 = background)
#define PENUMBRA_LV_ACCUMULATION_UNIT 3   // the accumulation target (RG32F) read by the composite
#define PENUMBRA_LV_LIT_IMAGE 0           // image unit of the engine's lit image (composite)
#define PENUMBRA_LV_SHADOW_MAP_UNIT 4     // the shadow map, for the ray-march baseline (window depth)

/// The render's constants block (std140 == std430, 352 bytes). Positions are relative to the eye
/// (the airlight's float convention): the host subtracts the eye in double.
struct PenumbraLightVolumeRenderParams {
    mat4 light_to_eye;            // lattice NDC -> position relative to the eye: translate(-eye) * inverse(light VP)
    mat4 camera_view_projection;  // (position relative to the eye, 1) -> camera clip space
    mat4 camera_inverse;          // camera NDC -> position relative to the eye (the inverse of the above)
    mat4 eye_to_light;            // position relative to the eye -> the light's clip space (the ray march)
    vec4 light;                   // xyz: light position relative to the eye, w: 0
    vec4 medium;                  // AirlightSetup::shaderMedium (sigma_s, sigma_t, g, intensity)
    vec4 airlight;                // AirlightSetup::shaderParams (W, H, min_distance, method)
    vec4 colour;                  // rgb: the light's colour the airlight is multiplied by, w: 0
    uvec4 size;                   // x: shadow-map resolution R, y: viewport width, z: viewport height, w: 0
    uvec4 march;                  // x: ray-march steps, yzw: 0
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
