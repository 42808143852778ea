// penumbra/reference/light_samples.hpp — deterministic light-sample sets for area and volume lights.
//
// Integration summary
//   Needs:    GLM (double vectors) and the C++17 standard library; no GPU, no GL, no libm
//             transcendental functions.
//   Produces: std::vector<glm::dvec3> of light-sample positions for a ball (volumetric sphere)
//             light, a disk light and a rectangular light. The same vector feeds the CPU oracle
//             (reference/visibility.hpp) and, converted to float, the GPU modes, so every mode
//             is compared on the same samples (BLOCKS.md "The oracle").
//   Hooks:    none.
//
// Determinism: same arguments -> bit-identical samples on every IEEE-754 platform. The sequences
// are built from 64-bit integer arithmetic (Kronecker/golden-ratio lattices, splitmix64 jitter);
// the geometry uses only +, -, *, /, sqrt and explicit std::fma, with an in-header polynomial
// sine/cosine and cube root, because the last bit of libm's sin/cos/cbrt differs between C
// libraries and an implicit a*b+c may or may not be fused depending on -ffp-contract/-mfma.
// (Not valid under -ffast-math, which allows the compiler to reassociate anything.)
//
// Stratification: sample i uses the i-th stratum of the "volume" coordinate (radius^3 for the
// ball, radius^2 for the disk) with a per-sample jitter inside the stratum, and a rank-1
// Kronecker lattice (golden ratio for the disk angle: the sunflower/Vogel spiral; the R2 plastic
// number lattice for the ball's direction) for the remaining coordinates. Samples are returned
// in stratum order (inner to outer), so any prefix is NOT a good subset: use all `count`.
//
// Bad input (all throw penumbra::Error with a message naming the value):
//   - count == 0 (also nu == 0 or nv == 0)                       -> throws;
//   - non-finite center / normal / corner / edges / radius        -> throws;
//   - negative radius                                             -> throws;
//   - zero-length disk normal                                     -> throws;
//   - radius == 0                                                 -> exactly ONE sample, at the
//     centre, whatever `count` is (a point light), so callers can size bit masks from size();
//   - degenerate rectangles (zero or parallel edges) are allowed: they give coincident samples.
#ifndef PENUMBRA_REFERENCE_LIGHT_SAMPLES_HPP
#define PENUMBRA_REFERENCE_LIGHT_SAMPLES_HPP

#include <penumbra/error.hpp>

