// penumbra — the streaming greedy L-infinity compressor (lokovic2000 §3.3) with a free segment
// start: the twin of penumbra::detail::DsmCompressor<C> (include/penumbra/deep_shadow_map.hpp),
// operation for operation. Each segment tries PENUMBRA_DSM_CANDIDATES start values per channel,
// each with its own slope window; the header explains the rule.
// One compressor per invocation (globals with the penumbraDsmC prefix). The candidate loops have no
// `continue`: with one, llvmpipe (Mesa 22.3) gave some lanes of a diverged batch other results.
//   hook:  PENUMBRA_DSM_COMPRESS_EMIT(index, z, v) — store output vertex `index` (float z, float v[C]).
//   needs: PENUMBRA_DSM_CHANNELS (1 or 3), PENUMBRA_DSM_CANDIDATES (deep_shadow_map_shared.h).
#ifndef PENUMBRA_DSM_COMPRESS_GLSL
#define PENUMBRA_DSM_COMPRESS_GLSL

#ifndef PENUMBRA_DSM_COMPRESS_EMIT
#error penumbra/deep_shadow_map/compress.glsl needs the hook PENUMBRA_DSM_COMPRESS_EMIT(index, z, v)
#endif
#define PENUMBRA_DSM_C PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_K PENUMBRA_DSM_CANDIDATES
#define PENUMBRA_DSM_KC (PENUMBRA_DSM_K * PENUMBRA_DSM_C)  // candidate k of channel c: k * C + c

float penumbraDsmCEps = 0.0;
bool penumbraDsmCOpen = false, penumbraDsmCExact = false;
float penumbraDsmCZs = 0.0, penumbraDsmCZLast = 0.0, penumbraDsmCZo = 0.0;
float penumbraDsmCVo[PENUMBRA_DSM_C];
float penumbraDsmCCand[PENUMBRA_DSM_KC], penumbraDsmCLo[PENUMBRA_DSM_KC], penumbraDsmCHi[PENUMBRA_DSM_KC];
bool penumbraDsmCAlive[PENUMBRA_DSM_KC];
float penumbraDsmCBestLo[PENUMBRA_DSM_C], penumbraDsmCBestHi[PENUMBRA_DSM_C];  // the chosen windows
uint penumbraDsmCCount = 0u;

void penumbraDsmCompressBegin(float eps_inner) {
    penumbraDsmCEps = eps_inner;
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        penumbraDsmCVo[c] = 1.0;
        penumbraDsmCBestLo[c] = 0.0;
        penumbraDsmCBestHi[c] = 0.0;
    }
    for (int i = 0; i < PENUMBRA_DSM_KC; ++i) {
        penumbraDsmCCand[i] = 1.0;
        penumbraDsmCLo[i] = 0.0;
        penumbraDsmCHi[i] = 0.0;
        penumbraDsmCAlive[i] = false;
    }
    penumbraDsmCOpen = false;
    penumbraDsmCCount = 0u;
}

void penumbraDsmCEmit() {
    PENUMBRA_DSM_COMPRESS_EMIT(penumbraDsmCCount, penumbraDsmCZo, penumbraDsmCVo);
    penumbraDsmCCount++;
}

// A segment starting at depth z with values in [wlo, whi] per channel; with_exact: candidate 0 is
// exact[c] (a vertical step, the first vertex), the others at k / K of the interval (K a power of
// two: exact fractions).
void penumbraDsmCStart(float z, float wlo[PENUMBRA_DSM_C], float whi[PENUMBRA_DSM_C], bool with_exact,
                       float exact[PENUMBRA_DSM_C]) {
    penumbraDsmCZs = z;
    penumbraDsmCZLast = z;
    penumbraDsmCExact = with_exact;
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        precise float span = whi[c] - wlo[c];
        for (int k = 0; k < PENUMBRA_DSM_K; ++k) {
            precise float f = (float(k) + (with_exact ? 0.0 : 0.5)) * (1.0 / float(PENUMBRA_DSM_K));
            precise float at = wlo[c] + span * f;
            int i = k * PENUMBRA_DSM_C + c;
            penumbraDsmCCand[i] = with_exact && k == 0 ? exact[c] : min(at, whi[c]);
            penumbraDsmCLo[i] = uintBitsToFloat(0xFF800000u);  // -infinity
            penumbraDsmCHi[i] = 0.0;
            penumbraDsmCAlive[i] = true;
        }
    }
    penumbraDsmCOpen = true;
}

