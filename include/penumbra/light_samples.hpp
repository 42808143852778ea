// penumbra — light-sample sets for area and volume lights (disk, rectangle, sphere, ellipsoid) in
// the light's normalised space, and their per-pixel selection (sintorn2008 §4.2, laine2005 §3.4).
//
// Integration summary
//   Needs:    GLM (double vectors and matrices) and the C++17 standard library; no GPU, no GL, no
//             libm transcendental function (this header is GL-free: include it anywhere).
//   Produces: lightFrame(light): the light's normalised space (LightFrame: centre, orthonormal
//             rotation, scale; toLocal / toWorld / planeToLocal). makeLightSampleSets(light,
//             options): K sets of N samples each, in local space (|q| <= 1 - 2^-20, strictly
//             inside the unit ball — what the light-sample LUT tabulates) and in world space
//             (what the CPU oracle, reference/visibility.hpp, tests against). lightSampleSet /
//             lightSampleRotationTurns: which set and which rotation about the local z axis a
//             pixel uses in a frame (banding turned into noise, temporal jitter).
//             The old reference::sphereLightSamples / diskLightSamples / rectLightSamples (also
//             reachable through penumbra/reference/light_samples.hpp) are built on the same
//             internals and keep their exact bits.
//   GPU code: shaders/penumbra/light_samples/select.glsl (penumbraLightSampleSet,
//             penumbraLightSampleRotationHash, penumbraLightSampleRotationTurns: the same integer
//             arithmetic, bit for bit), light_samples_shared.h (ranges and hash constants).
//   Hooks:    none.
//
// The normalised space (sintorn2008 §4.1's scaling trick, which makes an ellipsoid a ball):
//     q = inverse(scale) * transpose(rotation) * (p - center),   p = center + rotation * (scale * q)
// rotation's columns are the local x, y, z axes: z = normalize(axis_z), x = axis_x made orthogonal
// to z (Gram-Schmidt), y = z x x (right-handed). scale: Disk and Sphere the radius, Rectangle the
// half-diagonal (all three components), Ellipsoid the semi-axes along local x, y, z. Every light
// lies inside |q| <= 1; disks and rectangles lie in the plane q.z = 0.
//
// Samples. Every sample is the image of a point (t, u, v) of the unit cube under the shape's
// area- or volume-preserving map, shrunk by kInset = 1 - 2^-19 (so |q| <= 1 - 2^-20 holds by
// construction, rounding included; the light is sampled at 0.999998 of its size):
//   Sphere, Ellipsoid (the unit ball): radius = cbrt(t), direction z = 1 - 2u, phi = 2 pi v.
//   Disk: radius = sqrt(t), angle = 2 pi u.
//   Rectangle: q.x = (2a - 1) hx / d, q.y = (2b - 1) hy / d (half extents hx, hy; d = hypot).
// Strata ("every stratum holds exactly one sample", both patterns):
//   Stratified (today's reference:: schemes generalised; each set is its own seed's pattern):
//     ball:  N equal-volume shells, t = (i + jitter) / N; (u, v) a rank-1 R2 (plastic number)
//            lattice, Cranley-Patterson rotated — set 0 is reference::sphereLightSamples'.
//     disk:  N equal-area rings, t = (i + jitter) / N; u the golden-ratio lattice (a Vogel
//            spiral), rotated — set 0 is reference::diskLightSamples'.
//     rectangle: a jittered nu x nv grid, nu * nv = N, the divisor pair whose cells
//            (2 hx / nu by 2 hy / nv) are closest to square (ties: smaller nu); sample i in cell
//            (i % nu, i / nu) — u fastest, as reference::rectLightSamples (which is unjittered).
//   LowDiscrepancy: a scrambled Hammersley set t = (i + jitter) / N, u = vdC(i) ^ k1,
//     v = Sobol'2(i) ^ k2 (van der Corput and the second Sobol' dimension, 32 digits each,
//     random digit scrambling with per-set keys k1, k2, random bits below the 32 digits).
//     Strata: the N slabs of t — the shells (ball), rings (disk), columns of width 2 hx / N
//     (rectangle). When N is a power of two, (t, u) is moreover a (0, m, 2)-net (every
//     elementary interval of area 1/N of the unit square holds one point) and so is (u, v),
//     the first N points of a scrambled (0, 2)-sequence (the ball's direction).
//   Samples come in stratum order, so a prefix is NOT a good subset: use all N.
// K sets (laine2005 §3.4): set s uses seed + s * 0x9e3779b9 (mod 2^32): different jitters,
// lattice rotations and scrambles, pairwise distinct (the seeds are distinct for s < 2^32).
//
// Selection (select.glsl mirrors it): pixel (x, y) in frame f uses set
//     (x + c y + f) mod K,  c = floor(K / golden ratio) | 1 clamped to [2, K - 2]   (K >= 4)
// so the 8 neighbours of a pixel all use other sets whenever K >= 4 (offsets +-1, +-c, +-c+-1 are
// non-zero mod K), and a pixel walks through all K sets in K consecutive frames. For symmetric
// lights (LightFrame::symmetric) the pixel also rotates its set about the local z axis by
// lightSampleRotationTurns = hash(x, y, frame, seed) * 2^-32 turns (sintorn2008 §4.2).
//
// Determinism: same arguments -> bit-identical samples on every IEEE-754 platform and under any
// -ffp-contract: 64-bit integer sequences (splitmix64, lattices, radical inverses), geometry with
// only +, -, *, /, sqrt and explicit std::fma or opaque products, an in-header polynomial
// sine/cosine (cosSinTurns) and cube root (cubeRoot). (Not valid under -ffast-math.)
//
// Bad input (penumbra::Error naming the value): options.count not a multiple of 32 or outside
// [32, 1024]; options.sets 0 or > 64; an unknown shape or pattern; the size components a shape
// uses zero, negative or NaN/Inf (a zero radius is an error here, unlike the reference::
// functions' point light); non-finite centre or axes; zero axes; axis_x parallel to axis_z (sine
// of their angle <= 1e-6); an ellipsoid whose largest / smallest semi-axis > 1e6.
#ifndef PENUMBRA_LIGHT_SAMPLES_HPP
#define PENUMBRA_LIGHT_SAMPLES_HPP

