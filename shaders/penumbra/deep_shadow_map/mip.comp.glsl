// penumbra — deep shadow map mip level (lokovic2000 §5.3): texel (x, y) of level L averages texels
// (2x, 2y) .. (2x+1, 2y+1) of level L - 1 at the union of their depths (both one-sided limits) and
// recompresses with the level's tolerance eps / 2^L; the twin of detail::dsmAverageTexel +
// DsmCompressor. PENUMBRA_DSM_PASS 0 writes vertex counts, 1 vertices. One invocation per texel.
// Level l's offsets start at map-offset word level_texel_offset(l) + l (R_l^2 + 1 entries, local:
// 0 .. its vertex total); its vertices follow those of every coarser-indexed level before it.
// penumbra-permutation: PENUMBRA_DSM_PASS=0 PENUMBRA_DSM_CHANNELS=1
// penumbra-permutation: PENUMBRA_DSM_PASS=1 PENUMBRA_DSM_CHANNELS=3
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"
#include "penumbra/deep_shadow_map/deep_shadow_map.glsl"

#ifndef PENUMBRA_DSM_PASS
#error penumbra/deep_shadow_map/mip.comp.glsl needs PENUMBRA_DSM_PASS (0 count, 1 write)
#endif
#ifndef PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_CHANNELS 1
#endif
#define PENUMBRA_DSM_F uint(1 + PENUMBRA_DSM_CHANNELS)

