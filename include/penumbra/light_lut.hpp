// penumbra/light_lut.hpp — the light-sample LUT (block 5; sintorn2008 §4.2, Fig. 6): a table
// indexed by a plane that returns the bit mask of the light samples strictly behind it, plus a
// certified mode that also says which bits the table cannot vouch for.
//
// Integration summary
//   Needs:    GLM and the C++17 standard library (threads for the CPU generator); no GL. The GPU
//             generator and the GLSL lookups are in penumbra/gl/light_lut.hpp and
//             shaders/penumbra/light_lut/ (lookup.glsl: penumbraLutBehind,
//             penumbraLutBehindCertified, penumbraExactBehind, penumbraLutCombine).
//   Input:    light samples in the light's normalised space (LightFrame::toLocal, light_samples.hpp):
//             K sets of N samples, every |q| <= 1 - 2^-20. Planes in the same space: unit normal n and
//             d = signed distance of the light centre to the plane in units of the bounding radius
//             (LightFrame::planeToLocal); a sample q is *behind* when dot(n, q) + d < 0, strictly.
//   Produces: lightLutSetup(): the parameter block (PenumbraLutParams, light_lut_shared.h), sizes, and
//             the three small arrays the GPU generator reads (samples, normal cells, distance cells);
//             generateLightLut(): the tables on the CPU (multithreaded, progress, cancellation),
//             byte-identical to the GPU generator's; lightLutLookup()/lightLutLocate(): the lookup,
//             CPU twin of lookup.glsl; exactBehind(): the ground truth; exactBehindOracle(): the
//             same on the GPU's float inputs, what the exact modes are checked against.
//
// Layout. One table per 128 samples of one set: table t = set * tables_per_set + block answers the
// set's samples 128 * block ... 128 * block + 127 (bits past N are 0). A table is R_d slices of
// R_n x R_n texels, texel (i, j, k) at index (k * R_n + j) * R_n + i, one uvec4 each (bit b of word w
// = sample 32 w + b): exactly an RGBA32UI 3D texture of R_n x R_n x R_d, so a table can be uploaded
// as one with glTexImage3D. The LUT is `tables` such tables (the centre masks), followed in
// certified mode by as many again (the uncertain masks) at uvec4 index params.uncertain_offset.
//
// Cells. Normal: octahedral map (default) or two angles, R_n x R_n cells; distance: R_d = R cells over
// d in [0, 1] when symmetric (the default: (n, d) and (-n, -d) have complementary masks, so only
// d >= 0 is stored and the table halves, or, at equal memory, the distance cells halve), else over
// [-1, 1]. |d| >= 1 misses the bounding sphere and is answered without the table: d >= 1 -> no
// sample behind, d <= -1 -> every sample behind (all |q| < 1).
//   Why octahedral: locating a cell takes abs, add, one division (no acos/atan2, whose GPU precision
//   GLSL does not specify, so a certificate could not cover it), and its cells are of near-equal
//   solid angle (max/min ~2) where lat-long cells shrink to slivers at the poles; measured in the
//   issue note and by tools (light_lut_error): same memory, fewer wrong and uncertain bits.
//
// Seed mode (centre sampling). A texel's mask is the exact mask of its cell's centre plane
// (n_c, d_c), evaluated in fp64. Wrong bits are samples within a cell's reach of the actual plane.
//
// Certified mode (the step past the seed). A sample is *uncertain* in a cell when some plane of the
// cell (inflated by `tolerance`) may put it on either side:
//     |t + d_c| <= rho |q_perp| + (rho^2 / 2) |t| + h (+ margins),
// with t = dot(n_c, q), q_perp = q - t n_c, rho >= max |n - n_c| over the cell's normals (computed
// exactly from the cell's vertices on the octahedron, where the angle to n_c is quasi-convex, or
// bounded by arc length for two angles) and h the cell's half width in d. (Why: n = n_c cos a + e
// sin a with e _|_ n_c, so dot(n - n_c, q) = (cos a - 1) t + sin a dot(e, q_perp), and
// 1 - cos a <= rho^2 / 2, sin a <= rho. Evaluated without sqrt: A = |v| - (rho^2/2)|t| - h is
// certain when A > 0 and A^2 > rho^2 (|q|^2 - t^2) + 1e-12; 16 % fewer uncertain bits than
// rho |q|.) Every other sample is certain: behind iff its centre
// bit is set. lightLutLookup gives (centre, uncertain); certain-behind = centre & ~uncertain; a
// consumer that tests the uncertain samples against the actual plane gets the exact mask. The
// certificate holds for lookups whose normal-cell coordinates, d and sample positions are each off
// by at most `tolerance` (1e-6 covers float lookups and float samples on any GPU for the octahedral
// mapping; for two angles it also has to cover the driver's acos/atan2). A consumer may ask for
// more (up to 1e-2) to buy a margin: the soft pipeline's Exact mode needs one above the oracle's
// coplanar reach (sampleBasedSoftLutTolerance); each certificate then covers planes that far off.
//
// Determinism. The generator evaluates only fp64 +, * and compares (products rounded separately, no
// fused multiply-add: detail::mulRounded here, `precise` in GLSL) on the three arrays the setup
// computed, so CPU and GPU tables are byte-identical wherever fp64 add/mul are IEEE (llvmpipe and
// every desktop GPU with fp64). The setup's arrays use sqrt and the library-independent sin/cos of
// light_samples.hpp, so they are the same on every IEEE-754 platform.
//
// Exact side test (exactBehind<float>, lookup.glsl penumbraLutSampleBehind; what lutResolve uses).
// The reference is exactBehindOracle: the sign of dot(n, q) + w in fp64 on the float plane and the
// float samples (what the GPU has). A float evaluation s_f alone is not it: it rounds to 0 or flips
// within ~1e-7 of the plane. With u = 2^-23 (GLSL 4.50 §4.7.1: float +, * correctly rounded in an
// unspecified mode; fp64 charged the same u) both evaluations pass every term through <= 4
// roundings: |s - X| <= gamma_4 P, X exact, P = sum |n_i q_i| + |w| <= |n|_1 + |w| (|q_i| <= 1).
// So |s_f| > B = REL (|n|_1 + |w|) + ABS >= 2 gamma_4 P (+ flushed denormals: ABS) gives s_f, X and
// the fp64 value one nonzero sign; below B the fp64 value itself decides (light_lut_shared.h).
//
// Bad input (penumbra::Error at setup, naming the value): N not a multiple of 32 or outside 32..1024,
// sets 0, resolution outside 16..256 or odd, tolerance not in [0, 1e-2], a sample not finite or with
// |q| > 1 - 2^-20, a table beyond 2^32 uvec4s. Per lookup (no throw): a plane with a non-finite value
// or a zero normal has the documented empty mask (no sample behind, certain).
#ifndef PENUMBRA_LIGHT_LUT_HPP
#define PENUMBRA_LIGHT_LUT_HPP