#include "penumbra/detail/float_ops.hpp"
#include "penumbra/error.hpp"

// light_samples_shared.h lives with the shaders; with shaders/ on the include path it is found
// there, otherwise beside this header in the source tree.
#if defined(__has_include) && __has_include(<penumbra/light_samples/light_samples_shared.h>)
#include <penumbra/light_samples/light_samples_shared.h>
#else
#include "../../shaders/penumbra/light_samples/light_samples_shared.h"
#endif

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <cmath>
#include <cstddef>
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

/// Samples are shrunk by this factor: with the few ulps of rounding of the maps, |q| stays below
/// kLightSampleBound = 1 - 2^-20.
inline constexpr double kInset = 1.0 - 0x1.0p-19;
/// Seed step between consecutive sets (2^32 / golden ratio, odd: s -> seed + s * step is injective).
inline constexpr uint32_t kSetSeedStep = 0x9e3779b9u;
/// axis_x is "parallel" to axis_z below this sine of their angle.
inline constexpr double kMinAxisSine = 1e-6;
/// Largest accepted ratio of an ellipsoid's largest to smallest semi-axis.
inline constexpr double kMaxEllipsoidRatio = 1e6;

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

// ---- the unit-cube points behind every sample -----------------------------------------------

/// Stratum i of n, at `jitter` in [0, 1) inside it: (i + jitter) / n.
inline double stratum(uint32_t i, uint32_t n, double jitter) {
    return (static_cast<double>(i) + jitter) / static_cast<double>(n);
}

/// 32-digit base-2 radical inverse (van der Corput) of i, as the digits' integer.
inline uint32_t vanDerCorput(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x00ff00ffu) << 8) | ((i & 0xff00ff00u) >> 8);
    i = ((i & 0x0f0f0f0fu) << 4) | ((i & 0xf0f0f0f0u) >> 4);
    i = ((i & 0x33333333u) << 2) | ((i & 0xccccccccu) >> 2);
    i = ((i & 0x55555555u) << 1) | ((i & 0xaaaaaaaau) >> 1);
    return i;
}

