// penumbra — deep shadow map constants and blocks shared by C++ (include/penumbra/deep_shadow_map.hpp)
// and GLSL (shaders/penumbra/deep_shadow_map/*). Valid as both (STYLE.md habit 2): std140 == std430,
// no vec3 members, explicit padding; the host static_asserts every size.
#ifndef PENUMBRA_DEEP_SHADOW_MAP_SHARED_H
#define PENUMBRA_DEEP_SHADOW_MAP_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

// Limits the options are checked against (DsmOptions, deepShadowMapSetup).
#define PENUMBRA_DSM_MAX_RESOLUTION 4096
#define PENUMBRA_DSM_MAX_SAMPLES 1024
#define PENUMBRA_DSM_PATTERNS 16
// Sub-sample lists one texel's merge walks at once ((2 reach + 1)^2 * S): the per-invocation heap,
// cursors and transmittances of the GPU merge are private arrays of this size.
#define PENUMBRA_DSM_MAX_MERGE_LISTS 1024
#define PENUMBRA_DSM_GAUSS_TABLE 256
#define PENUMBRA_DSM_MAX_LEVELS 13
// Candidate start values per channel of each segment the compressor tries (DsmCompressor,
// compress.glsl), a power of two: more find longer segments (fewer vertices) at K times the
// compression work.
#define PENUMBRA_DSM_CANDIDATES 4

#define PENUMBRA_DSM_FILTER_BOX 0
#define PENUMBRA_DSM_FILTER_GAUSSIAN 1

#define PENUMBRA_DSM_GROUP_SIZE 64

#define PENUMBRA_DSM_OPACITY_MESH 0      // PenumbraDsmParams::opacity
#define PENUMBRA_DSM_OPACITY_TRIANGLE 1  // one vec4 per triangle (PENUMBRA_DSM_BINDING_TRIANGLE_OPACITY)
#define PENUMBRA_DSM_OPACITY_VERTEX 2    // vertex attribute 1 (vec3), interpolated like the depth
// The hook: vertex attribute 1 (vec3, e.g. texture coordinates), interpolated like the depth, handed
// with the triangle's index to penumbraDsmOpacityHook (penumbra/deep_shadow_map/opacity_hook.glsl:
// replace that file in your ShaderLibrary; the default reads the texture on unit
// PENUMBRA_DSM_OPACITY_TEXTURE_UNIT at uv = attribute.xy, nearest, repeat); its result is clamped
// to [0, 1] per channel, NaN -> 0.
#define PENUMBRA_DSM_OPACITY_HOOK 3
#define PENUMBRA_DSM_OPACITY_TEXTURE_UNIT 0

// Default bindings (DsmBindings can move them). Uniform buffers: the conservative emitter's block
// is binding 0 (PENUMBRA_CONSERVATIVE_PARAMS_BINDING), this block binding 1. Shader storage:
#define PENUMBRA_DSM_BINDING_PARAMS 1
#define PENUMBRA_DSM_BINDING_PATTERNS 0          // vec2 offsets[PATTERNS * S], then the Gaussian table (as vec2.x)
#define PENUMBRA_DSM_BINDING_COUNTS 1            // uint per sub-sample list (+1): counts, then offsets in place
#define PENUMBRA_DSM_BINDING_CURSOR 2            // uint per sub-sample list: scatter cursors
#define PENUMBRA_DSM_BINDING_RECORDS 3           // uvec4 per fragment (z, triangle, alpha r, alpha g); colour: + uvec4 (alpha b)
#define PENUMBRA_DSM_BINDING_TRIANGLE_OPACITY 4  // vec4 per triangle
#define PENUMBRA_DSM_BINDING_STATUS 5            // uint[PENUMBRA_DSM_STATUS_WORDS]
#define PENUMBRA_DSM_BINDING_MAP_OFFSETS 6       // uint: per level (R_l^2 + 1) local vertex offsets
#define PENUMBRA_DSM_BINDING_MAP_VERTICES 7      // float: (1 + channels) per vertex, levels one after another

// Status words (the header the GPU build writes; the integrator may read it back after a frame).
#define PENUMBRA_DSM_STATUS_FRAGMENTS 0         // fragments the casters produced
#define PENUMBRA_DSM_STATUS_FRAGMENT_OVERFLOW 1  // fragments dropped: over the fragment capacity
#define PENUMBRA_DSM_STATUS_VERTICES 2          // compressed vertices of level 0
#define PENUMBRA_DSM_STATUS_VERTEX_OVERFLOW 3   // vertices dropped: over the vertex capacity
#define PENUMBRA_DSM_STATUS_MERGE_OVERFLOW 4    // texels whose merge exceeded the per-invocation limits
#define PENUMBRA_DSM_STATUS_WORDS 8

/// The constants block of every deep-shadow-map kernel (std140 == std430, 272 bytes).
struct PenumbraDsmParams {
    mat4 light_view_projection;  // clip = light_view_projection * (p, 1) (float, fixed order, no FMA)
    mat4 inverse_view_projection;  // its inverse (host, float): the sub-sample rays of the medium
    vec4 medium_lo;              // medium box min (xyz), w: sigma_t (0 = no medium)
    vec4 medium_hi;              // medium box max (xyz), w: 0
    vec4 depth_row;              // light depth d = ((r.x x + r.y y) + r.z z) + r.w: distance along the light's axis
    vec4 opacity;                // per-mesh opacity (rgb; a = unused) when no per-triangle / per-vertex opacity
    uvec4 size;                  // x: resolution R, y: samples S, z: channels (1 or 3), w: level count
    uvec4 filtering;               // x: PENUMBRA_DSM_FILTER_*, y: reach (texels), z: merge lists (2 reach + 1)^2 S, w: level
    vec4 numbers;                // x: 2 / R (NDC per pixel), y: filter radius, z: 1 / radius^2, w: tolerance (inner) of this level
    uvec4 capacity;              // x: fragment capacity, y: vertex capacity, z: level texel offset, w: level resolution
    uvec4 flags;                 // x: opacity source (PENUMBRA_DSM_OPACITY_*), y: pass (0 count, 1 write), z: medium samples K (0 = none), w: 0
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
