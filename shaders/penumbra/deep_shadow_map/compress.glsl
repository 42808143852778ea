// penumbra — the streaming greedy L-infinity compressor (lokovic2000 §3.3): the twin of
// penumbra::detail::DsmCompressor<C> (include/penumbra/deep_shadow_map.hpp), operation for operation.
// One compressor per invocation (globals with the penumbraDsmC prefix).
//   hook:  PENUMBRA_DSM_COMPRESS_EMIT(index, z, v) — store output vertex `index` (float z, float v[C]).
//   needs: PENUMBRA_DSM_CHANNELS (1 or 3).
#ifndef PENUMBRA_DSM_COMPRESS_GLSL
#define PENUMBRA_DSM_COMPRESS_GLSL

#ifndef PENUMBRA_DSM_COMPRESS_EMIT
#error penumbra/deep_shadow_map/compress.glsl needs the hook PENUMBRA_DSM_COMPRESS_EMIT(index, z, v)
#endif
#define PENUMBRA_DSM_C PENUMBRA_DSM_CHANNELS

float penumbraDsmCEps = 0.0;
bool penumbraDsmCOpen = false;
float penumbraDsmCZo = 0.0, penumbraDsmCZLast = 0.0;
float penumbraDsmCVo[PENUMBRA_DSM_C], penumbraDsmCLo[PENUMBRA_DSM_C], penumbraDsmCHi[PENUMBRA_DSM_C];
uint penumbraDsmCCount = 0u;

void penumbraDsmCompressBegin(float eps_inner) {
    penumbraDsmCEps = eps_inner;
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        penumbraDsmCVo[c] = 1.0;
        penumbraDsmCLo[c] = 0.0;
        penumbraDsmCHi[c] = 0.0;
    }
    penumbraDsmCOpen = false;
    penumbraDsmCCount = 0u;
}

void penumbraDsmCEmit() {
    PENUMBRA_DSM_COMPRESS_EMIT(penumbraDsmCCount, penumbraDsmCZo, penumbraDsmCVo);
    penumbraDsmCCount++;
}

void penumbraDsmCOrigin(float z, float v[PENUMBRA_DSM_C]) {
    penumbraDsmCZo = z;
    penumbraDsmCZLast = z;
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        penumbraDsmCVo[c] = v[c];
        penumbraDsmCLo[c] = uintBitsToFloat(0xFF800000u);  // -infinity
        penumbraDsmCHi[c] = 0.0;
    }
    penumbraDsmCOpen = true;
}

void penumbraDsmCClose() {
    precise float dz = penumbraDsmCZLast - penumbraDsmCZo;
    float v[PENUMBRA_DSM_C];
    for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
        precise float m = penumbraDsmCLo[c] * 0.5 + penumbraDsmCHi[c] * 0.5;
        precise float e = penumbraDsmCVo[c] + m * dz;
        v[c] = max(0.0, e);
    }
    penumbraDsmCOrigin(penumbraDsmCZLast, v);
    penumbraDsmCEmit();
}

void penumbraDsmCompressAdd(float z, float v[PENUMBRA_DSM_C]) {
    if (!penumbraDsmCOpen) {
        penumbraDsmCOrigin(z, v);
        penumbraDsmCEmit();
        return;
    }
    for (int attempt = 0; attempt < 2; ++attempt) {
        if (z == penumbraDsmCZo) {
            bool within = true;
            for (int c = 0; c < PENUMBRA_DSM_C; ++c) within = within && abs(penumbraDsmCVo[c] - v[c]) <= penumbraDsmCEps;
            if (within) return;
            for (int c = 0; c < PENUMBRA_DSM_C; ++c)
                if (!(abs(penumbraDsmCVo[c] - v[c]) <= penumbraDsmCEps)) penumbraDsmCVo[c] = min(penumbraDsmCVo[c], v[c]);
            penumbraDsmCEmit();
            return;
        }
        precise float dz = z - penumbraDsmCZo;
        float nlo[PENUMBRA_DSM_C], nhi[PENUMBRA_DSM_C];
        bool open = true;
        for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
            precise float lo_num = max(v[c] - penumbraDsmCEps, 0.0) - penumbraDsmCVo[c];
            precise float hi_num = (v[c] + penumbraDsmCEps) - penumbraDsmCVo[c];
            precise float lo_slope = lo_num / dz;
            precise float hi_slope = hi_num / dz;
            nlo[c] = max(penumbraDsmCLo[c], lo_slope);
            nhi[c] = min(penumbraDsmCHi[c], hi_slope);
            open = open && nlo[c] <= nhi[c];
        }
        if (open) {
            for (int c = 0; c < PENUMBRA_DSM_C; ++c) {
                penumbraDsmCLo[c] = nlo[c];
                penumbraDsmCHi[c] = nhi[c];
            }
            penumbraDsmCZLast = z;
            return;
        }
        if (penumbraDsmCZLast == penumbraDsmCZo) {
            float w[PENUMBRA_DSM_C];
            for (int c = 0; c < PENUMBRA_DSM_C; ++c) w[c] = min(penumbraDsmCVo[c], v[c]);
            penumbraDsmCOrigin(z, w);
            penumbraDsmCEmit();
            return;
        }
        penumbraDsmCClose();
    }
}

void penumbraDsmCompressFinish() {
    if (penumbraDsmCOpen && penumbraDsmCZLast != penumbraDsmCZo) penumbraDsmCClose();
    if ((penumbraDsmCCount & 1u) != 0u) penumbraDsmCEmit();  // even counts: whole 32-bit words of 16-bit V
    penumbraDsmCOpen = false;
}

#endif