/// The second Sobol' dimension (primitive polynomial x + 1) of i, 32 digits.
inline uint32_t sobol2(uint32_t i) {
    uint32_t result = 0;
    for (uint32_t v = 0x80000000u; i != 0; i >>= 1, v ^= v >> 1) {
        if (i & 1u) result ^= v;
    }
    return result;
}

/// 32 scrambled digits followed by 21 random bits from `low`: a fraction in [0, 1).
inline double digitsUnit(uint32_t digits, uint64_t low) {
    return unitFromBits((static_cast<uint64_t>(digits) << 32) | (low & 0xffffffffull));
}

/// A point of the unit cube: t is the stratified coordinate (volume, area or the rectangle's a),
/// u and v the others (direction, angle, the rectangle's b).
struct CubePoint {
    double t = 0.0, u = 0.0, v = 0.0;
};

/// Today's ball scheme (reference::sphereLightSamples): stratum i of t, R2 lattice (u, v).
inline CubePoint stratifiedBallPoint(uint32_t seed, uint32_t count, uint32_t i) {
    CubePoint p;
    p.t = stratum(i, count, unitFromBits(hashSample(seed, 0, i)));
    p.u = unitFromBits(hashSample(seed, 1, 0) + static_cast<uint64_t>(i) * kPlastic1);
    p.v = unitFromBits(hashSample(seed, 2, 0) + static_cast<uint64_t>(i) * kPlastic2);
    return p;
}

/// Today's disk scheme (reference::diskLightSamples): stratum i of t, golden lattice u.
inline CubePoint stratifiedDiskPoint(uint32_t seed, uint32_t count, uint32_t i) {
    CubePoint p;
    p.t = stratum(i, count, unitFromBits(hashSample(seed, 0, i)));
    p.u = unitFromBits(hashSample(seed, 1, 0) + static_cast<uint64_t>(i) * kGolden);
    return p;
}

/// Jittered nu x nv grid cell (i % nu, i / nu): t = a, u = b.
inline CubePoint stratifiedGridPoint(uint32_t seed, uint32_t nu, uint32_t nv, uint32_t i) {
    CubePoint p;
    p.t = stratum(i % nu, nu, unitFromBits(hashSample(seed, 0, i)));
    p.u = stratum(i / nu, nv, unitFromBits(hashSample(seed, 1, i)));
    return p;
}

/// Scrambled Hammersley point i of count: (i + jitter) / count, vdC(i) ^ k1, Sobol'2(i) ^ k2.
inline CubePoint lowDiscrepancyPoint(uint32_t seed, uint32_t count, uint32_t i) {
    const uint32_t k1 = static_cast<uint32_t>(hashSample(seed, 3, 0));
    const uint32_t k2 = static_cast<uint32_t>(hashSample(seed, 4, 0));
    CubePoint p;
    p.t = stratum(i, count, unitFromBits(hashSample(seed, 0, i)));
    p.u = digitsUnit(vanDerCorput(i) ^ k1, hashSample(seed, 1, i));
    p.v = digitsUnit(sobol2(i) ^ k2, hashSample(seed, 2, i));
    return p;
}

/// The rectangle's grid: nu * nv = count, cells (2 hx / nu) x (2 hy / nv) closest to square
/// (smallest max(aspect, 1 / aspect); ties: smaller nu).
inline void rectGrid(uint32_t count, double hx, double hy, uint32_t& nu, uint32_t& nv) {
    nu = 1;
    nv = count;
    double best = INFINITY;
    for (uint32_t u = 1; u <= count; ++u) {
        if (count % u != 0) continue;
        const uint32_t v = count / u;
        // cell width / height = (hx / u) / (hy / v) = (hx * v) / (hy * u); products, no sums.
        const double aspect = (hx / static_cast<double>(u)) / (hy / static_cast<double>(v));
        const double badness = aspect >= 1.0 ? aspect : 1.0 / aspect;
        if (badness < best) {
            best = badness;
            nu = u;
            nv = v;
        }
    }
}

// ---- the maps -------------------------------------------------------------------------------

/// Ball map parts: radial = cbrt(t), z = 1 - 2u, ring = sqrt(1 - z^2), (c, s) = cos/sin(2 pi v).
struct BallParts {
    double radial = 0.0, z = 0.0, ring = 0.0, c = 0.0, s = 0.0;
};