layout(local_size_x = PENUMBRA_DSM_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_DSM_BINDING_PARAMS) uniform PenumbraDsmParamsBlock { PenumbraDsmParams penumbraDsmParams; };
layout(std430, binding = PENUMBRA_DSM_BINDING_STATUS) buffer PenumbraDsmStatus { uint penumbraDsmStatus[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_MAP_OFFSETS) buffer PenumbraDsmMapOffsets { uint penumbraDsmMapOffsets[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_MAP_VERTICES) buffer PenumbraDsmMapVertices { uint penumbraDsmMapWords[]; };

uint penumbraDsmOut = 0u;

#if PENUMBRA_DSM_PASS == 1
#define PENUMBRA_DSM_STORE_WORD(index, word) penumbraDsmMapWords[index] = (word)
#define PENUMBRA_DSM_STORE_OVERFLOW() atomicAdd(penumbraDsmStatus[PENUMBRA_DSM_STATUS_VERTEX_OVERFLOW], 1u)
#include "penumbra/deep_shadow_map/store.glsl"
#define PENUMBRA_DSM_COMPRESS_EMIT(index, z, v) penumbraDsmStoreVertex(penumbraDsmOut + (index), penumbraDsmParams.capacity.y, z, v)
#else
#define PENUMBRA_DSM_COMPRESS_EMIT(index, z, v)
#endif
#include "penumbra/deep_shadow_map/compress.glsl"

uint penumbraDsmFirst[4], penumbraDsmCount[4];

float penumbraDsmVz(uint k, uint i) {
    uint vertex = min(penumbraDsmFirst[k] + i, penumbraDsmParams.capacity.y - 1u);
    return uintBitsToFloat(penumbraDsmMapWords[vertex]);
}
float penumbraDsmVv(uint k, uint i, int c) {
    uint vertex = min(penumbraDsmFirst[k] + i, penumbraDsmParams.capacity.y - 1u);
    uint h = vertex * uint(PENUMBRA_DSM_CHANNELS) + uint(c);
    uint w = penumbraDsmMapWords[penumbraDsmParams.capacity.y + h / 2u];
    return penumbraDsmDecode((h & 1u) != 0u ? (w >> 16u) : (w & 0xFFFFu));
}

void main() {
    uint level = penumbraDsmParams.filtering.w;
    uint r = penumbraDsmParams.capacity.w;
    uint texel = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (texel >= r * r) return;
    uint x = texel % r, y = texel / r;
    uint R0 = penumbraDsmParams.size.x;
    // Vertex bases: level l's vertices start after the totals of levels 0 .. l-1.
    uint child_base = 0u, child_offsets = 0u, texel_offset = 0u;
    for (uint l = 0u; l + 1u < level; ++l) {
        uint rl = R0 >> l;
        child_base += penumbraDsmMapOffsets[texel_offset + l + rl * rl];
        texel_offset += rl * rl;
    }
    uint rc = R0 >> (level - 1u);
    child_offsets = texel_offset + (level - 1u);
    uint own_base = child_base + penumbraDsmMapOffsets[child_offsets + rc * rc];
    uint own_offsets = child_offsets + rc * rc + 1u;
    for (uint k = 0u; k < 4u; ++k) {
        uint t = (2u * y + (k >> 1u)) * rc + (2u * x + (k & 1u));
        uint a = penumbraDsmMapOffsets[child_offsets + t], b = penumbraDsmMapOffsets[child_offsets + t + 1u];
        penumbraDsmFirst[k] = child_base + a;
        penumbraDsmCount[k] = b - a;
    }
    penumbraDsmCompressBegin(penumbraDsmParams.numbers.w);
#if PENUMBRA_DSM_PASS == 1
    penumbraDsmOut = own_base + penumbraDsmMapOffsets[own_offsets + texel];
#endif
    uint cursor[4] = uint[4](0u, 0u, 0u, 0u);
    uint next[4] = uint[4](0u, 0u, 0u, 0u);
    for (;;) {
        float z = uintBitsToFloat(0x7F800000u);
        bool any = false;
        for (uint k = 0u; k < 4u; ++k)
            if (next[k] < penumbraDsmCount[k]) {
                z = min(z, penumbraDsmVz(k, next[k]));
                any = true;
            }
        if (!any) break;
        float l[4 * PENUMBRA_DSM_CHANNELS], rr[4 * PENUMBRA_DSM_CHANNELS];
        for (uint k = 0u; k < 4u; ++k) {
            uint n = penumbraDsmCount[k];
            uint i = cursor[k];
            while (i < n && penumbraDsmVz(k, i) < z) ++i;
            cursor[k] = i;
            uint j = i;
            while (j < n && penumbraDsmVz(k, j) == z) ++j;
            for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
                uint o = k * uint(PENUMBRA_DSM_CHANNELS) + uint(c);
                if (n == 0u) {
                    l[o] = 1.0;
                    rr[o] = 1.0;
                } else if (i < n && penumbraDsmVz(k, i) == z) {
                    l[o] = penumbraDsmVv(k, i, c);
                    rr[o] = penumbraDsmVv(k, j - 1u, c);
                } else if (i == 0u) {
                    l[o] = penumbraDsmVv(k, 0u, c);
                    rr[o] = l[o];
                } else if (i == n) {
                    l[o] = penumbraDsmVv(k, n - 1u, c);
                    rr[o] = l[o];
                } else {
                    float za = penumbraDsmVz(k, i - 1u), zb = penumbraDsmVz(k, i);
                    float va = penumbraDsmVv(k, i - 1u, c), vb = penumbraDsmVv(k, i, c);
                    precise float t = (z - za) / (zb - za);
                    precise float e = va + (vb - va) * t;
                    l[o] = e;
                    rr[o] = e;
                }
            }
            while (next[k] < n && penumbraDsmVz(k, next[k]) <= z) ++next[k];
        }
        float left[PENUMBRA_DSM_CHANNELS], right[PENUMBRA_DSM_CHANNELS];
        bool step = false;
        for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
            uint C = uint(PENUMBRA_DSM_CHANNELS);
            precise float sl = (l[uint(c)] + l[C + uint(c)]) + (l[2u * C + uint(c)] + l[3u * C + uint(c)]);
            precise float sr = (rr[uint(c)] + rr[C + uint(c)]) + (rr[2u * C + uint(c)] + rr[3u * C + uint(c)]);
            precise float al = sl * 0.25;
            precise float ar = sr * 0.25;
            left[c] = al;
            right[c] = ar;
            step = step || ar != al;
        }
        for (int j = 0; j < (step ? 2 : 1); ++j) {  // one call site of the (large) compressor
            float p[PENUMBRA_DSM_CHANNELS];
            for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) p[c] = j == 0 ? left[c] : right[c];
            penumbraDsmCompressAdd(z, p);
        }
    }
    penumbraDsmCompressFinish();
#if PENUMBRA_DSM_PASS == 0
    penumbraDsmMapOffsets[own_offsets + texel] = penumbraDsmCCount;
    if (texel == 0u) penumbraDsmMapOffsets[own_offsets + r * r] = 0u;
#endif
}