#include "penumbra/detail/float_ops.hpp"
#include "penumbra/detail/shared.hpp"
#include "penumbra/error.hpp"
#include "penumbra/light_samples.hpp"

#if __has_include(<penumbra/light_lut/light_lut_shared.h>)
#include <penumbra/light_lut/light_lut_shared.h>
#else
#include "../../shaders/penumbra/light_lut/light_lut_shared.h"
#endif

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <thread>
#include <type_traits>
#include <vector>

namespace penumbra {

static_assert(sizeof(shared::PenumbraLutParams) == 48, "light_lut_shared.h: PenumbraLutParams is 48 bytes");

enum class LutNormalMapping : uint32_t {
    Octahedral = PENUMBRA_LUT_MAPPING_OCTAHEDRAL,
    Spherical = PENUMBRA_LUT_MAPPING_SPHERICAL,  // two angles: polar angle from local z, azimuth
};

/// Value-initialised = the defaults.
struct LightLutOptions {
    uint32_t resolution = 128;  ///< R: R x R normal cells x R distance cells; even, 16..256
    LutNormalMapping mapping = LutNormalMapping::Octahedral;
    bool symmetric = true;      ///< store d >= 0 only (complement for d < 0)
    bool certified = false;     ///< also store the uncertain masks (twice the memory)
    double tolerance = 1e-6;    ///< slack the certificates allow in cell coordinates, d and samples
};

/// 128 bits: bit b of word w is sample 32 w + b of one table.
using LutMask = std::array<uint32_t, 4>;

/// A lookup's answer: the centre plane's mask and (certified mode) the bits it cannot vouch for.
/// certain behind = centre & ~uncertain; certain in front = ~centre & ~uncertain.
struct LutAnswer {
    LutMask centre{};
    LutMask uncertain{};
};

/// Where a plane's answer comes from (lightLutLocate; the same in lookup.glsl).
struct LutCell {
    uint32_t texel = 0;  ///< texel index inside a table, when trivial == 0
    bool flip = false;   ///< symmetric table read for (-n, -d): complement the centre mask
    int trivial = 0;     ///< 0 read the table; +1 every sample behind; -1 none (also bad planes)
};

/// Everything a generator or a lookup needs, computed once (lightLutSetup).
struct LightLutSetup {
    LightLutOptions options;
    shared::PenumbraLutParams params{};
    /// tables * 128 entries, table-major: (x, y, z, |q|^2 rounded up); padding past N is zero.
    std::vector<glm::dvec4> samples;
    /// R_n * R_n entries, index j * R_n + i: centre normal and rho (chord bound + tolerance).
    std::vector<glm::dvec4> normal_cells;
    /// R_d entries: centre d_c and h (half width + tolerance + rounding margin).
    std::vector<glm::dvec2> distance_cells;