inline BallParts ballParts(const CubePoint& p) {
    BallParts b;
    b.z = 1.0 - 2.0 * p.u;  // 2u is exact; one rounding, no product to fuse
    b.ring = std::sqrt(std::fmax(0.0, std::fma(-b.z, b.z, 1.0)));
    cosSinTurns(p.v, b.c, b.s);
    b.radial = cubeRoot(p.t);
    return b;
}

/// Disk map parts: radial = sqrt(t), (c, s) = cos/sin(2 pi u).
struct DiskParts {
    double radial = 0.0, c = 0.0, s = 0.0;
};

inline DiskParts diskParts(const CubePoint& p) {
    DiskParts d;
    cosSinTurns(p.u, d.c, d.s);
    d.radial = std::sqrt(p.t);
    return d;
}

// ---- small vector helpers: explicit fma and opaque products only ---------------------------

inline double dot3(const glm::dvec3& a, const glm::dvec3& b) {
    return std::fma(a.x, b.x, std::fma(a.y, b.y, mulRounded(a.z, b.z)));
}

inline glm::dvec3 cross3(const glm::dvec3& a, const glm::dvec3& b) {
    return glm::dvec3(std::fma(a.y, b.z, -mulRounded(a.z, b.y)), std::fma(a.z, b.x, -mulRounded(a.x, b.z)),
                      std::fma(a.x, b.y, -mulRounded(a.y, b.x)));
}

/// a * x + y, component-wise fma.
inline glm::dvec3 axpy(double a, const glm::dvec3& x, const glm::dvec3& y) {
    return glm::dvec3(std::fma(a, x.x, y.x), std::fma(a, x.y, y.y), std::fma(a, x.z, y.z));
}

inline double maxAbs(const glm::dvec3& v) { return std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z))); }

inline void checkSize(double value, const char* name, const char* shape) {
    PENUMBRA_CHECK(std::isfinite(value) && value > 0.0, "penumbra::lightFrame: ", name,
                   " must be finite and > 0 for a ", shape, " light (got ", value, ")");
}

}  // namespace light_samples
}  // namespace detail

// ================================================================================================
// Lights and their normalised space

enum class LightShape : uint32_t { Disk, Rectangle, Sphere, Ellipsoid };
enum class SamplePattern : uint32_t { Stratified, LowDiscrepancy };

/// Every local sample satisfies |q| <= kLightSampleBound (strictly inside the unit ball).
inline constexpr double kLightSampleBound = 1.0 - 0x1.0p-20;

/// An area or volume light. Value-initialised: the unit sphere at the origin.
struct Light {
    LightShape shape = LightShape::Sphere;
    glm::dvec3 center{0.0};
    glm::dvec3 axis_z{0, 0, 1};  // disk/rect normal, symmetry axis; need not be unit
    glm::dvec3 axis_x{1, 0, 0};  // in-plane direction; made orthogonal to z (Gram-Schmidt)
    glm::dvec3 size{1.0};        // Disk: x = radius. Rectangle: x, y = half extents.
                                 // Sphere: x = radius. Ellipsoid: x, y, z = semi-axes.
};

/// The light's normalised space (sintorn2008 §4.1 scaling trick for ellipsoids):
/// q = inverse(scale) * transpose(rotation) * (p - center); the light lies inside |q| <= 1.
struct LightFrame {
    glm::dvec3 center{0.0};
    glm::dmat3 rotation{1.0};  // orthonormal columns: local x, y, z (right-handed)
    glm::dvec3 scale{1.0};     // Sphere/Disk: radius (all 3); Rectangle: half-diagonal
                               // (all 3); Ellipsoid: the semi-axes
    bool symmetric = true;     // rotating about local z maps the light onto itself
                               // (disk, sphere, ellipsoid with size.x == size.y)

