// penumbra — float operations the CPU twins share with the GLSL they mirror (STYLE.md habit 10):
// bit views, a non-finite test on the bits, and products kept opaque so the compiler cannot fuse
// them with a following add into an FMA (GCC contracts across statements with -mfma /
// -march=native under its default -ffp-contract=fast; the GLSL side writes `precise`). The twins'
// bit-identity under `-ffp-contract=fast -march=native` is tested (tests/twin_digest).
#ifndef PENUMBRA_DETAIL_FLOAT_OPS_HPP
#define PENUMBRA_DETAIL_FLOAT_OPS_HPP

#include <cstdint>
#include <cstring>

namespace penumbra::detail {

inline uint32_t floatBits(float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    return bits;
}

inline float floatFromBits(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

/// NaN or Inf, on the bits (twin of penumbraSampleListsNonFinite).
inline bool nonFinite(float f) { return (floatBits(f) & 0x7F800000u) == 0x7F800000u; }

/// The value, rounded to its type and hidden from the optimiser: nothing computed from it can be
/// contracted with the operation that produced it.
template <typename Real>
inline Real opaque(Real r) {
#if defined(__GNUC__) && defined(__x86_64__)
    __asm__("" : "+x"(r));
#elif defined(__GNUC__) && defined(__aarch64__)
    __asm__("" : "+w"(r));
#else
    volatile Real v = r;
    r = v;
#endif
    return r;
}

/// a * b rounded to float (or double) and kept opaque (never fused into an FMA).
inline float mulRounded(float a, float b) { return opaque(a * b); }
inline double mulRounded(double a, double b) { return opaque(a * b); }

/// Component-wise v * s with every product opaque.
template <typename V, typename Real>
inline V mulRounded(const V& v, Real s) {
    V r;
    for (int i = 0; i < V::length(); ++i) r[i] = mulRounded(v[i], s);
    return r;
}

/// ((a.x b.x + a.y b.y) + a.z b.z), products opaque: the order of glm::dot and of GLSL's dot under
/// `precise`, without fused multiply-adds.
template <typename V>
inline auto dotRounded(const V& a, const V& b) {
    return (mulRounded(a.x, b.x) + mulRounded(a.y, b.y)) + mulRounded(a.z, b.z);
}

}  // namespace penumbra::detail

#endif
