// penumbra — deep shadow map vertex store: the layout lookup.glsl reads. Vertex i: z (float bits)
// at word i; V of channel c as a 16-bit halfword h = i * C + c at word capacity + h / 2 (low half
// first; penumbraDsmQuantize). A texel starts at an even vertex and stores an even count (the
// compressor pads), so its halfwords fill whole words: the low half waits in a register for its
// high half and no two invocations share a word. Used by merge.comp.glsl and mip.comp.glsl.
//   hooks: PENUMBRA_DSM_STORE_WORD(index, word) — write one word of the vertex buffer;
//          PENUMBRA_DSM_STORE_OVERFLOW() — count a vertex past the capacity (not written).
//   needs: PENUMBRA_DSM_CHANNELS, penumbra/deep_shadow_map/deep_shadow_map.glsl.
#ifndef PENUMBRA_DSM_STORE_GLSL
#define PENUMBRA_DSM_STORE_GLSL

#ifndef PENUMBRA_DSM_STORE_WORD
#error penumbra/deep_shadow_map/store.glsl needs the hook PENUMBRA_DSM_STORE_WORD(index, word)
#endif
#ifndef PENUMBRA_DSM_STORE_OVERFLOW
#error penumbra/deep_shadow_map/store.glsl needs the hook PENUMBRA_DSM_STORE_OVERFLOW()
#endif

uint penumbraDsmPendingHalf = 0u;

void penumbraDsmStoreVertex(uint vertex, uint capacity, float z, float v[PENUMBRA_DSM_CHANNELS]) {
    if (vertex >= capacity) {
        PENUMBRA_DSM_STORE_OVERFLOW();
        return;
    }
    PENUMBRA_DSM_STORE_WORD(vertex, floatBitsToUint(z));
    for (int c = 0; c < PENUMBRA_DSM_CHANNELS; ++c) {
        uint h = vertex * uint(PENUMBRA_DSM_CHANNELS) + uint(c);
        uint q = penumbraDsmQuantize(v[c]);
        if ((h & 1u) == 0u) {
            penumbraDsmPendingHalf = q;
        } else {
            PENUMBRA_DSM_STORE_WORD(capacity + h / 2u, penumbraDsmPendingHalf | (q << 16u));
        }
    }
}

#endif