    /// inverse(scale) * transpose(rotation) * (world - center).
    glm::dvec3 toLocal(const glm::dvec3& world) const {
        namespace ls = detail::light_samples;
        const glm::dvec3 d = world - center;
        return glm::dvec3(ls::dot3(rotation[0], d) / scale.x, ls::dot3(rotation[1], d) / scale.y,
                          ls::dot3(rotation[2], d) / scale.z);
    }
    /// center + rotation * (scale * local).
    glm::dvec3 toWorld(const glm::dvec3& local) const {
        namespace ls = detail::light_samples;
        const glm::dvec3 p(detail::mulRounded(scale.x, local.x), detail::mulRounded(scale.y, local.y),
                           detail::mulRounded(scale.z, local.z));
        return ls::axpy(p.x, rotation[0], ls::axpy(p.y, rotation[1], ls::axpy(p.z, rotation[2], center)));
    }
    /// World plane dot(n, p) + w = 0 (n need not be unit, must be non-zero and finite) ->
    /// local plane (unit n', d') so that dot(n', q) + d' has the sign of dot(n, p) + w at
    /// corresponding points; d' = signed distance of the light centre to the plane in units of
    /// the normalised space (|d'| >= 1: the plane misses the bounding sphere).
    /// dot(n, center + R S q) + w = dot(S R^T n, q) + (dot(n, center) + w), normalised.
    glm::dvec4 planeToLocal(const glm::dvec4& world_plane) const {
        namespace ls = detail::light_samples;
        const glm::dvec3 n(world_plane);
        PENUMBRA_CHECK(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z) && std::isfinite(world_plane.w),
                       "penumbra::LightFrame::planeToLocal: world_plane must be finite (got ", n.x, ", ", n.y, ", ",
                       n.z, ", ", world_plane.w, ")");
        const double m = ls::maxAbs(n);
        PENUMBRA_CHECK(m > 0.0, "penumbra::LightFrame::planeToLocal: world_plane's normal must be non-zero");
        const glm::dvec3 nm = n / m;  // max component +-1: no overflow or underflow below
        const double w = world_plane.w / m;
        const glm::dvec3 local_n(detail::mulRounded(scale.x, ls::dot3(rotation[0], nm)),
                                 detail::mulRounded(scale.y, ls::dot3(rotation[1], nm)),
                                 detail::mulRounded(scale.z, ls::dot3(rotation[2], nm)));
        const double local_w = ls::dot3(nm, center) + w;
        const double length = std::sqrt(ls::dot3(local_n, local_n));
        return glm::dvec4(local_n / length, local_w / length);
    }
};