    /// uvec4 texels of the whole LUT (centre tables, then uncertain tables when certified).
    uint64_t texelCount() const {
        return uint64_t(params.texels_per_table) * params.tables * (options.certified ? 2u : 1u);
    }
    /// Bytes of the LUT: 16 per texel.
    uint64_t tableBytes() const { return texelCount() * 16u; }
    /// Bytes of the generator's inputs (samples, normal and distance cells).
    uint64_t inputBytes() const {
        return samples.size() * sizeof(glm::dvec4) + normal_cells.size() * sizeof(glm::dvec4) +
               distance_cells.size() * sizeof(glm::dvec2);
    }
};

namespace detail::light_lut {

inline constexpr double kMaxSampleRadius = 1.0 - 0x1.0p-20;
/// Absolute slack of the squared comparison (every term is below 4: rounding stays under 1e-15).
inline constexpr double kReachMargin = 1e-12;

/// Octahedral decode of (u, v) in [-1, 1]^2 to a point on |x| + |y| + |z| = 1.
inline glm::dvec3 octahedronPoint(double u, double v) {
    const double z = 1.0 - std::fabs(u) - std::fabs(v);
    if (z >= 0.0) return {u, v, z};
    return {std::copysign(1.0 - std::fabs(v), u), std::copysign(1.0 - std::fabs(u), v), z};
}

// The setup's arithmetic keeps products opaque (detail::mulRounded) like the texel function: the
// cells must not change with -ffp-contract / -mfma (tests/twin_digest).
inline glm::dvec3 unit(const glm::dvec3& p) { return p / std::sqrt(dotRounded(p, p)); }

inline double chord(const glm::dvec3& a, const glm::dvec3& b) {
    const glm::dvec3 d = a - b;
    return std::sqrt(dotRounded(d, d));
}

/// Normal cell (i, j) of the octahedral map: centre normal, and the largest chord from it to the
/// cell's normals. The cell (R even: it never straddles u = 0 or v = 0) maps to at most two planar
/// convex pieces of the octahedron (split by the fold |u| + |v| = 1); the angle to n_c is
/// quasi-convex on each, so its maximum is at a piece vertex: a cell corner or a fold crossing.
inline glm::dvec4 octahedralCell(uint32_t i, uint32_t j, uint32_t r) {
    const double u0 = -1.0 + 2.0 * i / r, u1 = -1.0 + 2.0 * (i + 1) / r;
    const double v0 = -1.0 + 2.0 * j / r, v1 = -1.0 + 2.0 * (j + 1) / r;
    const double uc = 0.5 * (u0 + u1), vc = 0.5 * (v0 + v1);
    const glm::dvec3 centre = unit(octahedronPoint(uc, vc));
    double rho = 0.0;
    auto reach = [&](double u, double v) { rho = std::max(rho, chord(unit(octahedronPoint(u, v)), centre)); };
    reach(u0, v0), reach(u1, v0), reach(u0, v1), reach(u1, v1);
    const double su = uc < 0 ? -1.0 : 1.0, sv = vc < 0 ? -1.0 : 1.0;
    // Fold su u + sv v = 1 against the four edges.
    for (double u : {u0, u1}) {
        const double v = sv * (1.0 - mulRounded(su, u));
        if (v > v0 && v < v1) reach(u, v);
    }
    for (double v : {v0, v1}) {
        const double u = su * (1.0 - mulRounded(sv, v));
        if (u > u0 && u < u1) reach(u, v);
    }
    return {centre, rho};
}

/// Normal cell (i, j) of the two-angle map: theta in [pi j / R, pi (j+1) / R] from local z, phi in
/// [-pi + 2 pi i / R, ...]. Chord <= arc length along the centre's latitude then a meridian.
inline glm::dvec4 sphericalCell(uint32_t i, uint32_t j, uint32_t r) {
    namespace ls = ::penumbra::detail::light_samples;
    const double kPi = 3.14159265358979323846;
    double cos_theta = 0, sin_theta = 0, cos_phi = 0, sin_phi = 0;
    ls::cosSinTurns((j + 0.5) / (2.0 * r), cos_theta, sin_theta);
    double phi_turns = (i + 0.5) / r - 0.5;
    if (phi_turns < 0.0) phi_turns += 1.0;
    ls::cosSinTurns(phi_turns, cos_phi, sin_phi);
    const glm::dvec3 centre(sin_theta * cos_phi, sin_theta * sin_phi, cos_theta);
    const double half_theta = kPi / (2.0 * r), half_phi = kPi / r;
    return {centre, half_theta + mulRounded(sin_theta, half_phi)};
}

/// The texel function both generators evaluate (fp64 +, *, compares; products rounded).
inline void texel(const LightLutSetup& setup, uint32_t table, uint32_t texel_index, LutMask& centre,
                  LutMask& uncertain) {
    const shared::PenumbraLutParams& p = setup.params;
    const uint32_t rn = p.resolution_normal;
    const uint32_t cell = texel_index % (rn * rn), slice = texel_index / (rn * rn);
    const glm::dvec4 nc = setup.normal_cells[cell];
    const glm::dvec2 dc = setup.distance_cells[slice];
    const uint32_t block = table % p.tables_per_set;
    centre = LutMask{};
    uncertain = LutMask{};
    const uint32_t count = std::min<uint32_t>(PENUMBRA_LUT_SAMPLES_PER_TABLE, p.samples_per_set - block * 128u);
    const double rho2 = mulRounded(nc.w, nc.w), half_rho2 = 0.5 * rho2;
    for (uint32_t b = 0; b < count; ++b) {
        const glm::dvec4 s = setup.samples[size_t(table) * 128u + b];
        const double t = dotRounded(glm::dvec3(s), glm::dvec3(nc));
        const double k = mulRounded(half_rho2, std::fabs(t));
        const double reach2 = mulRounded(rho2, s.w - mulRounded(t, t)) + kReachMargin;
        const double v = t + dc.x;
        const double a = (std::fabs(v) - k) - dc.y;
        if (v < 0.0) centre[b >> 5] |= 1u << (b & 31);
        if (!(a > 0.0 && mulRounded(a, a) > reach2)) uncertain[b >> 5] |= 1u << (b & 31);
    }
}

/// B of the exact side test for a float plane (twin of penumbraLutExactBound).
inline float exactBound(const glm::vec4& plane) {
    const float s = ((std::fabs(plane.x) + std::fabs(plane.y)) + std::fabs(plane.z)) + std::fabs(plane.w);
    return mulRounded(float(PENUMBRA_LUT_EXACT_REL), s) + float(PENUMBRA_LUT_EXACT_ABS);
}

/// dot(n, q) + w < 0 in fp64 on float inputs: the products are exact, the sums round once each.
inline bool behindFp64(const glm::vec4& plane, const glm::vec3& q) {
    return dotRounded(glm::dvec3(plane), glm::dvec3(q)) + double(plane.w) < 0.0;
}

/// The exact side test (twin of penumbraLutSampleBehindBounded): the float value where it clears
/// `bound`, else fp64. NaN fails the filter and goes to fp64, as in GLSL.
inline bool behindFiltered(const glm::vec4& plane, float bound, const glm::vec3& q) {
    const float s = dotRounded(glm::vec3(plane), q) + plane.w;
    if (std::fabs(s) > bound) return s < 0.0f;
    return behindFp64(plane, q);
}

inline LutMask complement(const LutMask& m, const LutMask& valid) {
    return {~m[0] & valid[0], ~m[1] & valid[1], ~m[2] & valid[2], ~m[3] & valid[3]};
}

}  // namespace detail::light_lut

/// Validates and prepares a LUT for `sets` sets of `samples_per_set` samples each, given in the
/// light's normalised space, set-major (local[s * N + i]). Throws penumbra::Error (see header).
inline LightLutSetup lightLutSetup(const glm::dvec3* local, uint32_t samples_per_set, uint32_t sets,
                                   const LightLutOptions& options = {}) {
    namespace ll = detail::light_lut;
    PENUMBRA_CHECK(samples_per_set >= 32 && samples_per_set <= 1024 && samples_per_set % 32 == 0,
                   "lightLutSetup: samples per set must be a multiple of 32 in 32..1024 (got ", samples_per_set, ")");
    PENUMBRA_CHECK(sets >= 1, "lightLutSetup: sets must be >= 1 (got ", sets, ")");
    PENUMBRA_CHECK(local != nullptr, "lightLutSetup: local samples must not be null");
    const uint32_t r = options.resolution;
    PENUMBRA_CHECK(r >= PENUMBRA_LUT_MIN_RESOLUTION && r <= PENUMBRA_LUT_MAX_RESOLUTION && r % 2 == 0,
                   "lightLutSetup: resolution must be even in ", PENUMBRA_LUT_MIN_RESOLUTION, "..",
                   PENUMBRA_LUT_MAX_RESOLUTION, " (got ", r, ")");
    PENUMBRA_CHECK(options.mapping == LutNormalMapping::Octahedral || options.mapping == LutNormalMapping::Spherical,
                   "lightLutSetup: unknown normal mapping ", static_cast<uint32_t>(options.mapping));
    PENUMBRA_CHECK(options.tolerance >= 0.0 && options.tolerance <= 1e-2,
                   "lightLutSetup: tolerance must be in [0, 1e-2] (got ", options.tolerance, ")");
    const uint32_t tables_per_set = (samples_per_set + 127u) / 128u;
    const uint64_t texels = uint64_t(r) * r * r;
    const uint64_t total = texels * tables_per_set * sets * (options.certified ? 2u : 1u);
    PENUMBRA_CHECK(total <= 0xFFFFFFFFull, "lightLutSetup: ", total, " texels (", sets, " sets x ", tables_per_set,
                   " tables x ", r, "^3", options.certified ? " x 2, certified" : "", ") exceed 2^32 - 1");

    LightLutSetup setup;
    setup.options = options;
    shared::PenumbraLutParams& p = setup.params;
    p.resolution_normal = r;
    p.resolution_distance = r;
    p.tables = tables_per_set * sets;
    p.tables_per_set = tables_per_set;
    p.samples_per_set = samples_per_set;
    p.sets = sets;
    p.mapping = static_cast<uint32_t>(options.mapping);
    p.flags = (options.symmetric ? PENUMBRA_LUT_FLAG_SYMMETRIC : 0u) | (options.certified ? PENUMBRA_LUT_FLAG_CERTIFIED : 0u);
    p.texels_per_table = static_cast<uint32_t>(texels);
    p.uncertain_offset = options.certified ? static_cast<uint32_t>(texels * p.tables) : 0u;

    setup.samples.assign(size_t(p.tables) * 128u, glm::dvec4(0.0));
    for (uint32_t s = 0; s < sets; ++s) {
        for (uint32_t i = 0; i < samples_per_set; ++i) {
            const glm::dvec3 q = local[size_t(s) * samples_per_set + i];
            PENUMBRA_CHECK(std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z), "lightLutSetup: sample ", i,
                           " of set ", s, " is not finite (", q.x, ", ", q.y, ", ", q.z, ")");
            const double length = std::sqrt(detail::dotRounded(q, q));
            PENUMBRA_CHECK(length <= ll::kMaxSampleRadius, "lightLutSetup: sample ", i, " of set ", s,
                           " lies at |q| = ", length, ", outside the normalised light (|q| <= 1 - 2^-20)");
            // |q|^2 rounded up: the reach rho |q_perp| must not undershoot.
            setup.samples[(size_t(s) * tables_per_set + i / 128u) * 128u + i % 128u] =
                glm::dvec4(q, detail::mulRounded(length, length) * (1.0 + 0x1.0p-50));
        }
    }
    // Margins: `tolerance` in cell coordinates moves the normal by at most 3 sqrt(2) tolerance
    // (octahedral: |d n| <= |d o| / |o| <= sqrt(3) * sqrt(3) per unit uv, sqrt 2 for the max norm)
    // or 2 tolerance (two angles); in d and in the sample position by tolerance each; 1e-12 covers
    // the rounding of the fp64 evaluation (all terms are below 4).
    const double rounding = 1e-12;
    const double normal_slack = options.mapping == LutNormalMapping::Octahedral ? (3.0 * std::sqrt(2.0)) * options.tolerance
                                                                                 : 2.0 * options.tolerance;
    setup.normal_cells.resize(size_t(r) * r);
    for (uint32_t j = 0; j < r; ++j)
        for (uint32_t i = 0; i < r; ++i) {
            glm::dvec4 cell = options.mapping == LutNormalMapping::Octahedral ? ll::octahedralCell(i, j, r)
                                                                             : ll::sphericalCell(i, j, r);
            cell.w = (detail::mulRounded(cell.w, 1.0 + 1e-12) + normal_slack) + rounding;
            setup.normal_cells[size_t(j) * r + i] = cell;
        }
    setup.distance_cells.resize(r);
    const double lo = options.symmetric ? 0.0 : -1.0, width = (options.symmetric ? 1.0 : 2.0) / r;
    for (uint32_t k = 0; k < r; ++k)
        setup.distance_cells[k] = glm::dvec2(lo + detail::mulRounded(k + 0.5, width),
                                             (0.5 * width + 2.0 * options.tolerance) + rounding);
    return setup;
}