#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace penumbra {
namespace detail {
namespace light_samples {

// 2^64 / golden ratio and 2^64 / plastic number (and its square): the additive constants of the
// 1D golden lattice and the 2D R2 lattice (Roberts 2018), in fixed point so the sequences are
// exact integer arithmetic, identical everywhere and free of floating-point drift for large i.
inline constexpr uint64_t kGolden = 0x9e3779b97f4a7c15ull;
inline constexpr uint64_t kPlastic1 = 0xc13fa9a902a6328full;
inline constexpr uint64_t kPlastic2 = 0x91e10da5c79e7b1cull;
inline constexpr double kHalfPi = 1.57079632679489661923;

inline uint64_t splitmix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// Fixed-point fraction in [0, 1): the top 53 bits, exactly representable.
inline double unitFromBits(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

/// Stream-separated hash of (seed, stream, index).
inline uint64_t hashSample(uint32_t seed, uint32_t stream, uint64_t index) {
    return splitmix64(splitmix64((static_cast<uint64_t>(seed) << 32) | stream) ^ index);
}

/// cos and sin of 2*pi*turns for turns in [0, 1), from fixed Taylor polynomials on [0, pi/4]
/// (truncation error < 1e-19) so the result does not depend on the C library.
inline void cosSinTurns(double turns, double& cos_out, double& sin_out) {
    const double quadrant_f = std::floor(turns * 4.0);  // exact: power-of-two scaling
    const int quadrant = static_cast<int>(quadrant_f) & 3;
    double f = turns * 4.0 - quadrant_f;  // in [0, 1), exact
    const bool mirrored = f > 0.5;        // reduce to [0, pi/4] through the complement
    if (mirrored) f = 1.0 - f;
    const double x = f * kHalfPi;
    const double x2 = x * x;
    // Horner in x^2 with explicit fma so contraction flags cannot change the bits.
    double s = 1.0 / 355687428096000.0;  // 1/17!
    s = std::fma(s, -x2, 1.0 / 1307674368000.0);
    s = std::fma(s, -x2, 1.0 / 6227020800.0);
    s = std::fma(s, -x2, 1.0 / 39916800.0);
    s = std::fma(s, -x2, 1.0 / 362880.0);
    s = std::fma(s, -x2, 1.0 / 5040.0);
    s = std::fma(s, -x2, 1.0 / 120.0);
    s = std::fma(s, -x2, 1.0 / 6.0);
    s = std::fma(s, -x2, 1.0);
    s *= x;
    double c = 1.0 / 6402373705728000.0;  // 1/18!
    c = std::fma(c, -x2, 1.0 / 20922789888000.0);
    c = std::fma(c, -x2, 1.0 / 87178291200.0);
    c = std::fma(c, -x2, 1.0 / 479001600.0);
    c = std::fma(c, -x2, 1.0 / 3628800.0);
    c = std::fma(c, -x2, 1.0 / 40320.0);
    c = std::fma(c, -x2, 1.0 / 720.0);
    c = std::fma(c, -x2, 1.0 / 24.0);
    c = std::fma(c, -x2, 0.5);
    c = std::fma(c, -x2, 1.0);
    if (mirrored) std::swap(c, s);
    switch (quadrant) {
        case 0: cos_out = c; sin_out = s; break;
        case 1: cos_out = -s; sin_out = c; break;
        case 2: cos_out = -c; sin_out = -s; break;
        default: cos_out = s; sin_out = -c; break;
    }
}

/// Cube root of x in [0, 1] by range reduction (exact frexp/ldexp) and a fixed number of Newton
/// steps, for the same library-independence as cosSinTurns.
inline double cubeRoot(double x) {
    if (x <= 0.0) return 0.0;
    int exponent = 0;
    double m = std::frexp(x, &exponent);  // x = m * 2^exponent, m in [0.5, 1)
    while (exponent % 3 != 0) {           // at most two halvings: m ends in [0.125, 1)
        m *= 0.5;
        ++exponent;
    }
    double y = 0.75;  // m in [0.125, 1) -> cbrt(m) in [0.5, 1)
    for (int i = 0; i < 8; ++i) {
        const double y2 = y * y;
        y -= std::fma(y2, y, -m) / (3.0 * y2);
    }
    return std::ldexp(y, exponent / 3);
}

inline void checkFinite(const glm::dvec3& v, const char* function, const char* name) {
    PENUMBRA_CHECK(std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z), function, ": ", name,
                   " must be finite (got ", v.x, ", ", v.y, ", ", v.z, ")");
}

inline void checkRadius(double radius, const char* function) {
    PENUMBRA_CHECK(std::isfinite(radius) && radius >= 0.0, function,
                   ": radius must be finite and >= 0 (got ", radius, ")");
}

}  // namespace light_samples
}  // namespace detail

