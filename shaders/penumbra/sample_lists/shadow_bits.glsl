// penumbra — packed per-sample shadow bits (sintorn2008 §3.1, Storage: the lit/shadowed state is
// kept in its own array at the same slots "to pack the shadow data densely in single bits";
// §4.2: N light-sample bits per view sample for soft shadows).
//
// Layout (host twin: penumbra::shadowStrideBits / shadowBitAddress / shadowBitsWords): every slot
// owns `stride` bits, stride = N rounded up to a power of two when N <= 16 (1, 2, 4, 8, 16: a
// slot never straddles a word) and to a multiple of 32 when N > 16 (word-aligned slots). Bit k of
// slot s is bit (s * stride + k) of the uint array.
//
// Hooks the integrator defines before including this file:
//   PENUMBRA_SAMPLE_LISTS_SHADOW_BITS             N, bits per sample (compile-time constant >= 1)
//   PENUMBRA_SAMPLE_LISTS_SHADOW_OR(word, mask)   e.g. atomicOr(shadowWords[word], mask)
//   PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW(word)       -> uint, e.g. shadowWords[word]
#ifndef PENUMBRA_SAMPLE_LISTS_SHADOW_BITS_GLSL
#define PENUMBRA_SAMPLE_LISTS_SHADOW_BITS_GLSL

#ifndef PENUMBRA_SAMPLE_LISTS_SHADOW_BITS
#error "penumbra/sample_lists/shadow_bits.glsl: define the hook PENUMBRA_SAMPLE_LISTS_SHADOW_BITS (bits per sample, >= 1)"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_SHADOW_OR
#error "penumbra/sample_lists/shadow_bits.glsl: define the hook PENUMBRA_SAMPLE_LISTS_SHADOW_OR(word, mask)"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW
#error "penumbra/sample_lists/shadow_bits.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW(word) -> uint"
#endif

const uint penumbraSampleListsShadowBits = uint(PENUMBRA_SAMPLE_LISTS_SHADOW_BITS);
const uint penumbraSampleListsShadowStride =
    penumbraSampleListsShadowBits > 16u ? ((penumbraSampleListsShadowBits + 31u) / 32u) * 32u
    : penumbraSampleListsShadowBits > 8u ? 16u
    : penumbraSampleListsShadowBits > 4u ? 8u
    : penumbraSampleListsShadowBits > 2u ? 4u
    : penumbraSampleListsShadowBits;

// (word index, bit index in that word) of bit `bit` (< N) of `slot`. No 32-bit overflow for any
// slot whose words fit the array (the host checks the array size).
uvec2 penumbraSampleListsShadowAddress(uint slot, uint bit) {
    if (penumbraSampleListsShadowStride >= 32u) {
        return uvec2(slot * (penumbraSampleListsShadowStride / 32u) + (bit >> 5u), bit & 31u);
    }
    const uint perWord = 32u / penumbraSampleListsShadowStride;
    return uvec2(slot / perWord, (slot % perWord) * penumbraSampleListsShadowStride + bit);
}

// Marks light sample `bit` of the view sample in `slot` as blocked (atomic OR; §3.3 combines the
// result of every caster this way).
void penumbraSampleListsSetShadowBit(uint slot, uint bit) {
    const uvec2 at = penumbraSampleListsShadowAddress(slot, bit);
    PENUMBRA_SAMPLE_LISTS_SHADOW_OR(at.x, 1u << at.y);
}

// ORs the bits of `mask` into bits 32 * word .. 32 * word + 31 of the slot (bit i of `mask` =
// slot bit 32 * word + i; bits >= N must be 0). For N < 32 `word` must be 0: one atomic per
// caster and sample instead of one per light sample (§4.2 AND-ed LUT masks).
void penumbraSampleListsOrShadowMask(uint slot, uint word, uint mask) {
    const uvec2 at = penumbraSampleListsShadowAddress(slot, word * 32u);
    PENUMBRA_SAMPLE_LISTS_SHADOW_OR(at.x, mask << at.y);
}

// True when bit `bit` of `slot` is set.
bool penumbraSampleListsShadowBit(uint slot, uint bit) {
    const uvec2 at = penumbraSampleListsShadowAddress(slot, bit);
    return ((PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW(at.x) >> at.y) & 1u) != 0u;
}

// Bits 32 * word .. 32 * word + 31 of the slot, shifted down to bit 0 (for N < 32 only the low
// stride bits are the slot's; `word` must be 0).
uint penumbraSampleListsShadowMask(uint slot, uint word) {
    const uvec2 at = penumbraSampleListsShadowAddress(slot, word * 32u);
    const uint bits = PENUMBRA_SAMPLE_LISTS_LOAD_SHADOW(at.x) >> at.y;
    return penumbraSampleListsShadowStride >= 32u ? bits
                                                  : bits & ((1u << penumbraSampleListsShadowStride) - 1u);
}

#endif