/// Same, from a std::vector of sets * N local samples.
inline LightLutSetup lightLutSetup(const std::vector<glm::dvec3>& local, uint32_t samples_per_set,
                                   const LightLutOptions& options = {}) {
    PENUMBRA_CHECK(samples_per_set > 0 && !local.empty() && local.size() % samples_per_set == 0,
                   "lightLutSetup: ", local.size(), " samples are not whole sets of ", samples_per_set);
    return lightLutSetup(local.data(), samples_per_set, static_cast<uint32_t>(local.size() / samples_per_set), options);
}

/// From light_samples.hpp's sets: their local samples (already inside |q| <= 1 - 2^-20).
inline LightLutSetup lightLutSetup(const LightSampleSets& sets, const LightLutOptions& options = {}) {
    return lightLutSetup(sets.local, sets.count(), options);
}

/// One texel of one table, as both generators compute it.
inline LutAnswer lightLutTexel(const LightLutSetup& setup, uint32_t table, uint32_t texel_index) {
    PENUMBRA_ASSERT(table < setup.params.tables && texel_index < setup.params.texels_per_table);
    LutAnswer answer;
    detail::light_lut::texel(setup, table, texel_index, answer.centre, answer.uncertain);
    if (!setup.options.certified) answer.uncertain = LutMask{};
    return answer;
}