namespace reference {

/// Uniform samples of a solid ball (volumetric sphere light). Stratified in radius^3 (equal-volume
/// shells, jittered) x R2 lattice on the direction (z = 1 - 2u, phi = 2 pi v), Cranley-Patterson
/// rotated by `seed`. Returns `count` samples, or one sample at `center` when radius == 0.
/// Throws penumbra::Error for count == 0, non-finite center or radius, negative radius.
inline std::vector<glm::dvec3> sphereLightSamples(const glm::dvec3& center, double radius, uint32_t count,
                                                  uint32_t seed = 0) {
    namespace ls = ::penumbra::detail::light_samples;
    PENUMBRA_CHECK(count > 0, "sphereLightSamples: count must be > 0");
    ls::checkFinite(center, "sphereLightSamples", "center");
    ls::checkRadius(radius, "sphereLightSamples");
    if (radius == 0.0) return {center};

    const uint64_t rotate_u = ls::hashSample(seed, 1, 0);
    const uint64_t rotate_v = ls::hashSample(seed, 2, 0);
    std::vector<glm::dvec3> samples(count);
    for (uint32_t i = 0; i < count; ++i) {
        const double jitter = ls::unitFromBits(ls::hashSample(seed, 0, i));
        const double volume = (static_cast<double>(i) + jitter) / static_cast<double>(count);
        const double u = ls::unitFromBits(rotate_u + static_cast<uint64_t>(i) * ls::kPlastic1);
        const double v = ls::unitFromBits(rotate_v + static_cast<uint64_t>(i) * ls::kPlastic2);
        const double z = 1.0 - 2.0 * u;  // 2u is exact; one rounding, no product to fuse
        const double ring = std::sqrt(std::fmax(0.0, std::fma(-z, z, 1.0)));
        double c = 0.0, s = 0.0;
        ls::cosSinTurns(v, c, s);
        const double r = radius * ls::cubeRoot(volume);
        const double r_ring = r * ring;
        samples[i] = glm::dvec3(std::fma(r_ring, c, center.x), std::fma(r_ring, s, center.y),
                                std::fma(r, z, center.z));
    }
    return samples;
}

/// Uniform samples of a disk (radius `radius`, facing `normal`, which need not be unit length).
/// Stratified in radius^2 (equal-area rings, jittered) x golden-angle lattice (a Vogel spiral),
/// rotated by `seed`. The in-plane basis is Duff et al. 2017's branchless ONB of normalize(normal).
/// Returns `count` samples, or one sample at `center` when radius == 0.
/// Throws penumbra::Error for count == 0, non-finite inputs, zero normal, negative radius.
inline std::vector<glm::dvec3> diskLightSamples(const glm::dvec3& center, const glm::dvec3& normal, double radius,
                                                uint32_t count, uint32_t seed = 0) {
    namespace ls = ::penumbra::detail::light_samples;
    PENUMBRA_CHECK(count > 0, "diskLightSamples: count must be > 0");
    ls::checkFinite(center, "diskLightSamples", "center");
    ls::checkFinite(normal, "diskLightSamples", "normal");
    ls::checkRadius(radius, "diskLightSamples");
    const double length = std::sqrt(std::fma(normal.x, normal.x, std::fma(normal.y, normal.y, normal.z * normal.z)));
    PENUMBRA_CHECK(length > 0.0 && std::isfinite(length), "diskLightSamples: normal must be non-zero (got ", normal.x,
                   ", ", normal.y, ", ", normal.z, ")");
    if (radius == 0.0) return {center};

    const glm::dvec3 n = normal / length;
    const double sign = std::copysign(1.0, n.z);
    const double a = -1.0 / (sign + n.z);
    const double b = (n.x * n.y) * a;
    const glm::dvec3 tangent(std::fma(sign * (n.x * n.x), a, 1.0), sign * b, -sign * n.x);
    const glm::dvec3 bitangent(b, std::fma(n.y * n.y, a, sign), -n.y);

    const uint64_t rotate = ls::hashSample(seed, 1, 0);
    std::vector<glm::dvec3> samples(count);
    for (uint32_t i = 0; i < count; ++i) {
        const double jitter = ls::unitFromBits(ls::hashSample(seed, 0, i));
        const double area = (static_cast<double>(i) + jitter) / static_cast<double>(count);
        double c = 0.0, s = 0.0;
        ls::cosSinTurns(ls::unitFromBits(rotate + static_cast<uint64_t>(i) * ls::kGolden), c, s);
        const double r = radius * std::sqrt(area);
        const double rc = r * c, rs = r * s;
        samples[i] = glm::dvec3(std::fma(rc, tangent.x, std::fma(rs, bitangent.x, center.x)),
                                std::fma(rc, tangent.y, std::fma(rs, bitangent.y, center.y)),
                                std::fma(rc, tangent.z, std::fma(rs, bitangent.z, center.z)));
    }
    return samples;
}

/// Cell centres of an nu x nv grid on the parallelogram corner + [0,1] edge_u + [0,1] edge_v:
/// sample (i, j) = corner + (i + 1/2)/nu * edge_u + (j + 1/2)/nv * edge_v, stored at index
/// j * nu + i (u fastest). Not jittered: the closed-form shadow tests rely on the exact grid.
/// Throws penumbra::Error for nu == 0, nv == 0 or non-finite inputs.
inline std::vector<glm::dvec3> rectLightSamples(const glm::dvec3& corner, const glm::dvec3& edge_u,
                                                const glm::dvec3& edge_v, uint32_t nu, uint32_t nv) {
    namespace ls = ::penumbra::detail::light_samples;
    PENUMBRA_CHECK(nu > 0 && nv > 0, "rectLightSamples: nu and nv must be > 0 (got ", nu, " x ", nv, ")");
    ls::checkFinite(corner, "rectLightSamples", "corner");
    ls::checkFinite(edge_u, "rectLightSamples", "edge_u");
    ls::checkFinite(edge_v, "rectLightSamples", "edge_v");
    std::vector<glm::dvec3> samples(static_cast<size_t>(nu) * nv);
    for (uint32_t j = 0; j < nv; ++j) {
        const double b = (2.0 * j + 1.0) / (2.0 * nv);  // integers < 2^34: exact, one rounding
        for (uint32_t i = 0; i < nu; ++i) {
            const double a = (2.0 * i + 1.0) / (2.0 * nu);
            samples[static_cast<size_t>(j) * nu + i] =
                glm::dvec3(std::fma(a, edge_u.x, std::fma(b, edge_v.x, corner.x)),
                           std::fma(a, edge_u.y, std::fma(b, edge_v.y, corner.y)),
                           std::fma(a, edge_u.z, std::fma(b, edge_v.z, corner.z)));
        }
    }
    return samples;
}

}  // namespace reference
}  // namespace penumbra

#endif