/// The normalised space of `light`; validates it (see the header's "Bad input").
inline LightFrame lightFrame(const Light& light) {
    namespace ls = detail::light_samples;
    const uint32_t shape = static_cast<uint32_t>(light.shape);
    PENUMBRA_CHECK(shape <= static_cast<uint32_t>(LightShape::Ellipsoid),
                   "penumbra::lightFrame: light.shape must be Disk, Rectangle, Sphere or Ellipsoid (got ", shape, ")");
    ls::checkFinite(light.center, "penumbra::lightFrame", "light.center");
    ls::checkFinite(light.axis_z, "penumbra::lightFrame", "light.axis_z");
    ls::checkFinite(light.axis_x, "penumbra::lightFrame", "light.axis_x");
    const double mz = ls::maxAbs(light.axis_z), mx = ls::maxAbs(light.axis_x);
    PENUMBRA_CHECK(mz > 0.0, "penumbra::lightFrame: light.axis_z must be non-zero");
    PENUMBRA_CHECK(mx > 0.0, "penumbra::lightFrame: light.axis_x must be non-zero");
    // Scaled to a largest component of +-1 first, so tiny or huge axes neither underflow nor overflow.
    glm::dvec3 z = light.axis_z / mz;
    z /= std::sqrt(ls::dot3(z, z));
    const glm::dvec3 xs = light.axis_x / mx;
    glm::dvec3 x = ls::axpy(-ls::dot3(xs, z), z, xs);
    const double sine = std::sqrt(ls::dot3(x, x)) / std::sqrt(ls::dot3(xs, xs));
    PENUMBRA_CHECK(sine > ls::kMinAxisSine, "penumbra::lightFrame: light.axis_x (", light.axis_x.x, ", ",
                   light.axis_x.y, ", ", light.axis_x.z, ") must not be parallel to light.axis_z (", light.axis_z.x,
                   ", ", light.axis_z.y, ", ", light.axis_z.z, "): sine of their angle ", sine, " <= ",
                   ls::kMinAxisSine);
    x /= std::sqrt(ls::dot3(x, x));
    x = ls::axpy(-ls::dot3(x, z), z, x);  // second Gram-Schmidt pass: orthogonal to rounding
    x /= std::sqrt(ls::dot3(x, x));
    const glm::dvec3 y = ls::cross3(z, x);

    LightFrame frame;
    frame.center = light.center;
    frame.rotation = glm::dmat3(x, y, z);
    const glm::dvec3& size = light.size;
    switch (light.shape) {
        case LightShape::Disk:
            ls::checkSize(size.x, "light.size.x (radius)", "Disk");
            frame.scale = glm::dvec3(size.x);
            frame.symmetric = true;
            break;
        case LightShape::Rectangle: {
            ls::checkSize(size.x, "light.size.x (half extent)", "Rectangle");
            ls::checkSize(size.y, "light.size.y (half extent)", "Rectangle");
            const double m = std::fmax(size.x, size.y);
            const double a = size.x / m, b = size.y / m;
            const double diagonal = m * std::sqrt(std::fma(a, a, detail::mulRounded(b, b)));
            PENUMBRA_CHECK(std::isfinite(diagonal), "penumbra::lightFrame: light.size (", size.x, ", ", size.y,
                           ") is too large: its half-diagonal overflows");
            frame.scale = glm::dvec3(diagonal);
            frame.symmetric = false;
            break;
        }
        case LightShape::Sphere:
            ls::checkSize(size.x, "light.size.x (radius)", "Sphere");
            frame.scale = glm::dvec3(size.x);
            frame.symmetric = true;
            break;
        case LightShape::Ellipsoid: {
            ls::checkSize(size.x, "light.size.x (semi-axis)", "Ellipsoid");
            ls::checkSize(size.y, "light.size.y (semi-axis)", "Ellipsoid");
            ls::checkSize(size.z, "light.size.z (semi-axis)", "Ellipsoid");
            const double largest = std::fmax(size.x, std::fmax(size.y, size.z));
            const double smallest = std::fmin(size.x, std::fmin(size.y, size.z));
            PENUMBRA_CHECK(largest <= ls::kMaxEllipsoidRatio * smallest, "penumbra::lightFrame: light.size (",
                           size.x, ", ", size.y, ", ", size.z, ") is a degenerate Ellipsoid: largest / smallest semi-axis ",
                           largest / smallest, " > ", ls::kMaxEllipsoidRatio);
            frame.scale = size;
            frame.symmetric = size.x == size.y;
            break;
        }
    }
    return frame;
}

// ================================================================================================
// Sample sets

struct LightSampleOptions {
    uint32_t count = 128;  // N: 32..1024, multiple of 32
    uint32_t sets = 8;     // K distinct sets (1..64), laine2005 §3.4
    SamplePattern pattern = SamplePattern::Stratified;
    uint32_t seed = 0;
};

struct LightSampleSets {
    Light light;
    LightFrame frame;
    LightSampleOptions options;
    std::vector<glm::dvec3> local;  // sets*count, set-major (local[s*count+i]); |q| <= 1 - 2^-20
    std::vector<glm::dvec3> world;  // frame.toWorld(local[i]): what the CPU oracle uses

    uint32_t count() const { return options.count; }
    uint32_t sets() const { return options.sets; }
    /// count() local samples of set s (s < sets()).
    const glm::dvec3* localSet(uint32_t s) const {
        PENUMBRA_ASSERT(s < sets());
        return local.data() + static_cast<size_t>(s) * count();
    }
    /// count() world samples of set s (s < sets()).
    const glm::dvec3* worldSet(uint32_t s) const {
        PENUMBRA_ASSERT(s < sets());
        return world.data() + static_cast<size_t>(s) * count();
    }
};