/// Called now and then from the generating thread with the fraction done; return false to cancel.
using LutProgress = std::function<bool(double fraction)>;

/// Fills `texels` (setup.texelCount() uvec4s, 4 words each) on the CPU with `threads` threads
/// (0 = all cores). Returns false when `progress` cancelled (the table is then incomplete).
inline bool generateLightLut(const LightLutSetup& setup, uint32_t* words, uint64_t word_count,
                             const LutProgress& progress = {}, unsigned threads = 0) {
    PENUMBRA_CHECK(words != nullptr && word_count >= setup.texelCount() * 4u, "generateLightLut: the output holds ",
                   word_count, " words, the LUT needs ", setup.texelCount() * 4u);
    const shared::PenumbraLutParams& p = setup.params;
    const uint32_t rn = p.resolution_normal, rd = p.resolution_distance;
    // Tasks: one (table, normal row j). Per normal cell, t and w of every sample are computed once
    // and reused for all R_d distance cells: the same operations as texel(), in the same order.
    const uint64_t tasks = uint64_t(p.tables) * rn;
    std::atomic<uint64_t> next{0}, done{0};
    std::atomic<bool> cancelled{false};
    auto work = [&](bool caller) {
        std::vector<double> t(128), k(128), reach2(128);
        for (;;) {
            if (cancelled.load(std::memory_order_relaxed)) return;
            const uint64_t task = next.fetch_add(1);
            if (task >= tasks) return;
            const uint32_t table = static_cast<uint32_t>(task / rn), j = static_cast<uint32_t>(task % rn);
            const uint32_t block = table % p.tables_per_set;
            const uint32_t count = std::min<uint32_t>(128u, p.samples_per_set - block * 128u);
            for (uint32_t i = 0; i < rn; ++i) {
                const glm::dvec4 nc = setup.normal_cells[size_t(j) * rn + i];
                const double rho2 = detail::mulRounded(nc.w, nc.w), half_rho2 = 0.5 * rho2;
                for (uint32_t b = 0; b < count; ++b) {
                    const glm::dvec4 s = setup.samples[size_t(table) * 128u + b];
                    t[b] = detail::dotRounded(glm::dvec3(s), glm::dvec3(nc));
                    k[b] = detail::mulRounded(half_rho2, std::fabs(t[b]));
                    reach2[b] = detail::mulRounded(rho2, s.w - detail::mulRounded(t[b], t[b])) +
                                detail::light_lut::kReachMargin;
                }
                for (uint32_t kd = 0; kd < rd; ++kd) {
                    const glm::dvec2 dc = setup.distance_cells[kd];
                    LutMask centre{}, uncertain{};
                    for (uint32_t b = 0; b < count; ++b) {
                        const double v = t[b] + dc.x;
                        const double a = (std::fabs(v) - k[b]) - dc.y;
                        if (v < 0.0) centre[b >> 5] |= 1u << (b & 31);
                        if (!(a > 0.0 && detail::mulRounded(a, a) > reach2[b])) uncertain[b >> 5] |= 1u << (b & 31);
                    }
                    const uint64_t texel = (uint64_t(kd) * rn + j) * rn + i;
                    uint32_t* out = words + (uint64_t(table) * p.texels_per_table + texel) * 4u;
                    std::copy(centre.begin(), centre.end(), out);
                    if (setup.options.certified) {
                        uint32_t* out_u = words + (uint64_t(p.uncertain_offset) + uint64_t(table) * p.texels_per_table + texel) * 4u;
                        std::copy(uncertain.begin(), uncertain.end(), out_u);
                    }
                }
            }
            const uint64_t finished = done.fetch_add(1) + 1;
            if (caller && progress && !progress(double(finished) / double(tasks))) cancelled.store(true);
        }
    };
    unsigned count = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (unsigned n = 1; n < count; ++n) pool.emplace_back(work, false);
    work(true);
    for (std::thread& thread : pool) thread.join();
    if (cancelled.load()) return false;
    if (progress) progress(1.0);
    return true;
}

