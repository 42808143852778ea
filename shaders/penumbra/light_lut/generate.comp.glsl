// penumbra — the light-sample LUT generator (sintorn2008 §4.2, Fig. 6): the GPU twin of
// penumbra::generateLightLut (include/penumbra/light_lut.hpp), byte for byte. Driven by
// penumbra::LightLutGenerator (include/penumbra/gl/light_lut.hpp); engines normally never bind it.
//
// Work split: one work group of 64 invocations per (table, normal cell, chunk of 64 distance
// cells). The group first computes, for every sample b of the table, t_b = dot(q_b, n_c),
// k_b = (rho^2 / 2) |t_b| and reach2_b = rho^2 (|q_b|^2 - t_b^2) + 1e-12 into shared memory (the
// CPU generator's per-normal-cell reuse, same operations), then invocation l answers distance cell
// k = first + 64 * chunk + l: centre bit b if v = t_b + d_c < 0, uncertain bit b unless
// a = (|v| - k_b) - h > 0 and a * a > reach2_b. Every operation is an fp64 +, * or compare written
// as in detail::light_lut::texel(), with every product rounded (`precise`: no fused multiply-add).
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
// glShaderStorageBlockBinding / glUniformBlockBinding for penumbra::LightLutBindings); the
// uncertain window is bound only in certified mode.
#include "penumbra/light_lut/light_lut_shared.h"
#include "penumbra/common/dispatch.glsl"

#define PENUMBRA_LUT_GENERATE_GROUP_SIZE 64u

layout(local_size_x = 64) in;

layout(std140, binding = PENUMBRA_LUT_BINDING_PARAMS) uniform PenumbraLutParamsBlock {
    PenumbraLutParams penumbraLutParams;
};
layout(std430, binding = PENUMBRA_LUT_BINDING_SAMPLES) readonly buffer PenumbraLutSamplesBlock {
    dvec4 penumbraLutSamples[];  // 128 per table from the first table: x, y, z, |q|^2 rounded up
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

// kReachMargin of light_lut.hpp.
#define PENUMBRA_LUT_REACH_MARGIN 1e-12lf

shared double penumbraLutSharedT[PENUMBRA_LUT_SAMPLES_PER_TABLE];
shared double penumbraLutSharedK[PENUMBRA_LUT_SAMPLES_PER_TABLE];
shared double penumbraLutSharedReach2[PENUMBRA_LUT_SAMPLES_PER_TABLE];

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
    precise double rho2 = nc.w * nc.w;
    precise double half_rho2 = 0.5lf * rho2;
    for (uint b = gl_LocalInvocationID.x; b < count; b += PENUMBRA_LUT_GENERATE_GROUP_SIZE) {
        const dvec4 s = penumbraLutSamples[local_table * 128u + b];
        precise double t = (s.x * nc.x + s.y * nc.y) + s.z * nc.z;
        precise double k = half_rho2 * abs(t);
        precise double reach2 = rho2 * (s.w - t * t) + PENUMBRA_LUT_REACH_MARGIN;
        penumbraLutSharedT[b] = t;
        penumbraLutSharedK[b] = k;
        penumbraLutSharedReach2[b] = reach2;
    }
    barrier();

    const uint local_k = chunk * PENUMBRA_LUT_GENERATE_GROUP_SIZE + gl_LocalInvocationID.x;
    if (local_k >= penumbraLutDispatch.z) return;
    const dvec2 dc = penumbraLutDistanceCells[penumbraLutDispatch.y + local_k];
    uvec4 centre = uvec4(0u), uncertain = uvec4(0u);
    for (uint b = 0u; b < count; ++b) {
        precise double v = penumbraLutSharedT[b] + dc.x;
        precise double a = (abs(v) - penumbraLutSharedK[b]) - dc.y;
        precise double a2 = a * a;
        const uint bit = 1u << (b & 31u);
        if (v < 0.0lf) centre[b >> 5u] |= bit;
        if (!(a > 0.0lf && a2 > penumbraLutSharedReach2[b])) uncertain[b >> 5u] |= bit;
    }
    const uint at = local_table * penumbraLutParams.texels_per_table + local_k * cells + cell;
    penumbraLutCentreMasks[at] = centre;
    if ((penumbraLutParams.flags & uint(PENUMBRA_LUT_FLAG_CERTIFIED)) != 0u) penumbraLutUncertainMasks[at] = uncertain;
}