/// K sets of N samples of `light` (see the header comment for the strata of each pattern).
/// Throws penumbra::Error naming the bad value (options or light).
inline LightSampleSets makeLightSampleSets(const Light& light, const LightSampleOptions& options = {}) {
    namespace ls = detail::light_samples;
    const uint32_t n = options.count, k = options.sets;
    PENUMBRA_CHECK(n >= PENUMBRA_LIGHT_SAMPLES_MIN_COUNT && n <= PENUMBRA_LIGHT_SAMPLES_MAX_COUNT &&
                       n % PENUMBRA_LIGHT_SAMPLES_COUNT_MULTIPLE == 0,
                   "penumbra::makeLightSampleSets: options.count must be a multiple of ",
                   PENUMBRA_LIGHT_SAMPLES_COUNT_MULTIPLE, " in [", PENUMBRA_LIGHT_SAMPLES_MIN_COUNT, ", ",
                   PENUMBRA_LIGHT_SAMPLES_MAX_COUNT, "] (got ", n, ")");
    PENUMBRA_CHECK(k >= 1 && k <= PENUMBRA_LIGHT_SAMPLES_MAX_SETS, "penumbra::makeLightSampleSets: options.sets must be in [1, ",
                   PENUMBRA_LIGHT_SAMPLES_MAX_SETS, "] (got ", k, ")");
    const uint32_t pattern = static_cast<uint32_t>(options.pattern);
    PENUMBRA_CHECK(pattern <= static_cast<uint32_t>(SamplePattern::LowDiscrepancy),
                   "penumbra::makeLightSampleSets: options.pattern must be Stratified or LowDiscrepancy (got ", pattern,
                   ")");
    LightSampleSets out;
    out.light = light;
    out.frame = lightFrame(light);
    out.options = options;
    out.local.resize(static_cast<size_t>(n) * k);
    out.world.resize(out.local.size());

    const bool low_discrepancy = options.pattern == SamplePattern::LowDiscrepancy;
    // Rectangle: q.x = (2a - 1) * ex, q.y = (2b - 1) * ey, the inset folded into ex, ey.
    double ex = 0.0, ey = 0.0;
    uint32_t nu = 1, nv = n;
    if (light.shape == LightShape::Rectangle) {
        ex = detail::mulRounded(ls::kInset, light.size.x / out.frame.scale.x);
        ey = detail::mulRounded(ls::kInset, light.size.y / out.frame.scale.x);
        ls::rectGrid(n, light.size.x, light.size.y, nu, nv);
    }
    for (uint32_t s = 0; s < k; ++s) {
        const uint32_t seed = options.seed + s * ls::kSetSeedStep;
        glm::dvec3* local = out.local.data() + static_cast<size_t>(s) * n;
        for (uint32_t i = 0; i < n; ++i) {
            switch (light.shape) {
                case LightShape::Sphere:
                case LightShape::Ellipsoid: {
                    const ls::BallParts b = ls::ballParts(low_discrepancy ? ls::lowDiscrepancyPoint(seed, n, i)
                                                                          : ls::stratifiedBallPoint(seed, n, i));
                    const double rho = detail::mulRounded(ls::kInset, b.radial);
                    const double r_ring = detail::mulRounded(rho, b.ring);
                    local[i] = glm::dvec3(detail::mulRounded(r_ring, b.c), detail::mulRounded(r_ring, b.s),
                                          detail::mulRounded(rho, b.z));
                    break;
                }
                case LightShape::Disk: {
                    const ls::DiskParts d = ls::diskParts(low_discrepancy ? ls::lowDiscrepancyPoint(seed, n, i)
                                                                          : ls::stratifiedDiskPoint(seed, n, i));
                    const double rho = detail::mulRounded(ls::kInset, d.radial);
                    local[i] = glm::dvec3(detail::mulRounded(rho, d.c), detail::mulRounded(rho, d.s), 0.0);
                    break;
                }
                case LightShape::Rectangle: {
                    const ls::CubePoint p = low_discrepancy ? ls::lowDiscrepancyPoint(seed, n, i)
                                                            : ls::stratifiedGridPoint(seed, nu, nv, i);
                    // 2a is exact: 2a - 1 is one rounding whether or not it is fused.
                    local[i] = glm::dvec3(detail::mulRounded(2.0 * p.t - 1.0, ex), detail::mulRounded(2.0 * p.u - 1.0, ey),
                                          0.0);
                    break;
                }
            }
        }
    }
    for (size_t i = 0; i < out.local.size(); ++i) out.world[i] = out.frame.toWorld(out.local[i]);
    return out;
}