/// The whole LUT on the CPU, as a vector of setup.texelCount() * 4 words. Throws penumbra::Error
/// if `progress` cancels.
inline std::vector<uint32_t> generateLightLut(const LightLutSetup& setup, const LutProgress& progress = {},
                                              unsigned threads = 0) {
    std::vector<uint32_t> words(setup.texelCount() * 4u);
    PENUMBRA_CHECK(generateLightLut(setup, words.data(), words.size(), progress, threads),
                   "generateLightLut: cancelled");
    return words;
}

/// The cell of a local plane (n, d): n need not be unit (d is divided by |n|). Real = float gives
/// the float lookup of lookup.glsl (same operations, `precise`), double the reference lookup.
/// Non-finite planes and zero normals give trivial = -1 (no sample behind).
template <typename Real>
inline LutCell lightLutLocate(const shared::PenumbraLutParams& p, const glm::vec<4, Real>& plane) {
    using detail::mulRounded;
    LutCell cell;
    glm::vec<3, Real> n(plane);
    const Real length2 = detail::dotRounded(n, n);
    const Real length = std::sqrt(length2);
    if (!(length > Real(0)) || !std::isfinite(length) || !std::isfinite(plane.w)) {
        cell.trivial = -1;
        return cell;
    }
    Real d = plane.w / length;
    if (d >= Real(1)) {
        cell.trivial = -1;
        return cell;
    }
    if (d <= Real(-1)) {
        cell.trivial = 1;
        return cell;
    }
    if ((p.flags & PENUMBRA_LUT_FLAG_SYMMETRIC) && d < Real(0)) {
        cell.flip = true;
        n = -n;
        d = -d;
    }
    const int rn = static_cast<int>(p.resolution_normal), rd = static_cast<int>(p.resolution_distance);
    const Real half_rn = Real(0.5) * Real(rn);
    int i = 0, j = 0;
    if (p.mapping == PENUMBRA_LUT_MAPPING_OCTAHEDRAL) {
        const Real sum = (std::fabs(n.x) + std::fabs(n.y)) + std::fabs(n.z);
        Real u = n.x / sum, v = n.y / sum;
        if (n.z < Real(0)) {
            const Real fu = Real(1) - std::fabs(v), fv = Real(1) - std::fabs(u);
            u = u < Real(0) ? -fu : fu;
            v = v < Real(0) ? -fv : fv;
        }
        i = static_cast<int>(std::floor(mulRounded(u + Real(1), half_rn)));
        j = static_cast<int>(std::floor(mulRounded(v + Real(1), half_rn)));
    } else {
        const Real kPi = Real(3.14159265358979323846);
        const Real z = std::clamp(n.z / length, Real(-1), Real(1));
        const Real theta = std::acos(z), phi = std::atan2(n.y, n.x);
        j = static_cast<int>(std::floor(mulRounded(theta / kPi, Real(rn))));
        i = static_cast<int>(std::floor(mulRounded((phi + kPi) / (Real(2) * kPi), Real(rn))));
    }
    i = std::clamp(i, 0, rn - 1);
    j = std::clamp(j, 0, rn - 1);
    const Real dk = (p.flags & PENUMBRA_LUT_FLAG_SYMMETRIC) ? mulRounded(d, Real(rd))
                                                             : mulRounded(d + Real(1), Real(0.5) * Real(rd));
    const int k = std::clamp(static_cast<int>(std::floor(dk)), 0, rd - 1);
    cell.texel = static_cast<uint32_t>((k * rn + j) * rn + i);
    return cell;
}

