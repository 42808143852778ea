// penumbra — the light-sample LUT generator (sintorn2008 §4.2, Fig. 6): the GPU twin of
// penumbra::generateLightLut (include/penumbra/light_lut.hpp), byte for byte. Driven by
// penumbra::LightLutGenerator (include/penumbra/gl/light_lut.hpp); engines normally never bind it.
//
// Work split: one work group of 64 invocations per (table, normal cell, chunk of 64 distance
// cells). The group first computes, for every sample b of the table, t_b = dot(q_b, n_c) and
// w_b = rho * |q_b| into shared memory (the CPU generator's per-normal-cell reuse, same operations),
// then invocation l answers distance cell k = first + 64 * chunk + l: centre bit b if
// t_b + d_c < 0, uncertain bit b if !(|t_b + d_c| > w_b + h). Every operation is an fp64 +, * or
// compare written as in detail::light_lut::texel(): t = (s.x*nc.x + s.y*nc.y) + s.z*nc.z with every
// product rounded (`precise`: no fused multiply-add), v = t + dc.x, w = nc.w*s.w + dc.y.
//
// Dispatch (the host plans it at reserve(); one uniform per dispatch, no other state):
//   penumbraLutDispatch = (first table, first distance cell, distance cells, work groups);
//   groups = tables x R_n^2 x ceil(distance cells / 64), folded into a 2D grid (dispatch.glsl).
// The bound ranges are windows that start at the dispatch's first table (samples) or at its first
// texel (first table, first distance cell) of the centre and the uncertain masks, so no binding
// exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE: texel (table, k, cell) is written at
// (table - first table) * texels_per_table + (k - first k) * R_n^2 + cell of each window.
//
// Bindings: PENUMBRA_LUT_BINDING_* of light_lut_shared.h (the host re-points the blocks with
// glShaderStorageBlockBinding / glUniformBlockBinding for penumbra::LightLutBindings) and
// PENUMBRA_LUT_BINDING_UNCERTAIN below (the uncertain window; bound only in certified mode).
#include "penumbra/light_lut/light_lut_shared.h"
#include "penumbra/common/dispatch.glsl"

// The uncertain masks' window (light_lut_shared.h has no binding for it).
#ifndef PENUMBRA_LUT_BINDING_UNCERTAIN
#define PENUMBRA_LUT_BINDING_UNCERTAIN 4
#endif

#define PENUMBRA_LUT_GENERATE_GROUP_SIZE 64u

layout(local_size_x = 64) in;

layout(std140, binding = PENUMBRA_LUT_BINDING_PARAMS) uniform PenumbraLutParamsBlock {
    PenumbraLutParams penumbraLutParams;
};
layout(std430, binding = PENUMBRA_LUT_BINDING_SAMPLES) readonly buffer PenumbraLutSamplesBlock {
    dvec4 penumbraLutSamples[];  // 128 per table from the first table: x, y, z, |q| rounded up
};
layout(std430, binding = PENUMBRA_LUT_BINDING_NORMAL_CELLS) readonly buffer PenumbraLutNormalCellsBlock {
    dvec4 penumbraLutNormalCells[];  // R_n^2: centre normal, rho
};
layout(std430, binding = PENUMBRA_LUT_BINDING_DISTANCE_CELLS) readonly buffer PenumbraLutDistanceCellsBlock {
    dvec2 penumbraLutDistanceCells[];  // R_d: centre d, half width + margins
};
layout(std430, binding = PENUMBRA_LUT_BINDING_TABLE) writeonly buffer PenumbraLutCentreBlock {
    uvec4 penumbraLutCentreMasks[];
};
layout(std430, binding = PENUMBRA_LUT_BINDING_UNCERTAIN) writeonly buffer PenumbraLutUncertainBlock {
    uvec4 penumbraLutUncertainMasks[];
};

// x: first table, y: first distance cell, z: distance cells, w: work groups of this dispatch.
layout(location = 0) uniform uvec4 penumbraLutDispatch;

shared double penumbraLutSharedT[PENUMBRA_LUT_SAMPLES_PER_TABLE];
shared double penumbraLutSharedW[PENUMBRA_LUT_SAMPLES_PER_TABLE];

void main() {
    const uint group = penumbraLinearGroup();
    if (group >= penumbraLutDispatch.w) return;  // uniform per group: before the barrier
    const uint rn = penumbraLutParams.resolution_normal;
    const uint cells = rn * rn;
    const uint chunks = (penumbraLutDispatch.z + PENUMBRA_LUT_GENERATE_GROUP_SIZE - 1u) / PENUMBRA_LUT_GENERATE_GROUP_SIZE;
    const uint cell = group % cells;
    const uint rest = group / cells;
    const uint chunk = rest % chunks;
    const uint local_table = rest / chunks;
    const uint table = penumbraLutDispatch.x + local_table;
    const uint block = table % penumbraLutParams.tables_per_set;
    const uint count = min(uint(PENUMBRA_LUT_SAMPLES_PER_TABLE), penumbraLutParams.samples_per_set - block * 128u);

    const dvec4 nc = penumbraLutNormalCells[cell];
    for (uint b = gl_LocalInvocationID.x; b < count; b += PENUMBRA_LUT_GENERATE_GROUP_SIZE) {
        const dvec4 s = penumbraLutSamples[local_table * 128u + b];
        precise double t = (s.x * nc.x + s.y * nc.y) + s.z * nc.z;
        precise double w = nc.w * s.w;
        penumbraLutSharedT[b] = t;
        penumbraLutSharedW[b] = w;
    }
    barrier();

    const uint local_k = chunk * PENUMBRA_LUT_GENERATE_GROUP_SIZE + gl_LocalInvocationID.x;
    if (local_k >= penumbraLutDispatch.z) return;
    const dvec2 dc = penumbraLutDistanceCells[penumbraLutDispatch.y + local_k];
    uvec4 centre = uvec4(0u), uncertain = uvec4(0u);
    for (uint b = 0u; b < count; ++b) {
        precise double v = penumbraLutSharedT[b] + dc.x;
        precise double w = penumbraLutSharedW[b] + dc.y;
        const uint bit = 1u << (b & 31u);
        if (v < 0.0lf) centre[b >> 5u] |= bit;
        if (!(abs(v) > w)) uncertain[b >> 5u] |= bit;
    }
    const uint at = local_table * penumbraLutParams.texels_per_table + local_k * cells + cell;
    penumbraLutCentreMasks[at] = centre;
    if ((penumbraLutParams.flags & uint(PENUMBRA_LUT_FLAG_CERTIFIED)) != 0u) penumbraLutUncertainMasks[at] = uncertain;
}