// ================================================================================================
// Per-pixel selection (select.glsl is the GLSL twin, bit for bit)

/// The row stride c of the set pattern: floor(sets / golden ratio) | 1, clamped to [2, sets - 2]
/// (sets >= 4; 1 below: no pattern of fewer than 4 sets separates all 8 neighbours).
inline uint32_t lightSampleSetStride(uint32_t sets) {
    if (sets < 4u) return 1u;
    uint32_t c = ((sets * static_cast<uint32_t>(PENUMBRA_LIGHT_SAMPLES_STRIDE_NUMERATOR)) >> 16) | 1u;
    if (c > sets - 2u) c = sets - 2u;
    if (c < 2u) c = 2u;
    return c;
}

/// Per-pixel choice (laine2005 §3.4 banding -> noise; sintorn2008 §4.2 rotation + temporal jitter):
/// (x + c y + frame) mod sets. The 8 neighbours of a pixel use other sets whenever sets >= 4, and
/// a pixel takes every set once in `sets` consecutive frames. sets == 0 or 1: set 0.
inline uint32_t lightSampleSet(uint32_t x, uint32_t y, uint32_t frame, uint32_t sets) {
    if (sets <= 1u) return 0u;
    const uint32_t c = lightSampleSetStride(sets);
    return ((x % sets) + c * (y % sets) + (frame % sets)) % sets;
}

/// Chris Wellons' lowbias32 integer finaliser (a bijection of uint32).
inline uint32_t lightSampleHash32(uint32_t v) {
    v ^= v >> 16;
    v *= PENUMBRA_LIGHT_SAMPLES_HASH_M1;
    v ^= v >> 15;
    v *= PENUMBRA_LIGHT_SAMPLES_HASH_M2;
    v ^= v >> 16;
    return v;
}

/// The 32-bit rotation hash of (x, y, frame, seed):
/// hash32(x + hash32(y + hash32(frame + hash32(seed + 0x9e3779b9)))).
inline uint32_t lightSampleRotationHash(uint32_t x, uint32_t y, uint32_t frame, uint32_t seed) {
    const uint32_t h = lightSampleHash32(seed + PENUMBRA_LIGHT_SAMPLES_HASH_SEED_OFFSET);
    return lightSampleHash32(x + lightSampleHash32(y + lightSampleHash32(frame + h)));
}

/// Rotation about local z for symmetric lights, in turns [0,1): 32-bit integer hash * 2^-32.
inline double lightSampleRotationTurns(uint32_t x, uint32_t y, uint32_t frame, uint32_t seed) {
    return static_cast<double>(lightSampleRotationHash(x, y, frame, seed)) * 0x1.0p-32;
}

/// What penumbraLightSampleRotationTurns returns: the turn truncated to float's 24 bits,
/// (hash >> 8) * 2^-24 — exact in float and still < 1 (rounding to nearest could give 1.0f).
inline float lightSampleRotationTurnsFloat(uint32_t x, uint32_t y, uint32_t frame, uint32_t seed) {
    return static_cast<float>(lightSampleRotationHash(x, y, frame, seed) >> 8) * 0x1.0p-24f;
}

// ================================================================================================
// The reference:: sample sets of the oracle's tests and the demo (unchanged bits)

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

    std::vector<glm::dvec3> samples(count);
    for (uint32_t i = 0; i < count; ++i) {
        const ls::BallParts b = ls::ballParts(ls::stratifiedBallPoint(seed, count, i));
        const double r = radius * b.radial;
        const double r_ring = r * b.ring;
        samples[i] = glm::dvec3(std::fma(r_ring, b.c, center.x), std::fma(r_ring, b.s, center.y),
                                std::fma(r, b.z, center.z));
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

    std::vector<glm::dvec3> samples(count);
    for (uint32_t i = 0; i < count; ++i) {
        const ls::DiskParts d = ls::diskParts(ls::stratifiedDiskPoint(seed, count, i));
        const double r = radius * d.radial;
        const double rc = r * d.c, rs = r * d.s;
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
        const double b = ls::stratum(j, nv, 0.5);  // the cell centre: (j + 1/2) / nv, one rounding
        for (uint32_t i = 0; i < nu; ++i) {
            const double a = ls::stratum(i, nu, 0.5);
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