/// The bits of table `table` that stand for real samples (all of them but past N in the last block).
inline LutMask lightLutValidMask(const shared::PenumbraLutParams& p, uint32_t table) {
    const uint32_t block = table % p.tables_per_set;
    const uint32_t count = std::min<uint32_t>(128u, p.samples_per_set - block * 128u);
    LutMask m{};
    for (uint32_t w = 0; w < 4; ++w) {
        const uint32_t bits = count > 32 * w ? std::min<uint32_t>(32u, count - 32 * w) : 0u;
        m[w] = bits == 32 ? 0xFFFFFFFFu : (1u << bits) - 1u;
    }
    return m;
}

/// Looks a local plane up in table `table` of `texels` (the LUT's uvec4s as words): seed mode
/// reads `centre`, certified mode also `uncertain`. CPU twin of penumbraLutBehindCertified.
template <typename Real>
inline LutAnswer lightLutLookup(const shared::PenumbraLutParams& p, const uint32_t* words, uint32_t table,
                                const glm::vec<4, Real>& plane) {
    const LutCell cell = lightLutLocate(p, plane);
    const LutMask valid = lightLutValidMask(p, table);
    LutAnswer answer;
    if (cell.trivial != 0) {
        if (cell.trivial > 0) answer.centre = valid;
        return answer;
    }
    const uint32_t* c = words + (uint64_t(table) * p.texels_per_table + cell.texel) * 4u;
    std::copy(c, c + 4, answer.centre.begin());
    if (p.flags & PENUMBRA_LUT_FLAG_CERTIFIED) {
        const uint32_t* u = words + (uint64_t(p.uncertain_offset) + uint64_t(table) * p.texels_per_table + cell.texel) * 4u;
        std::copy(u, u + 4, answer.uncertain.begin());
    }
    if (cell.flip) answer.centre = detail::light_lut::complement(answer.centre, valid);
    return answer;
}

