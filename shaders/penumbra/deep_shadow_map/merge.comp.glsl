// penumbra — deep shadow map build: the merge of one texel's sub-sample functions (lokovic2000 §5.1)
// streamed into the compressor (§3.3); the twin of detail::dsmMergeTexel + DsmCompressor. A binary
// heap over the contributing sub-sample lists keyed by (depth, list); each event subtracts the
// sub-sample's old contribution, V -= (w_j T_j) alpha, T_j *= 1 - alpha; one vertical step per
// distinct depth. PENUMBRA_DSM_PASS 0 writes the texel's compressed vertex count (scanned next into
// the level's offsets), 1 writes the vertices. One invocation per texel.
// penumbra-permutation: PENUMBRA_DSM_PASS=0 PENUMBRA_DSM_CHANNELS=1 PENUMBRA_DSM_MERGE_LISTS=16
// penumbra-permutation: PENUMBRA_DSM_PASS=1 PENUMBRA_DSM_CHANNELS=3 PENUMBRA_DSM_MERGE_LISTS=144
#include "penumbra/deep_shadow_map/deep_shadow_map_shared.h"
#include "penumbra/deep_shadow_map/deep_shadow_map.glsl"

#ifndef PENUMBRA_DSM_PASS
#error penumbra/deep_shadow_map/merge.comp.glsl needs PENUMBRA_DSM_PASS (0 count, 1 write)
#endif
#ifndef PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_CHANNELS 1
#endif
#ifndef PENUMBRA_DSM_MERGE_LISTS
#error penumbra/deep_shadow_map/merge.comp.glsl needs PENUMBRA_DSM_MERGE_LISTS ((2 reach + 1)^2 S, DsmSetup::merge_lists)
#endif
#if PENUMBRA_DSM_CHANNELS == 3
#define PENUMBRA_DSM_STRIDE 2u
#else
#define PENUMBRA_DSM_STRIDE 1u
#endif

