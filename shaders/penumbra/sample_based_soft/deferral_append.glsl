// penumbra — sample-based soft shadows, deferred pairs: how a (triangle slot, texel) fragment hands
// its list block's view samples to the pairs' compute pass (light_pass.comp.glsl), shared by the
// light pass's fragment stage (light_pass.frag.glsl, the regions it rasterizes) and the coverage
// pass (light_pass_coverage.comp.glsl, the regions it covers itself): one pair per sample no wedge
// plane of the triangle rejects (SoftSkips::wedges), appended to the pairs buffer, or, past that
// buffer's capacity, the whole fragment to the fragments buffer (the per-fragment pass walks it).
// Needs light_pass_work.glsl (its bindings and penumbraSampleListsPosition) and the deferral,
// pairs and fragments buffers declared writable as penumbraSbsDeferral, penumbraSbsPairs and
// penumbraSbsFragments; PENUMBRA_SBS_COUNT(index) adds one to a pending work counter.
#ifndef PENUMBRA_SBS_DEFERRAL_APPEND_GLSL
#define PENUMBRA_SBS_DEFERRAL_APPEND_GLSL

// `range` = the texel's list block (non-empty). Once the pairs buffer is full no fragment adds to
// its counter, which cannot wrap around then (at most the fragments in flight add past the
// capacity, each at most a list block); the fragment that straddles the capacity leaves its share
// below it empty.
void penumbraSbsAppendBlock(uvec2 texel, uvec2 range, uint slot, PenumbraSbsWedges wedges) {
#if PENUMBRA_SBS_WEDGES
    const float wedge_mu2 = uintBitsToFloat(penumbraSbsParams.reserved.z);  // detail::soft::wedgeMu2
    uint kept = 0u, kept_bits = 0u;  // kept_bits: the first 32 samples' verdicts, not tested again
    for (uint i = 0u; i < range.y; ++i)
        if (!penumbraSbsWedgeRejects(wedges, penumbraSampleListsPosition(range.x + i), wedge_mu2)) {
            ++kept;
            if (i < 32u) kept_bits |= 1u << i;
        }
#else
    const uint kept = range.y;
    const uint kept_bits = range.y >= 32u ? 0xFFFFFFFFu : (1u << range.y) - 1u;
#endif
    const uint capacity = uint(penumbraSbsPairs.length());
    const uint first = kept == 0u ? 0u
                       : penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PAIRS] >= capacity
                           ? capacity
                           : atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PAIRS], kept);
    const bool fits = kept == 0u || (first < capacity && kept <= capacity - first);
    if (fits) {
        uint k = first;
        for (uint bits = kept_bits; bits != 0u; bits &= bits - 1u) {
            const uint i = uint(findLSB(bits));
            penumbraSbsPairs[k++] = uvec2(PENUMBRA_SBS_PAIR_X(slot, i), PENUMBRA_SBS_PAIR_Y(texel.x, texel.y, i));
        }
        for (uint i = 32u; i < range.y && k < first + kept; ++i) {  // blocks of more than 32 samples
#if PENUMBRA_SBS_WEDGES
            if (penumbraSbsWedgeRejects(wedges, penumbraSampleListsPosition(range.x + i), wedge_mu2)) continue;
#endif
            penumbraSbsPairs[k++] = uvec2(PENUMBRA_SBS_PAIR_X(slot, i), PENUMBRA_SBS_PAIR_Y(texel.x, texel.y, i));
        }
#if PENUMBRA_SBS_COUNT_WORK
        PENUMBRA_SBS_COUNT(PENUMBRA_SBS_WORK_FRAGMENTS);
        if (kept < range.y)
            atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_PENDING + PENUMBRA_SBS_WORK_PAIRS_WEDGED], range.y - kept);
#endif
    } else {
        for (uint k = first; k < capacity; ++k) penumbraSbsPairs[k] = uvec2(0u, PENUMBRA_SBS_PAIR_EMPTY);
        if (first < capacity) penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_EMPTY] = capacity - first;
        const uint f = atomicAdd(penumbraSbsDeferral[PENUMBRA_SBS_DEFERRAL_FRAGMENTS], 1u);
        if (f < uint(penumbraSbsFragments.length())) penumbraSbsFragments[f] = uvec2(slot, texel.x | texel.y << 16u);
    }
}

#endif