/// Per-pixel rotation of a rotationally symmetric light's samples (sintorn2008 §4.2: "rotating the
/// normal around the symmetry axes ... jittering at almost no cost"): the samples rotated by angle
/// a about local z are behind `plane` exactly when the unrotated ones are behind the returned plane,
/// whose normal is rotated by -a. cos_a, sin_a: of the angle (light_samples.hpp's
/// lightSampleRotationTurns gives it per pixel and frame). Twin of penumbraLutRotate.
template <typename Real>
inline glm::vec<4, Real> lightLutRotate(const glm::vec<4, Real>& plane, Real cos_a, Real sin_a) {
    using detail::mulRounded;
    return {mulRounded(cos_a, plane.x) + mulRounded(sin_a, plane.y), mulRounded(cos_a, plane.y) - mulRounded(sin_a, plane.x),
            plane.z, plane.w};
}

/// The ground truth: bits of the samples of table `table` strictly behind the plane (n need not
/// be unit: only the sign of dot(n, q) + w counts). Real = double: fp64 on the setup's double
/// samples; Real = float: the CPU twin of penumbraExactBehind, on the samples rounded to float, equal
/// to exactBehindOracle (header, "Exact side test").
template <typename Real>
inline LutMask exactBehind(const LightLutSetup& setup, uint32_t table, const glm::vec<4, Real>& plane) {
    LutMask m{};
    const shared::PenumbraLutParams& p = setup.params;
    const uint32_t block = table % p.tables_per_set;
    const uint32_t count = std::min<uint32_t>(128u, p.samples_per_set - block * 128u);
    if constexpr (std::is_same_v<Real, float>) {
        const float bound = detail::light_lut::exactBound(plane);
        for (uint32_t b = 0; b < count; ++b) {
            const glm::vec3 q(setup.samples[size_t(table) * 128u + b]);
            if (detail::light_lut::behindFiltered(plane, bound, q)) m[b >> 5] |= 1u << (b & 31);
        }
    } else {
        const glm::vec<3, Real> n(plane);
        for (uint32_t b = 0; b < count; ++b) {
            const glm::vec<3, Real> q(setup.samples[size_t(table) * 128u + b]);
            if (detail::dotRounded(n, q) + plane.w < Real(0)) m[b >> 5] |= 1u << (b & 31);
        }
    }
    return m;
}

/// The oracle for lookups on the GPU's inputs: fp64 on the float plane and the setup's samples
/// rounded to float (what PENUMBRA_LUT_SAMPLE hands lookup.glsl). Exact modes are checked against
/// it: exactBehind<float>, penumbraExactBehind and penumbraLutResolve must equal it.
inline LutMask exactBehindOracle(const LightLutSetup& setup, uint32_t table, const glm::vec4& plane) {
    LutMask m{};
    const shared::PenumbraLutParams& p = setup.params;
    const uint32_t block = table % p.tables_per_set;
    const uint32_t count = std::min<uint32_t>(128u, p.samples_per_set - block * 128u);
    for (uint32_t b = 0; b < count; ++b) {
        const glm::vec3 q(setup.samples[size_t(table) * 128u + b]);
        if (detail::light_lut::behindFp64(plane, q)) m[b >> 5] |= 1u << (b & 31);
    }
    return m;
}

/// A certified answer in its three states: certain behind, uncertain, the rest certain in front.
struct LutCertain {
    LutMask behind{};
    LutMask uncertain{};
};

inline LutCertain lutCertain(const LutAnswer& a) {
    LutCertain c;
    for (int w = 0; w < 4; ++w) {
        c.uncertain[w] = a.uncertain[w];
        c.behind[w] = a.centre[w] & ~a.uncertain[w];
    }
    return c;
}

/// AND of the planes of one caster for one view sample (sintorn2008 Fig. 6: the samples blocked are
/// behind every plane): certain behind only if certain behind in all; certain in front if certain
/// in front in any; else uncertain. Twin of penumbraLutCombine.
inline LutCertain lutCombine(const LutCertain& a, const LutCertain& b) {
    LutCertain c;
    for (int w = 0; w < 4; ++w) {
        const uint32_t front_a = ~(a.behind[w] | a.uncertain[w]), front_b = ~(b.behind[w] | b.uncertain[w]);
        c.behind[w] = a.behind[w] & b.behind[w];
        c.uncertain[w] = ~(c.behind[w] | front_a | front_b);
    }
    return c;
}

/// Resolves a certified answer exactly: the certain bits as they are, the uncertain ones tested
/// against `plane`.
template <typename Real>
inline LutMask lutResolve(const LightLutSetup& setup, uint32_t table, const LutCertain& c, const glm::vec<4, Real>& plane) {
    LutMask m = c.behind;
    bool any = false;
    for (uint32_t w : c.uncertain) any |= w != 0;
    if (!any) return m;
    const LutMask exact = exactBehind(setup, table, plane);
    for (int w = 0; w < 4; ++w) m[w] |= exact[w] & c.uncertain[w];
    return m;
}

}  // namespace penumbra

#endif