// Each channel's candidate (the exact one while open, else the widest open window, ties: the lowest
// index); emits the segment's start vertex with those values.
void penumbraDsmCEmitStart() {
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        // Constant indices only (the loop unrolls): no array indexed by the choice.
        int b = -1;
        float width = 0.0, value = 0.0, lo = 0.0, hi = 0.0;
        for (int k = 0; k < PENUMBRA_DSM_K; ++k) {
            int i = k * PENUMBRA_DSM_C + c;
            precise float w = penumbraDsmCHi[i] - penumbraDsmCLo[i];
            bool eligible = penumbraDsmCAlive[i] && !(penumbraDsmCExact && b == 0);
            if (eligible && (b < 0 || w > width)) {
                b = k;
                width = w;
                value = penumbraDsmCCand[i];
                lo = penumbraDsmCLo[i];
                hi = penumbraDsmCHi[i];
            }
        }
        penumbraDsmCVo[c] = value;
        penumbraDsmCBestLo[c] = lo;
        penumbraDsmCBestHi[c] = hi;
    }
    penumbraDsmCZo = penumbraDsmCZs;
    penumbraDsmCEmit();
}

void penumbraDsmCClose() {
    penumbraDsmCEmitStart();
    precise float dz = penumbraDsmCZLast - penumbraDsmCZs;
    float wlo[PENUMBRA_DSM_C], whi[PENUMBRA_DSM_C];
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        precise float lo = penumbraDsmCVo[c] + penumbraDsmCBestLo[c] * dz;
        precise float hi = penumbraDsmCVo[c] + penumbraDsmCBestHi[c] * dz;
        wlo[c] = max(0.0, lo);
        whi[c] = max(wlo[c], hi);
    }
    penumbraDsmCStart(penumbraDsmCZLast, wlo, whi, false, wlo);
}

void penumbraDsmCompressAdd(float z, float v[PENUMBRA_DSM_C]) {
    if (!penumbraDsmCOpen) {
        penumbraDsmCStart(z, v, v, true, v);
        return;
    }
    for (int attempt = 0; attempt < 2; ++attempt) {
        bool same = z == penumbraDsmCZs;
        precise float dz = z - penumbraDsmCZs;
        float nlo[PENUMBRA_DSM_KC], nhi[PENUMBRA_DSM_KC];
        bool nalive[PENUMBRA_DSM_KC];
        bool open = true;
        for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
            bool any = false;
            for (int k = 0; k < PENUMBRA_DSM_K; ++k) {
                int i = k * PENUMBRA_DSM_C + c;
                nlo[i] = penumbraDsmCLo[i];
                nhi[i] = penumbraDsmCHi[i];
                nalive[i] = false;
                if (!penumbraDsmCAlive[i]) {
                    // a closed window stays closed
                } else if (same) {
                    nalive[i] = abs(penumbraDsmCCand[i] - v[c]) <= penumbraDsmCEps;
                } else {
                    precise float lo_num = max(v[c] - penumbraDsmCEps, 0.0) - penumbraDsmCCand[i];
                    precise float hi_num = (v[c] + penumbraDsmCEps) - penumbraDsmCCand[i];
                    precise float lo_slope = lo_num / dz;
                    precise float hi_slope = hi_num / dz;
                    nlo[i] = max(penumbraDsmCLo[i], lo_slope);
                    nhi[i] = min(penumbraDsmCHi[i], hi_slope);
                    nalive[i] = nlo[i] <= nhi[i];
                }
                any = any || nalive[i];
            }
            open = open && any;
        }
        if (open) {
            for (int i = 0; i < PENUMBRA_DSM_KC; ++i) {
                penumbraDsmCLo[i] = nlo[i];
                penumbraDsmCHi[i] = nhi[i];
                penumbraDsmCAlive[i] = nalive[i];
            }
            penumbraDsmCZLast = z;
            return;
        }
        if (penumbraDsmCZLast == penumbraDsmCZs) {  // nothing accepted since the start: a vertical step
            penumbraDsmCEmitStart();
            float wlo[PENUMBRA_DSM_C], whi[PENUMBRA_DSM_C], exact[PENUMBRA_DSM_C];
            for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
                exact[c] = abs(penumbraDsmCVo[c] - v[c]) <= penumbraDsmCEps ? penumbraDsmCVo[c] : min(penumbraDsmCVo[c], v[c]);
                precise float up = v[c] + penumbraDsmCEps;
                precise float down = v[c] - penumbraDsmCEps;
                whi[c] = min(up, penumbraDsmCVo[c]);
                wlo[c] = min(max(down, 0.0), whi[c]);
            }
            penumbraDsmCStart(z, wlo, whi, true, exact);
            return;
        }
        penumbraDsmCClose();
    }
}

void penumbraDsmCompressFinish() {
    if (penumbraDsmCOpen) {
        penumbraDsmCEmitStart();
        if (penumbraDsmCZLast != penumbraDsmCZs) {
            precise float dz = penumbraDsmCZLast - penumbraDsmCZs;
            for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
                precise float m = penumbraDsmCBestLo[c] * 0.5 + penumbraDsmCBestHi[c] * 0.5;
                precise float e = penumbraDsmCVo[c] + m * dz;
                penumbraDsmCVo[c] = max(0.0, e);
            }
            penumbraDsmCZo = penumbraDsmCZLast;
            penumbraDsmCEmit();
        }
    }
    if ((penumbraDsmCCount & 1u) != 0u) penumbraDsmCEmit();  // even counts: whole 32-bit words of 16-bit V
    penumbraDsmCOpen = false;
}

#endif
