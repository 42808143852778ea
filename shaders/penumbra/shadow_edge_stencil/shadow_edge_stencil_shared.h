// penumbra — shadow-edge stencil (galoppo2010) constants and the parameter block shared by C++
// (include/penumbra/shadow_edge_stencil.hpp, gl/shadow_edge_stencil.hpp) and GLSL
// (shaders/penumbra/shadow_edge_stencil/*). Valid as both (STYLE.md habit 2): std140 == std430, no
// vec3 members, explicit padding; the host static_asserts the size.
#ifndef PENUMBRA_SHADOW_EDGE_STENCIL_SHARED_H
#define PENUMBRA_SHADOW_EDGE_STENCIL_SHARED_H

#ifdef __cplusplus
namespace penumbra::shared {
#endif

#define PENUMBRA_AA_MAX_SAMPLES 64
#define PENUMBRA_AA_GROUP_SIZE 64

// The stencil word per pixel (stencil() after a run: only FLAG, SHADOWED and LIT remain).
#define PENUMBRA_AA_FLAG 1u         // multi-sample this pixel
#define PENUMBRA_AA_SHADOWED 2u     // unflagged and every point shadowed (a cover, or all light-back-facing)
#define PENUMBRA_AA_ACTIVE 4u       // internal: classified against the casters
#define PENUMBRA_AA_SPLIT 8u        // internal: some triangle blocks some but not all of its points
#define PENUMBRA_AA_COVERED 16u     // internal: some triangle blocks all of its points
#define PENUMBRA_AA_LIT 32u         // unflagged and every point lit (classified: no triangle blocks any point)

// Uniform buffer: the conservative emitter's block is binding 0, this block binding 1.
#define PENUMBRA_AA_BINDING_PARAMS 1
// Shader storage (one meaning per binding within a kernel; see each entry shader):
#define PENUMBRA_AA_BINDING_CENTRES 0      // vec4 [P]: the view samples (w == 0: none)
#define PENUMBRA_AA_BINDING_NORMALS 1      // vec4 [P]: face normals (xyz)
#define PENUMBRA_AA_BINDING_STATUS 1       // uint [PENUMBRA_AA_STATUS_WORDS] (kernels that read no normals)
#define PENUMBRA_AA_BINDING_SUB_SAMPLES 2  // vec4 [P * N]: pixel i's sub-sample k at i * N + k
#define PENUMBRA_AA_BINDING_STENCIL 3      // uint [P]: the stencil word
#define PENUMBRA_AA_BINDING_FOOTPRINTS 4   // PenumbraAaFootprint [P]
#define PENUMBRA_AA_BINDING_COUNTS 5       // uint [W * H + 1]: footprints per light texel, then offsets (scan)
#define PENUMBRA_AA_BINDING_CURSOR 6       // uint [W * H]: scatter cursors
#define PENUMBRA_AA_BINDING_LIST 7         // uint [list capacity]: pixel ids per light texel
#define PENUMBRA_AA_BINDING_OUT_POSITIONS 4  // sample-buffer kernel: vec4 [sampleCount(mode, budget)]
#define PENUMBRA_AA_BINDING_OUT_NORMALS 5    // sample-buffer kernel: vec4 [sampleCount(mode, budget)]
#define PENUMBRA_AA_BINDING_STATES 4         // resolve kernel: uint states of the hard pipeline
#define PENUMBRA_AA_BINDING_VISIBLE 5        // resolve kernel: float [P]
#define PENUMBRA_AA_BINDING_RANKS 6          // ranks, sample-buffer, resolve: uint [P + 1], flagged pixels before each
// The Chebyshev stencil's moment map (moments.* and chebyshev.comp.glsl):
#define PENUMBRA_AA_BINDING_MIN_DEPTH 4      // uint [W * H]: ordered bits of the least float depth (atomicMin)
#define PENUMBRA_AA_BINDING_MIN_COVER 5      // uint [W * H]: ordered bits of the least cover value
#define PENUMBRA_AA_BINDING_MOMENTS 6        // vec2 per texel, every level one after another (E(x), E(x^2))
#define PENUMBRA_AA_BINDING_COVERS 7         // float per texel, every level (inner coverage)

// Status words (statusWords(): a read-back for tests and tools).
#define PENUMBRA_AA_STATUS_LIST_ENTRIES 0   // footprint-texel entries the setup counted
#define PENUMBRA_AA_STATUS_LIST_OVERFLOW 1  // entries over the list capacity (their pixels are flagged: safe)
#define PENUMBRA_AA_STATUS_PAIRS 2          // (footprint, triangle) pairs classified
#define PENUMBRA_AA_STATUS_EXACT 3          // exact point tests of undecided pairs
#define PENUMBRA_AA_STATUS_BUDGET_OVERFLOW 4  // flagged pixels past the edge layout's budget (resolve: single-sampled)
#define PENUMBRA_AA_STATUS_WORDS 8

#define PENUMBRA_AA_MODE_OFF 0u
#define PENUMBRA_AA_MODE_EDGE 1u
#define PENUMBRA_AA_MODE_FULL 2u
#define PENUMBRA_AA_MODE_EDGE_PROVEN 3u  // edge, unflagged pixels' states from the provable stencil's word

/// One pixel's footprint as the light pass reads it (64 bytes, std430).
struct PenumbraAaFootprint {
    dvec4 sphere;  // xyz: the centre sample (double of the float), w: radius over its points
    ivec4 box;     // light-texel box x0, y0, x1, y1 (inclusive)
    ivec4 pad;
};

/// The constants of every shadow-edge-stencil kernel (std140 == std430, 960 bytes).
struct PenumbraAaParams {
    dvec4 inverse_view_projection[4];  // view clip -> world, columns (double of the engine's float matrix)
    dvec4 light_view_projection[4];    // world -> light clip, columns (double of the float matrix): binning
    dvec4 numbers;                     // x: coplanar epsilon, y: directional reach, z: view clip z of the near plane, w: scene extent E (the exact test's coplanar scale cap)
    mat4 light_clip;                   // the same light matrix in float: the casters' raster
    vec4 light;                        // w = 1: point light position; w = 0: direction towards the light
    vec4 offsets[PENUMBRA_AA_MAX_SAMPLES / 2];  // sub-sample offsets (pixels), two per vec4 (xy, zw)
    uvec4 view;                        // x: width, y: height, z: N, w: 1 = cull light-back-facing samples
    uvec4 grid;                        // x: light grid W, y: H, z: list capacity, w: mode (PENUMBRA_AA_MODE_*)
    uvec4 limits;                      // x: max footprint texels, y: max list length per texel, z: edge-mode budget (pixels), w: 0
    vec4 chebyshev;                    // x: threshold, y: bias_scale, z: min_variance, w: d_far (empty texels)
    uvec4 moments;                     // x: levels, y: 1 = inner_shadow_proof, z: 1 = perspective light, w: the level a mip pass writes
};

#ifdef __cplusplus
}  // namespace penumbra::shared
#endif

#endif