layout(local_size_x = PENUMBRA_DSM_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_DSM_BINDING_PARAMS) uniform PenumbraDsmParamsBlock { PenumbraDsmParams penumbraDsmParams; };
layout(std430, binding = PENUMBRA_DSM_BINDING_PATTERNS) readonly buffer PenumbraDsmPatterns { vec2 penumbraDsmPatterns[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_COUNTS) readonly buffer PenumbraDsmOffsets { uint penumbraDsmOffsets[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_RECORDS) readonly buffer PenumbraDsmRecords { uvec4 penumbraDsmRecords[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_STATUS) buffer PenumbraDsmStatus { uint penumbraDsmStatus[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_MAP_OFFSETS) buffer PenumbraDsmMapOffsets { uint penumbraDsmMapOffsets[]; };
layout(std430, binding = PENUMBRA_DSM_BINDING_MAP_VERTICES) writeonly buffer PenumbraDsmMapVertices { uint penumbraDsmMapWords[]; };

uint penumbraDsmOut = 0u;  // write pass: the texel's first vertex (floats / (1 + C))

#if PENUMBRA_DSM_PASS == 1
#define PENUMBRA_DSM_STORE_WORD(index, word) penumbraDsmMapWords[index] = (word)
#define PENUMBRA_DSM_STORE_OVERFLOW() atomicAdd(penumbraDsmStatus[PENUMBRA_DSM_STATUS_VERTEX_OVERFLOW], 1u)
#include "penumbra/deep_shadow_map/store.glsl"
#define PENUMBRA_DSM_COMPRESS_EMIT(index, z, v) penumbraDsmStoreVertex(penumbraDsmOut + (index), penumbraDsmParams.capacity.y, z, v)
#else
#define PENUMBRA_DSM_COMPRESS_EMIT(index, z, v)
#endif
#include "penumbra/deep_shadow_map/compress.glsl"

uint penumbraDsmCur[PENUMBRA_DSM_MERGE_LISTS];
uint penumbraDsmEnd[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmW[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmT[PENUMBRA_DSM_MERGE_LISTS * PENUMBRA_DSM_CHANNELS];
uint penumbraDsmHeap[PENUMBRA_DSM_MERGE_LISTS];
// The medium, per list: entry depth, span, sigma_t k, current segment (start, value, slope), next
// medium vertex depth (+inf: none) and index.
float penumbraDsmZin[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmZspan[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmSk[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmSegZ[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmSegM[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmSegS[PENUMBRA_DSM_MERGE_LISTS];
float penumbraDsmZm[PENUMBRA_DSM_MERGE_LISTS];
uint penumbraDsmMi[PENUMBRA_DSM_MERGE_LISTS];
uint penumbraDsmK = 0u;
uint penumbraDsmHeapSize = 0u;

float penumbraDsmFragmentZ(uint list) {
    return penumbraDsmCur[list] < penumbraDsmEnd[list] ? uintBitsToFloat(penumbraDsmRecords[penumbraDsmCur[list] * PENUMBRA_DSM_STRIDE].x)
                                                       : uintBitsToFloat(0x7F800000u);
}
float penumbraDsmZ(uint list) { return min(penumbraDsmFragmentZ(list), penumbraDsmZm[list]); }

float penumbraDsmMediumZ(uint list, uint i) {
    precise float f = float(i) / float(penumbraDsmK);
    precise float z = penumbraDsmZin[list] + penumbraDsmZspan[list] * f;
    return z;
}

bool penumbraDsmLess(uint a, uint b) {
    float za = penumbraDsmZ(a), zb = penumbraDsmZ(b);
    return za < zb || (za == zb && a < b);
}

void penumbraDsmSiftDown(uint i) {
    for (;;) {
        uint m = i, l = 2u * i + 1u, r = l + 1u;
        if (l < penumbraDsmHeapSize && penumbraDsmLess(penumbraDsmHeap[l], penumbraDsmHeap[m])) m = l;
        if (r < penumbraDsmHeapSize && penumbraDsmLess(penumbraDsmHeap[r], penumbraDsmHeap[m])) m = r;
        if (m == i) return;
        uint t = penumbraDsmHeap[i];
        penumbraDsmHeap[i] = penumbraDsmHeap[m];
        penumbraDsmHeap[m] = t;
        i = m;
    }
}

void penumbraDsmStep(float z, float before[PENUMBRA_DSM_CHANNELS], float v[PENUMBRA_DSM_CHANNELS], bool kink) {
    bool step = false;
    for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) step = step || v[c] != before[c];
    // One call site of the compressor (it is large once inlined): a step passes both sides.
    int points = step ? 2 : (kink ? 1 : 0);
    for (int j = 0; j < points; ++j) {
        float p[PENUMBRA_DSM_CHANNELS];
        for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) p[c] = step && j == 0 ? before[c] : v[c];
        penumbraDsmCompressAdd(z, p);
    }
}

void main() {
    int R = int(penumbraDsmParams.size.x);
    uint S = penumbraDsmParams.size.y;
    uint texel = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * gl_WorkGroupSize.x;
    if (texel >= uint(R * R)) return;
    int x = int(texel % uint(R)), y = int(texel / uint(R));
    int reach = int(penumbraDsmParams.filtering.y);
    float radius = penumbraDsmParams.numbers.y, inv_r2 = penumbraDsmParams.numbers.z;
    bool box = penumbraDsmParams.filtering.x == uint(PENUMBRA_DSM_FILTER_BOX);
    uint cap = penumbraDsmParams.capacity.x;
    uint gauss = uint(PENUMBRA_DSM_PATTERNS) * S;  // the Gaussian table follows the patterns
    uint n = 0u;
    float total = 0.0;
    penumbraDsmK = penumbraDsmParams.flags.z;
    for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx) {
            int nx = x + dx, ny = y + dy;
            if (nx < 0 || ny < 0 || nx >= R || ny >= R) continue;
            uint pattern = penumbraDsmPattern(uint(nx), uint(ny));
            for (uint j = 0u; j < S; ++j) {
                vec2 o = penumbraDsmPatterns[pattern * S + j];
                precise float rx = (float(dx) + o.x) - 0.5;
                precise float ry = (float(dy) + o.y) - 0.5;
                float w;
                if (box) {
                    if (!(abs(rx) <= radius && abs(ry) <= radius)) continue;
                    w = 1.0;
                } else {
                    precise float q = (rx * rx + ry * ry) * inv_r2;
                    if (!(q <= 1.0)) continue;
                    precise float qi = q * float(PENUMBRA_DSM_GAUSS_TABLE);
                    w = penumbraDsmPatterns[gauss + min(uint(PENUMBRA_DSM_GAUSS_TABLE) - 1u, uint(qi))].x;
                }
                precise float t = total + w;
                total = t;
                uint k = (uint(ny) * uint(R) + uint(nx)) * S + j;
                penumbraDsmCur[n] = min(penumbraDsmOffsets[k], cap);
                penumbraDsmEnd[n] = min(penumbraDsmOffsets[k + 1u], cap);
                penumbraDsmW[n] = w;
                for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) penumbraDsmT[n * uint(PENUMBRA_DSM_CHANNELS) + uint(c)] = 1.0;
                penumbraDsmZin[n] = 0.0;
                penumbraDsmZspan[n] = 0.0;
                penumbraDsmSk[n] = 0.0;
                penumbraDsmSegZ[n] = 0.0;
                penumbraDsmSegS[n] = 0.0;
                penumbraDsmSegM[n] = 1.0;
                penumbraDsmZm[n] = uintBitsToFloat(0x7F800000u);
                penumbraDsmMi[n] = penumbraDsmK + 1u;
                if (penumbraDsmK > 0u) {
                    precise float sx = float(nx) + o.x;
                    precise float sy = float(ny) + o.y;
                    precise float px = sx * penumbraDsmParams.numbers.x - 1.0;
                    precise float py = sy * penumbraDsmParams.numbers.x - 1.0;
                    vec4 span = penumbraDsmMediumSpan(penumbraDsmParams.inverse_view_projection, penumbraDsmParams.depth_row,
                                                      penumbraDsmParams.medium_lo, penumbraDsmParams.medium_hi, px, py);
                    if (span.w != 0.0) {
                        penumbraDsmZin[n] = span.x;
                        precise float zspan = span.y - span.x;
                        penumbraDsmZspan[n] = zspan;
                        penumbraDsmSk[n] = span.z;
                        penumbraDsmMi[n] = 0u;
                        penumbraDsmZm[n] = span.x;
                    }
                }
                ++n;
            }
        }
    penumbraDsmCompressBegin(penumbraDsmParams.numbers.w);
#if PENUMBRA_DSM_PASS == 1
    penumbraDsmOut = penumbraDsmMapOffsets[texel];
#endif
    if (n > 0u) {
        for (uint i = 0u; i < n; ++i) {
            precise float wn = penumbraDsmW[i] / total;
            penumbraDsmW[i] = wn;
        }
        penumbraDsmHeapSize = 0u;
        for (uint i = 0u; i < n; ++i)
            if (penumbraDsmCur[i] < penumbraDsmEnd[i] || penumbraDsmZm[i] < uintBitsToFloat(0x7F800000u))
                penumbraDsmHeap[penumbraDsmHeapSize++] = i;
        for (uint i = penumbraDsmHeapSize / 2u; i-- > 0u;) penumbraDsmSiftDown(i);
        float v[PENUMBRA_DSM_CHANNELS], before[PENUMBRA_DSM_CHANNELS], slope[PENUMBRA_DSM_CHANNELS];
        for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
            v[c] = 1.0;
            before[c] = 1.0;
            slope[c] = 0.0;
        }
        bool pending = false, kink = false, have_prev = false;
        float z_group = 0.0, z_prev = 0.0;
        while (penumbraDsmHeapSize > 0u) {
            uint li = penumbraDsmHeap[0];
            float zf = penumbraDsmFragmentZ(li);
            bool medium_event = penumbraDsmZm[li] <= zf;
            float z = medium_event ? penumbraDsmZm[li] : zf;
            if (pending && z != z_group) {
                penumbraDsmStep(z_group, before, v, kink);
                pending = false;
            }
            if (!pending) {
                pending = true;
                kink = false;
                z_group = z;
                if (penumbraDsmK > 0u && have_prev) {
                    for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
                        precise float e = v[c] + min(slope[c], 0.0) * (z - z_prev);
                        v[c] = max(0.0, min(v[c], e));
                    }
                }
                z_prev = z;
                have_prev = true;
                for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) before[c] = v[c];
            }
            bool alive = false;
            if (medium_event) {
                precise float xm = penumbraDsmSk[li] * (penumbraDsmZm[li] - penumbraDsmZin[li]);
                float m = penumbraDsmExpNeg(xm);
                float s_new = 0.0;
                if (penumbraDsmMi[li] < penumbraDsmK) {
                    float z_next = penumbraDsmMediumZ(li, penumbraDsmMi[li] + 1u);
                    precise float xn = penumbraDsmSk[li] * (z_next - penumbraDsmZin[li]);
                    float m_next = penumbraDsmExpNeg(xn);
                    precise float dz = z_next - penumbraDsmZm[li];
                    precise float sn = (m_next - m) / dz;
                    s_new = dz > 0.0 ? sn : 0.0;
                }
                for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
                    uint ti = li * uint(PENUMBRA_DSM_CHANNELS) + uint(c);
                    precise float wt = penumbraDsmW[li] * penumbraDsmT[ti];
                    precise float ns = slope[c] + wt * (s_new - penumbraDsmSegS[li]);
                    slope[c] = ns;
                    alive = alive || penumbraDsmT[ti] > 0.0;
                }
                penumbraDsmSegZ[li] = penumbraDsmZm[li];
                penumbraDsmSegM[li] = m;
                penumbraDsmSegS[li] = s_new;
                penumbraDsmMi[li]++;
                penumbraDsmZm[li] = penumbraDsmMi[li] <= penumbraDsmK ? penumbraDsmMediumZ(li, penumbraDsmMi[li]) : uintBitsToFloat(0x7F800000u);
                kink = true;
            } else {
                uint rec = penumbraDsmCur[li] * PENUMBRA_DSM_STRIDE;
                uvec4 r0 = penumbraDsmRecords[rec];
                vec3 alpha;
#if PENUMBRA_DSM_CHANNELS == 3
                alpha = vec3(uintBitsToFloat(r0.z), uintBitsToFloat(r0.w), uintBitsToFloat(penumbraDsmRecords[rec + 1u].x));
#else
                alpha = vec3(uintBitsToFloat(r0.z), 0.0, 0.0);
#endif
                precise float mzl = penumbraDsmSegM[li] + penumbraDsmSegS[li] * (z - penumbraDsmSegZ[li]);
                float mz = penumbraDsmMi[li] == 0u ? 1.0 : mzl;
                for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
                    uint ti = li * uint(PENUMBRA_DSM_CHANNELS) + uint(c);
                    float a = alpha[c];
                    precise float wta = (penumbraDsmW[li] * penumbraDsmT[ti]) * a;
                    precise float nv = v[c] - wta * mz;
                    v[c] = max(0.0, nv);
                    precise float ns = slope[c] - wta * penumbraDsmSegS[li];
                    slope[c] = ns;
                    precise float nt = penumbraDsmT[ti] * (1.0 - a);
                    penumbraDsmT[ti] = nt;
                    alive = alive || nt > 0.0;
                }
                if (penumbraDsmSegS[li] != 0.0) kink = true;
                penumbraDsmCur[li]++;
            }
            if ((penumbraDsmCur[li] < penumbraDsmEnd[li] || penumbraDsmZm[li] < uintBitsToFloat(0x7F800000u)) && alive) {
                penumbraDsmSiftDown(0u);
            } else {
                penumbraDsmHeap[0] = penumbraDsmHeap[penumbraDsmHeapSize - 1u];
                penumbraDsmHeapSize--;
                if (penumbraDsmHeapSize > 0u) penumbraDsmSiftDown(0u);
            }
        }
        if (pending) penumbraDsmStep(z_group, before, v, kink);
    }
    penumbraDsmCompressFinish();
#if PENUMBRA_DSM_PASS == 0
    penumbraDsmMapOffsets[texel] = penumbraDsmCCount;
    if (texel == 0u) penumbraDsmMapOffsets[uint(R * R)] = 0u;
#endif
}
