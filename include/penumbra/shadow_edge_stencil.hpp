// penumbra — eye-view anti-aliasing for irregular (alias-free) hard shadows (galoppo2010): which
// pixels may be partly lit (the shadow-edge stencil), where their extra view samples go (shadow
// sample splatting) and how per-sample states become fractional occlusion (resolve).
//
// Integration summary (this header is GL-free: pure setup and the CPU path; the per-sample states
// come from the alias-free hard pipeline, penumbra/pipelines/alias_free_hard.hpp, GPU or CPU twin)
//   needs:    the engine's per-pixel view samples (vec4 world position, w == 0: no surface) and face
//             normals, the view (SampleListsView: size and inverse view-projection), the light
//             (SampleListsLight, a view-projection seeing every sub-sample: aaFootprintBounds())
//             and the casters (AfhCasters) — the same inputs the hard pipeline takes.
//   produces: AaFootprints (the pixel's centre sample plus N sub-samples on the pixel's plane:
//             aaSubSampleOffset() patterns, rotated grid by default), a 1-byte-per-pixel stencil
//             (1 = multi-sample this pixel), the extended sample buffer the hard pipeline runs on
//             (aaSampleBuffer: the P centres, w == 0 where edge mode multi-samples the pixel or,
//             AaUnflagged::Proven, where the provable stencil decided it; then N sub-samples per
//             multi-sampled pixel) and the resolve (aaResolve: per pixel the mean of its samples'
//             lit states, or the provable stencil's verdict).
//   stencils: two, measured against each other:
//     - provableEdgeStencilCpu (default): a pixel is left unflagged only when every caster
//       triangle either blocks all of its K = N + 1 points or none of them (then their states,
//       an OR over triangles, all agree) — so `--aa edge` equals `--aa full` bit for bit. Per
//       (footprint, triangle) pair: a bounding-sphere test against the triangle's shadow volume
//       (3 side planes through the light, the triangle's plane; + the reach plane for directional
//       lights) decides most pairs with 4-5 dot products; undecided pairs run the hard pipeline's
//       exact test (afhBlocks<double>) on the K points. A pixel some triangle covers entirely is
//       fully shadowed whatever else splits it (no flag). This is a footprint-level irregular
//       z-buffer pass: it also yields the unflagged pixels' states (lit, shadowed), so edge mode
//       needs no sample of them (AaUnflagged::Proven: the hard pipeline runs on the flagged
//       pixels' sub-samples alone).
//     - chebyshevEdgeStencilCpu (galoppo2010 Listing 1.6.1): a conservative moment map (each light
//       texel holds the minimum caster depth over its area — conservative raster, Fig. 1.6.8 — as
//       E(x), E(x^2), mip-mapped) read at the level the pixel's light-space footprint fits; the
//       pixel stays unflagged when a one-tailed Chebyshev bound says it is fully lit or fully
//       shadowed with probability >= 1 - threshold. A probability, not a proof: its misses are
//       counted against the oracle (the receiver itself lies in the map, so the lit test compares
//       against t_min minus a multiple of its own depth spread; see ChebyshevStencilOptions).
//   sub-samples: each on the plane through the centre sample with the pixel's face normal, where the
//       sub-pixel's eye ray meets it (galoppo2010 "Shadow Sample Splatting"); a grazing plane is
//       limited to kAaMaxStretch fronto-parallel pixel widths from the centre (documented
//       fallback: the centre itself when the ray misses the plane).
//   lights: point (light.w = 1) or directional (w = 0, options.directional_reach > 0), as the
//       hard pipeline; samples' back-facing state uses the sample lists' own test.
#ifndef PENUMBRA_SHADOW_EDGE_STENCIL_HPP
#define PENUMBRA_SHADOW_EDGE_STENCIL_HPP

#include "penumbra/detail/shared.hpp"
#include <penumbra/shadow_edge_stencil/shadow_edge_stencil_shared.h>

#include "penumbra/error.hpp"
#include "penumbra/pipelines/alias_free_hard.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace penumbra {

using AaParams = shared::PenumbraAaParams;
using AaFootprintRecord = shared::PenumbraAaFootprint;
static_assert(sizeof(AaParams) == 960 && offsetof(AaParams, numbers) == 256 && offsetof(AaParams, light_clip) == 288 &&
                  offsetof(AaParams, offsets) == 368 && offsetof(AaParams, view) == 880 && offsetof(AaParams, chebyshev) == 928,
              "PenumbraAaParams: the std140 offsets the shaders assume");
static_assert(sizeof(AaFootprintRecord) == 64, "PenumbraAaFootprint: 64 bytes (std430)");

enum class AaPattern { RotatedGrid, Jittered };
enum class AaMode { Off, Edge, Full };

inline constexpr uint32_t kAaMaxSamples = PENUMBRA_AA_MAX_SAMPLES;
/// Loop iterations one light-pass fragment may spend (llvmpipe stops an invocation's loops after
/// 65 535): a texel's list is walked only when list length x (N + 2) stays below it.
inline constexpr uint32_t kAaLoopBudget = 65000;
inline constexpr double kAaMaxStretch = 8.0;
inline constexpr double kAaBoxSlack = 1.0 / 64.0;  ///< texels added around a footprint's light-space box (setup.comp.glsl)  ///< sub-sample distance limit, in fronto-parallel pixel widths

/// Value-initialised = rotated grid 4x.
struct AaPatternOptions {
    uint32_t samples = 4;  ///< N sub-samples per flagged pixel, in [1, kAaMaxSamples]
    AaPattern pattern = AaPattern::RotatedGrid;
    uint32_t seed = 0;     ///< jittered: the hash seed (one pattern per pixel)
};

inline void checkAaPatternOptions(const AaPatternOptions& o) {
    PENUMBRA_CHECK(o.samples >= 1 && o.samples <= kAaMaxSamples, "penumbra::AaPatternOptions: samples = ", o.samples,
                   " is outside [1, ", kAaMaxSamples, "]");
}

namespace detail {
/// N = a x b with a the largest divisor <= sqrt(N): the pattern's strata.
inline std::pair<uint32_t, uint32_t> aaStrata(uint32_t n) {
    uint32_t a = 1;
    for (uint32_t d = 1; d * d <= n; ++d)
        if (n % d == 0) a = d;
    return {a, n / a};
}
inline uint32_t aaHash(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}
}  // namespace detail

/// Offset of sub-sample k of pixel `pixel` from the pixel centre, in pixels, inside (-0.5, 0.5)^2.
/// Rotated grid: the a x b grid of the strata rotated into N-rooks positions (every column and
/// every row of the N x N sub-grid holds one sample; 4x is the classic RGSS pattern
/// (+-1/8, +-3/8)). Jittered: one uniformly jittered point per a x b stratum, per pixel. Offsets
/// are dyadic for the rotated grid (exact in float).
inline glm::vec2 aaSubSampleOffset(const AaPatternOptions& o, uint32_t pixel, uint32_t k) {
    const auto [a, b] = detail::aaStrata(o.samples);
    const uint32_t i = k / b, j = k % b;  // i in [0, a), j in [0, b)
    const float n = float(o.samples);
    if (o.pattern == AaPattern::RotatedGrid) {
        const uint32_t x = i * b + j, y = j * a + (a - 1 - i);
        return {(float(x) + 0.5f) / n - 0.5f, (float(y) + 0.5f) / n - 0.5f};
    }
    const uint32_t h = detail::aaHash(pixel * 0x9e3779b9u ^ detail::aaHash(k + 0x632be5abu * (o.seed + 1u)));
    const float jx = float(h & 0xffffu) / 65536.0f, jy = float(h >> 16) / 65536.0f;
    return {(float(j) + jx) / float(b) - 0.5f, (float(i) + jy) / float(a) - 0.5f};
}

/// One pixel's centre sample and its N sub-samples, all pixels of a view.
struct AaFootprints {
    uint32_t pixels = 0, samples = 0;       ///< P pixels, N sub-samples each
    std::vector<glm::vec4> centres;         ///< [P] the engine's view samples (w == 0: none)
    std::vector<glm::vec4> normals;         ///< [P] face normals (xyz)
    std::vector<glm::vec4> sub_samples;     ///< [P * N] sub-sample k of pixel i at i * N + k (w == 0 with no centre)
    uint64_t stretched = 0;                 ///< sub-samples limited to kAaMaxStretch pixel widths (grazing planes)
    uint64_t fallbacks = 0;                 ///< sub-samples whose ray missed the plane: the centre itself
    const glm::vec4* subSamples(uint32_t pixel) const { return sub_samples.data() + size_t(pixel) * samples; }
};

namespace detail {
// Double arithmetic in a fixed order with opaque products (no FMA contraction), mirrored step for
// step by shadow_edge_stencil.glsl (`precise`): the GPU's footprints and decisions match these bits
// wherever fp64 +, -, *, / and sqrt are correctly rounded (llvmpipe; most GPUs for + - *).
inline double aaDot(const glm::dvec3& a, const glm::dvec3& b) {
    return (mulRounded(a.x, b.x) + mulRounded(a.y, b.y)) + mulRounded(a.z, b.z);
}
inline double aaLength(const glm::dvec3& v) { return std::sqrt(aaDot(v, v)); }
inline glm::dvec3 aaCross(const glm::dvec3& a, const glm::dvec3& b) {
    return {mulRounded(a.y, b.z) - mulRounded(a.z, b.y), mulRounded(a.z, b.x) - mulRounded(a.x, b.z),
            mulRounded(a.x, b.y) - mulRounded(a.y, b.x)};
}
inline glm::dvec3 aaAxpy(const glm::dvec3& o, double t, const glm::dvec3& d) {  // o + t d
    return {o.x + mulRounded(t, d.x), o.y + mulRounded(t, d.y), o.z + mulRounded(t, d.z)};
}
/// m * v as GLM groups it: (m0 x + m1 y) + (m2 z + m3 w).
inline glm::dvec4 aaTransform(const glm::dmat4& m, const glm::dvec4& v) {
    glm::dvec4 r;
    for (int c = 0; c < 4; ++c)
        r[c] = (mulRounded(m[0][c], v.x) + mulRounded(m[1][c], v.y)) + (mulRounded(m[2][c], v.z) + mulRounded(m[3][c], v.w));
    return r;
}
inline glm::dvec3 aaUnproject(const glm::dmat4& inverse, double x, double y, double z) {
    const glm::dvec4 h = aaTransform(inverse, glm::dvec4(x, y, z, 1.0));
    return {h.x / h.w, h.y / h.w, h.z / h.w};
}
/// Pixel coordinate -> NDC: (p / size) * 2 - 1.
inline double aaNdc(double p, uint32_t size) { return mulRounded(p / double(size), 2.0) - 1.0; }
/// Light clip -> grid coordinate: ((x / w) * 0.5 + 0.5) * size.
inline double aaGrid(double x, double w, uint32_t size) { return mulRounded(mulRounded(x / w, 0.5) + 0.5, double(size)); }

/// The sub-sample of the pixel (x, y) with centre c and plane normal n at offset `off`.
inline glm::vec4 aaSubSample(const glm::dmat4& inverse, double z_near, uint32_t width, uint32_t height, uint32_t x,
                             uint32_t y, const glm::dvec3& c, const glm::dvec3& n, const glm::vec2& off, double s0,
                             bool& stretched, bool& fallback) {
    const double px = (double(x) + 0.5) + double(off.x), py = (double(y) + 0.5) + double(off.y);
    const double nx = aaNdc(px, width), ny = aaNdc(py, height);
    const glm::dvec3 o = aaUnproject(inverse, nx, ny, z_near);
    const glm::dvec3 d = aaUnproject(inverse, nx, ny, 1.0) - o;
    const double dn = aaDot(n, d);
    const double t = aaDot(n, c - o) / dn;
    stretched = fallback = false;
    glm::dvec3 q = c;
    if (dn != 0.0 && std::isfinite(t) && t > 0.0) {
        q = aaAxpy(o, t, d);
        // Grazing planes: at most kAaMaxStretch fronto-parallel pixel widths away.
        const double fronto = aaLength(aaAxpy(o, s0, d) - c);
        const double reach = mulRounded(kAaMaxStretch, fronto);
        const double dist = aaLength(q - c);
        if (dist > reach && dist > 0.0) {
            q = aaAxpy(c, reach / dist, q - c);
            stretched = true;
        }
    } else {
        fallback = true;
    }
    return glm::vec4(float(q.x), float(q.y), float(q.z), 1.0f);
}

/// The centre's parameter on its own pixel-centre ray (for the fronto-parallel pixel width).
inline double aaCentreParameter(const glm::dmat4& inverse, double z_near, uint32_t width, uint32_t height, uint32_t x,
                                uint32_t y, const glm::dvec3& c) {
    const double nx = aaNdc(double(x) + 0.5, width), ny = aaNdc(double(y) + 0.5, height);
    const glm::dvec3 o = aaUnproject(inverse, nx, ny, z_near);
    const glm::dvec3 d = aaUnproject(inverse, nx, ny, 1.0) - o;
    return aaDot(c - o, d) / aaDot(d, d);
}
}  // namespace detail

/// Sub-samples on each pixel's plane (see the header comment). centres/normals: view.width *
/// view.height entries, row-major from the bottom row (GL's order); normals need not be unit.
/// Throws penumbra::Error for an empty view or a non-finite inverse view-projection.
inline AaFootprints aaFootprintsCpu(const SampleListsView& view, const glm::vec4* centres, const glm::vec4* normals,
                                    const AaPatternOptions& pattern) {
    checkAaPatternOptions(pattern);
    PENUMBRA_CHECK(view.width > 0 && view.height > 0, "penumbra::aaFootprintsCpu: empty view ", view.width, "x", view.height);
    PENUMBRA_CHECK(centres && normals, "penumbra::aaFootprintsCpu: centres and normals must not be null");
    for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r)
            PENUMBRA_CHECK(std::isfinite(view.inverse_view_projection[c][r]),
                           "penumbra::aaFootprintsCpu: the inverse view-projection is not finite");
    AaFootprints f;
    f.pixels = view.width * view.height;
    f.samples = pattern.samples;
    f.centres.assign(centres, centres + f.pixels);
    f.normals.assign(normals, normals + f.pixels);
    f.sub_samples.assign(size_t(f.pixels) * f.samples, glm::vec4(0.0f));
    const glm::dmat4 inverse(view.inverse_view_projection);
    const double z_near = view.depth_zero_to_one ? 0.0 : -1.0;
    for (uint32_t y = 0; y < view.height; ++y) {
        for (uint32_t x = 0; x < view.width; ++x) {
            const uint32_t i = y * view.width + x;
            if (centres[i].w == 0.0f) continue;
            const glm::dvec3 c(glm::vec3(centres[i])), n(glm::vec3(normals[i]));
            const double s0 = detail::aaCentreParameter(inverse, z_near, view.width, view.height, x, y, c);
            for (uint32_t k = 0; k < f.samples; ++k) {
                bool stretched = false, fallback = false;
                f.sub_samples[size_t(i) * f.samples + k] =
                    detail::aaSubSample(inverse, z_near, view.width, view.height, x, y, c, n,
                                        aaSubSampleOffset(pattern, i, k), s0, stretched, fallback);
                f.stretched += stretched;
                f.fallbacks += fallback;
            }
        }
    }
    return f;
}

/// The box of every centre and sub-sample (pass it to lightViewProjectionForBounds: the light
/// must see the sub-samples too). `count` = surface pixels.
inline std::pair<glm::vec3, glm::vec3> aaFootprintBounds(const AaFootprints& f, size_t* count = nullptr) {
    auto [lo, hi] = viewSampleBounds(f.centres.data(), f.centres.size(), count);
    size_t subs = 0;
    auto [slo, shi] = viewSampleBounds(f.sub_samples.data(), f.sub_samples.size(), &subs);
    if (subs > 0) {
        lo = glm::min(lo, slo);
        hi = glm::max(hi, shi);
    }
    return {lo, hi};
}

/// Pixels whose sub-samples the edge layout holds: the budget, at most P (kAaAllPixels: every pixel).
inline constexpr uint32_t kAaAllPixels = 0xffffffffu;

/// Samples of the extended sample buffer for `mode` and `budget`: P (Off), P (1 + N) (Full),
/// P + min(budget, P) N (Edge).
inline uint64_t aaSampleCount(AaMode mode, uint32_t pixels, uint32_t samples, uint32_t budget = kAaAllPixels) {
    if (mode == AaMode::Off) return pixels;
    const uint64_t held = mode == AaMode::Full ? pixels : std::min(budget, pixels);
    return uint64_t(pixels) + held * samples;
}

/// Edge mode's unflagged pixels: their centre sample decides each (any stencil), or the provable
/// stencil's verdict does (ProvableStencilCpu::lit / PENUMBRA_AA_LIT, else dark) and they are no
/// sample at all: the hard pipeline then runs on the flagged pixels' sub-samples alone.
enum class AaUnflagged { Sampled, Proven };

/// The extended sample buffer: [0, P) the centres, then N sub-samples per multi-sampled pixel.
/// Full (`flags` null): pixel i's at P + i N + k. Edge (`flags`): packed, the flagged pixel of
/// rank r (flagged pixels before it, in pixel order) at P + r N + k while r < budget, and its
/// centre slot has w == 0 (aaResolve reads only its sub-samples, so the hard pipeline skips the
/// centre); a flagged pixel past the budget keeps its centre alone (aaBudgetOverflow counts
/// them), and the slots of ranks in [flagged count, budget) have w == 0 (the lists skip them).
/// AaUnflagged::Proven (edge only) also gives the unflagged pixels' centre slots w == 0. Full
/// keeps every centre (the K = N + 1 points the provable stencil reasons about, for tests and
/// --reference). aaSampleCount entries. Normals: each sample carries its pixel's (zero where
/// w == 0).
inline void aaSampleBuffer(const AaFootprints& f, const uint8_t* flags, std::vector<glm::vec4>& positions,
                           std::vector<glm::vec4>& normals, uint32_t budget = kAaAllPixels,
                           AaUnflagged unflagged = AaUnflagged::Sampled) {
    const size_t p = f.pixels, n = f.samples;
    const size_t count = aaSampleCount(flags ? AaMode::Edge : AaMode::Full, f.pixels, f.samples, budget);
    const bool proven = flags && unflagged == AaUnflagged::Proven;
    positions.assign(count, glm::vec4(0.0f));
    normals.assign(count, glm::vec4(0.0f));
    size_t rank = 0;
    for (size_t i = 0; i < p; ++i) {
        if (flags && !flags[i]) {
            if (!proven) {
                positions[i] = f.centres[i];
                normals[i] = f.normals[i];
            }
            continue;
        }
        const size_t slot = flags ? rank++ : i;
        const bool held = p + slot * n < count;
        if (!flags || !held) {  // Full, or past the budget: the centre is a sample
            positions[i] = f.centres[i];
            normals[i] = f.normals[i];
        }
        if (!held) continue;
        for (size_t k = 0; k < n; ++k) {
            positions[p + slot * n + k] = f.sub_samples[i * n + k];
            normals[p + slot * n + k] = f.normals[i];
        }
    }
}

/// Flagged pixels the edge layout of `budget` leaves single-sampled (0 when it holds them all).
inline uint32_t aaBudgetOverflow(const uint8_t* flags, uint32_t pixels, uint32_t budget) {
    uint32_t flagged = 0;
    for (uint32_t i = 0; i < pixels; ++i) flagged += flags[i] != 0;
    return flagged > budget ? flagged - budget : 0;
}

/// Per pixel: the fraction of its samples the hard pipeline found lit (PENUMBRA_AFH_LIT), from
/// states of aaSampleBuffer's layout (the same budget). Off: the centre's state; Full: the mean of
/// the N sub-samples; Edge: the mean where the pixel is flagged and within the budget, else the
/// centre's state — or, given `proven_lit` (ProvableStencilCpu::lit, the layout of
/// AaUnflagged::Proven), an unflagged pixel's verdict: 1 where lit, else 0 (shadowed, all
/// back-facing or no surface, as its samples would say). N a power of two makes the means exact,
/// so Edge and Full agree bit for bit wherever their sample states agree.
inline std::vector<float> aaResolve(AaMode mode, const std::vector<uint32_t>& states, uint32_t pixels, uint32_t samples,
                                    const uint8_t* flags = nullptr, uint32_t budget = kAaAllPixels,
                                    const uint8_t* proven_lit = nullptr) {
    PENUMBRA_CHECK(states.size() >= aaSampleCount(mode, pixels, samples, budget), "penumbra::aaResolve: ", states.size(),
                   " states for ", pixels, " pixels x ", samples, " samples");
    PENUMBRA_CHECK(mode != AaMode::Edge || flags, "penumbra::aaResolve: edge mode needs the stencil");
    std::vector<float> lit(pixels);
    uint32_t rank = 0;
    for (uint32_t i = 0; i < pixels; ++i) {
        if (mode == AaMode::Edge && proven_lit && !flags[i]) {
            lit[i] = proven_lit[i] ? 1.0f : 0.0f;
            continue;
        }
        const bool multi = mode == AaMode::Full || (mode == AaMode::Edge && flags[i] && rank++ < budget);
        if (!multi) {
            lit[i] = states[i] == PENUMBRA_AFH_LIT ? 1.0f : 0.0f;
            continue;
        }
        const size_t slot = mode == AaMode::Full ? i : rank - 1;
        uint32_t count = 0;
        for (uint32_t k = 0; k < samples; ++k) count += states[pixels + slot * samples + k] == PENUMBRA_AFH_LIT;
        lit[i] = float(count) / float(samples);
    }
    return lit;
}

// ---------------------------------------------------------------------------------------------
// The provable stencil

/// Value-initialised = defaults.
struct ProvableStencilOptions {
    bool cull_back_facing = true;         ///< the sample lists' rule (AliasFreeHard's lists cull them)
    uint32_t max_footprint_texels = 1024; ///< a footprint whose light-texel box is larger is flagged (grazing views)
    /// A light texel holding more footprints than this flags them all instead of classifying them
    /// (0 = kAaLoopBudget / (N + 2), what one fragment can walk on llvmpipe).
    uint32_t max_list = 0;
    uint32_t maxList(uint32_t samples) const { return max_list ? max_list : kAaLoopBudget / (samples + 2); }
};

/// What the provable stencil found (per pixel flags plus work counters).
struct ProvableStencilCpu {
    std::vector<uint8_t> flags;     ///< 1 = multi-sample (some triangle splits the footprint, none covers it)
    std::vector<uint8_t> shadowed;  ///< unflagged pixels: 1 = every point shadowed (a cover or all back-facing)
    std::vector<uint8_t> lit;       ///< unflagged pixels: 1 = every point lit (classified; no triangle blocks any point)
    uint64_t pairs = 0;             ///< (footprint, triangle) pairs classified
    uint64_t sphere_decided = 0;    ///< ... decided by the bounding-sphere test alone
    uint64_t exact_tests = 0;       ///< exact point tests of the undecided pairs
    uint64_t outside = 0;           ///< footprints with a point outside the light frustum (flagged)
    uint64_t mixed_facing = 0;      ///< footprints whose points disagree on facing the light (flagged)
    uint64_t over_limits = 0;       ///< footprints flagged for a box over max_footprint_texels or an over-long list
    /// The GPU's stencil word per pixel (PENUMBRA_AA_FLAG | PENUMBRA_AA_SHADOWED | PENUMBRA_AA_LIT).
    std::vector<uint32_t> words() const {
        std::vector<uint32_t> w(flags.size());
        for (size_t i = 0; i < w.size(); ++i)
            w[i] = (flags[i] ? PENUMBRA_AA_FLAG : 0u) | (shadowed[i] ? PENUMBRA_AA_SHADOWED : 0u) | (lit[i] ? PENUMBRA_AA_LIT : 0u);
        return w;
    }
};

namespace detail {
/// The sample lists' back-facing test (classifySample), step for step.
inline bool aaBackFacing(const glm::vec4& light, const glm::vec4& p, const glm::vec3& normal) {
    const float lx = light.w == 0.0f ? light.x : light.x - p.x;
    const float ly = light.w == 0.0f ? light.y : light.y - p.y;
    const float lz = light.w == 0.0f ? light.z : light.z - p.z;
    float facing = mulRounded(normal.x, lx) + mulRounded(normal.y, ly);
    facing = facing + mulRounded(normal.z, lz);
    return !(facing > 0.0f);
}

/// A triangle's shadow volume as up to 5 unit-normal planes (positive inside): the 3 side planes
/// through the light (or along the light direction), the triangle's plane (positive beyond it),
/// and for a directional light the reach plane. valid = false: no shortcut (edge-on triangle,
/// light near its plane); the exact test decides every point.
struct AaShadowVolume {
    glm::dvec4 planes[5];
    int count = 0;
    bool valid = false;
    bool blocks_nothing = false;  ///< the light lies exactly in the triangle's plane: afhBlocks is false everywhere
};

inline AaShadowVolume aaShadowVolume(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::vec4& light,
                                     double reach) {
    AaShadowVolume v;
    const bool point = light.w != 0.0f;
    const glm::dvec3 l{glm::vec3(light)};
    const glm::dvec3 nt = aaCross(b - a, c - a);
    const double nt_len = aaLength(nt);
    if (!(nt_len > 0.0)) return v;
    const glm::dvec3 u = nt / nt_len;
    const glm::dvec3 corners[3] = {a, b, c};
    for (int e = 0; e < 3; ++e) {
        const glm::dvec3& p0 = corners[e];
        const glm::dvec3& p1 = corners[(e + 1) % 3];
        const glm::dvec3& opposite = corners[(e + 2) % 3];
        const glm::dvec3 m = point ? aaCross(p0 - l, p1 - l) : aaCross(p1 - p0, l);
        const double len = aaLength(m);
        if (!(len > 0.0)) return v;
        glm::dvec3 mu = m / len;
        const double side = aaDot(mu, opposite - p0);
        if (side == 0.0) return v;  // edge-on from the light
        if (side < 0.0) mu = -mu;
        v.planes[e] = glm::dvec4(mu, -aaDot(mu, p0));
    }
    if (point) {
        const double dl = aaDot(u, l - a);
        if (dl == 0.0) {
            v.blocks_nothing = true;
            return v;
        }
        const glm::dvec3 beyond = dl > 0.0 ? -u : u;
        v.planes[3] = glm::dvec4(beyond, -aaDot(beyond, a));
        v.count = 4;
    } else {
        const double dd = aaDot(u, l);
        if (dd == 0.0) {
            v.blocks_nothing = true;
            return v;
        }
        const glm::dvec3 beyond = dd > 0.0 ? -u : u;  // behind the triangle seen along the light
        v.planes[3] = glm::dvec4(beyond, -aaDot(beyond, a));
        // Within reach: distance beyond the plane < reach * |u . d|.
        v.planes[4] = glm::dvec4(-beyond, aaDot(beyond, a) + mulRounded(reach, std::abs(dd)));
        v.count = 5;
    }
    v.valid = true;
    return v;
}

inline double aaPlaneDistance(const glm::dvec4& plane, const glm::dvec3& p) { return aaDot(glm::dvec3(plane), p) + plane.w; }

/// The sphere test's margin: the exact test's coplanar tolerance (eps times its scale, which
/// these distances bound, uncapped: it also bounds the scale capped at scene_extent) doubled, plus
/// 1e-9 of the scale for rounding (planes through the light round with its distance).
inline double aaSphereMargin(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& q, double r,
                             const glm::vec4& light, double reach, double eps) {
    const double tri = std::max(aaLength(b - a), std::max(aaLength(c - a), aaLength(c - b)));
    const double to_light = light.w != 0.0f ? aaLength(glm::dvec3(glm::vec3(light)) - q)
                                            : mulRounded(reach, aaLength(glm::dvec3(glm::vec3(light))));
    const double scale = ((aaLength(a - q) + tri) + r) + to_light;
    return r + mulRounded(mulRounded(2.0, eps) + 1e-9, scale);
}

/// One (footprint, triangle) pair by the sphere (centre q, radius r) alone: -1 outside (blocks
/// none), 1 inside (blocks all), 0 undecided (run the exact test on every point).
inline int aaSphereClass(const AaShadowVolume& volume, const glm::dvec3& q, double margin, const glm::vec4& light) {
    if (!volume.valid) return 0;
    bool all_inside = true;
    for (int k = 0; k < volume.count; ++k) {
        const double d = aaPlaneDistance(volume.planes[k], q);
        if (d < -margin) return -1;
        if (!(d > margin)) all_inside = false;
    }
    // A point light within the margin of the triangle's plane: the exact test's endpoint rule may
    // apply; leave it to the exact test.
    if (all_inside && light.w != 0.0f && std::abs(aaPlaneDistance(volume.planes[3], glm::dvec3(glm::vec3(light)))) <= margin)
        return 0;
    return all_inside ? 1 : 0;
}
}  // namespace detail

/// The provable shadow-edge stencil (see the header comment). `options` gives the exact test's
/// coplanar epsilon, the directional reach and the caster culling (light_facing_only /
/// back_faces_only) of the hard pipeline whose states it must reproduce; `light.view_projection`
/// must see every centre and sub-sample (aaFootprintBounds); the binning grid is
/// options.grid_width x grid_height. Sample offsets (options.sample_offset) are not supported
/// (exact geometry only).
inline ProvableStencilCpu provableEdgeStencilCpu(const AliasFreeHardOptions& options, const SampleListsLight& light,
                                                 const AaFootprints& f, const AfhCasters& casters,
                                                 const ProvableStencilOptions& so = {}) {
    validateAliasFreeHardOptions(options, light.light);
    PENUMBRA_CHECK(options.precision == AfhPrecision::Exact && options.sample_offset == 0.0f,
                   "penumbra::provableEdgeStencilCpu: needs the exact hard pipeline (precision Exact, sample_offset 0)");
    PENUMBRA_CHECK(casters.positions && casters.indices && casters.closed &&
                       casters.closed->size() * 3 == casters.indices->size(),
                   "penumbra::provableEdgeStencilCpu: casters need positions, indices and one closed flag per triangle");
    PENUMBRA_CHECK(f.centres.size() == f.pixels && f.sub_samples.size() == size_t(f.pixels) * f.samples,
                   "penumbra::provableEdgeStencilCpu: inconsistent footprints");
    ProvableStencilCpu out;
    out.flags.assign(f.pixels, 0);
    out.shadowed.assign(f.pixels, 0);
    out.lit.assign(f.pixels, 0);
    const uint32_t gw = options.grid_width, gh = options.grid_height;
    const uint32_t k_points = f.samples + 1;
    const bool point = light.light.w != 0.0f;
    const double reach = options.directional_reach;
    const double eps = options.coplanar_epsilon;

    const glm::dmat4 vp(light.view_projection);
    // Bin each footprint into every light texel its points' box touches.
    std::vector<std::vector<uint32_t>> bins(size_t(gw) * gh);
    std::vector<glm::dvec3> centre(f.pixels);
    std::vector<double> radius(f.pixels, 0.0);
    std::vector<uint8_t> active(f.pixels, 0);  // 1: classify against the casters
    std::vector<uint8_t> split(f.pixels, 0), covered(f.pixels, 0);
    for (uint32_t i = 0; i < f.pixels; ++i) {
        if (f.centres[i].w == 0.0f) continue;
        const glm::vec3 n(f.normals[i]);
        const glm::vec4* subs = f.subSamples(i);
        // Facing: the lists reject light-back-facing samples (state BACK_FACING, not lit).
        if (so.cull_back_facing) {
            uint32_t back = detail::aaBackFacing(light.light, f.centres[i], n);
            for (uint32_t k = 0; k < f.samples; ++k) back += detail::aaBackFacing(light.light, subs[k], n);
            if (back == k_points) {
                out.shadowed[i] = 1;
                continue;
            }
            if (back != 0) {
                out.flags[i] = 1;
                ++out.mixed_facing;
                continue;
            }
        }
        glm::dvec2 lo(1e300), hi(-1e300);
        bool inside = true;
        centre[i] = glm::dvec3(glm::vec3(f.centres[i]));
        for (uint32_t k = 0; k < k_points; ++k) {
            const glm::dvec3 p(glm::vec3(k == 0 ? f.centres[i] : subs[k - 1]));
            radius[i] = std::max(radius[i], detail::aaLength(p - centre[i]));
            const glm::dvec4 clip = detail::aaTransform(vp, glm::dvec4(p, 1.0));
            if (!(clip.w > 0.0)) {
                inside = false;
                break;
            }
            const glm::dvec2 g(detail::aaGrid(clip.x, clip.w, gw), detail::aaGrid(clip.y, clip.w, gh));
            if (!(g.x >= 0.0 && g.x <= gw && g.y >= 0.0 && g.y <= gh)) {
                inside = false;
                break;
            }
            lo = glm::min(lo, g);
            hi = glm::max(hi, g);
        }
        if (!inside) {
            out.flags[i] = 1;
            ++out.outside;
            continue;
        }
        // kAaBoxSlack texels of slack on every side: the casters' hulls come from float clip
        // coordinates (~1e-4 texel from the exact projection even at 4096^2).
        const int x0 = std::max(0, int(std::floor(lo.x - kAaBoxSlack))), y0 = std::max(0, int(std::floor(lo.y - kAaBoxSlack)));
        const int x1 = std::min(int(gw) - 1, int(std::floor(hi.x + kAaBoxSlack)));
        const int y1 = std::min(int(gh) - 1, int(std::floor(hi.y + kAaBoxSlack)));
        if (uint64_t(x1 - x0 + 1) * uint64_t(y1 - y0 + 1) > so.max_footprint_texels) {
            out.flags[i] = 1;
            ++out.over_limits;
            continue;
        }
        active[i] = 1;
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) bins[size_t(y) * gw + x].push_back(i);
    }

    // Over-long lists: their footprints are flagged, not classified (the GPU fragment's loop budget).
    const uint32_t max_list = so.maxList(f.samples);
    for (const std::vector<uint32_t>& bin : bins) {
        if (bin.size() <= max_list) continue;
        for (const uint32_t i : bin) {
            if (!out.flags[i]) ++out.over_limits;
            out.flags[i] = 1;
            active[i] = 0;
        }
    }
    const ConservativeRasterSetup cr = afhConservativeSetup(options);
    const auto& P = *casters.positions;
    const auto& I = *casters.indices;
    std::vector<uint32_t> stamp(f.pixels, std::numeric_limits<uint32_t>::max());
    std::vector<uint8_t> blocked(k_points);
    for (size_t t = 0; t < casters.closed->size(); ++t) {
        const glm::vec3 v[3] = {P[I[3 * t]], P[I[3 * t + 1]], P[I[3 * t + 2]]};
        const glm::dvec3 a(v[0]), b(v[1]), c(v[2]);
        if (detail::degenerateTriangle(a, b, c)) continue;
        if (detail::afhCulled(options, (*casters.closed)[t] != 0, v, light.light)) continue;
        const glm::vec4 clip[3] = {light.view_projection * glm::vec4(v[0], 1.0f), light.view_projection * glm::vec4(v[1], 1.0f),
                                   light.view_projection * glm::vec4(v[2], 1.0f)};
        const std::vector<glm::dvec2> polygon = conservativeReferencePolygon(clip[0], clip[1], clip[2], cr);
        if (polygon.empty()) continue;
        glm::dvec2 lo(1e300), hi(-1e300);
        for (const auto& q : polygon) {
            lo = glm::min(lo, q);
            hi = glm::max(hi, q);
        }
        const int x0 = std::max(0, int(std::floor(lo.x)) - 1), y0 = std::max(0, int(std::floor(lo.y)) - 1);
        const int x1 = std::min(int(gw) - 1, int(std::floor(hi.x)) + 1), y1 = std::min(int(gh) - 1, int(std::floor(hi.y)) + 1);
        if (x0 > x1 || y0 > y1) continue;
        const detail::AaShadowVolume volume = detail::aaShadowVolume(a, b, c, light.light, reach);
        if (volume.blocks_nothing) continue;
        for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) {
                for (const uint32_t i : bins[size_t(y) * gw + x]) {
                    if (stamp[i] == uint32_t(t) || covered[i] || !active[i]) continue;
                    stamp[i] = uint32_t(t);
                    ++out.pairs;
                    const double margin = detail::aaSphereMargin(a, b, c, centre[i], radius[i], light.light, reach, eps);
                    const int sphere = detail::aaSphereClass(volume, centre[i], margin, light.light);
                    if (sphere != 0) {
                        ++out.sphere_decided;
                        if (sphere > 0) covered[i] = 1;
                        continue;
                    }
                    uint32_t count = 0;
                    const glm::vec4* subs = f.subSamples(i);
                    for (uint32_t k = 0; k < k_points; ++k) {
                        const glm::dvec3 p(glm::vec3(k == 0 ? f.centres[i] : subs[k - 1]));
                        const glm::dvec3 l = point ? glm::dvec3(light.light) : p + detail::mulRounded(glm::dvec3(light.light), reach);
                        blocked[k] = afhBlocks<double>(a, b, c, p, l, eps, 0.0, options.scene_extent) ? 1 : 0;
                        count += blocked[k];
                    }
                    out.exact_tests += k_points;
                    if (count == k_points) covered[i] = 1;
                    else if (count != 0) split[i] = 1;
                }
            }
        }
    }
    for (uint32_t i = 0; i < f.pixels; ++i) {
        if (!active[i]) continue;
        if (covered[i]) out.shadowed[i] = 1;
        else if (split[i]) out.flags[i] = 1;
        else out.lit[i] = 1;
    }
    return out;
}

// ---------------------------------------------------------------------------------------------
// The Chebyshev (variance shadow map) stencil

/// Conservative moment map: level 0 holds, per light texel, (d, d^2) of the minimum caster depth
/// over the texel's area (every texel a caster overlaps by more than 2^-10 texel: conservative
/// raster up to that sliver, detail::aaDepthTexel; the GPU builds the same bits), d = -1/w for a
/// perspective light (affine in screen space on a plane, increasing with distance), z_ndc for an
/// orthographic one; texels no caster touches hold d_far (beyond every sample). Levels average
/// 2x2 (odd sizes: the last row/column repeats), down to 1x1.
struct MomentMapCpu {
    uint32_t width = 0, height = 0;
    bool perspective = true;
    float d_far = 0.0f;
    std::vector<std::vector<glm::vec2>> levels;
    /// Inner coverage (the "underestimate" the shadowed claim can rest on): per texel the least,
    /// over caster triangles whose projection contains the whole texel, of the triangle's largest
    /// depth over it (+inf: no such triangle); coarser levels take the largest of their 2x2.
    std::vector<std::vector<float>> cover;
    uint32_t levelWidth(uint32_t l) const { return std::max(1u, width >> l); }
    uint32_t levelHeight(uint32_t l) const { return std::max(1u, height >> l); }
};

namespace detail {
inline double aaLightDepth(const glm::dvec4& clip, bool perspective) { return perspective ? -1.0 / clip.w : clip.z / clip.w; }

/// A caster triangle in the moment map's texel space (moments.geom.glsl computes the same): the
/// triangle clipped to w >= 1e-4 w_max (a caster reaching behind the light keeps the exact depths
/// of its part in front), at most 4 vertices (x, y, d); the depth plane d = g0 + ga x + gb y
/// (affine on a plane: d = -1/w, or z_ndc for an orthographic light) fitted on the widest fan
/// triangle; the clipped vertices' depth range; the winding.
struct AaDepthTriangle {
    glm::dvec3 s[4];
    int count = 0;
    double ga = 0, gb = 0, g0 = 0, dmin = 0, dmax = 0, orientation = 1;
    glm::dvec2 lo{0.0}, hi{0.0};
};

inline bool aaDepthTriangle(const glm::dmat4& vp, const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2,
                            uint32_t width, uint32_t height, bool perspective, AaDepthTriangle& t) {
    const glm::dvec4 h[3] = {aaTransform(vp, glm::dvec4(p0, 1.0)), aaTransform(vp, glm::dvec4(p1, 1.0)),
                             aaTransform(vp, glm::dvec4(p2, 1.0))};
    const double w_max = std::max(h[0].w, std::max(h[1].w, h[2].w));
    if (!(w_max > 0.0)) return false;
    const double w_min = perspective ? mulRounded(1e-4, w_max) : -1e300;
    t.count = 0;
    for (int k = 0; k < 3; ++k) {
        const glm::dvec4& a = h[k];
        const glm::dvec4& b = h[(k + 1) % 3];
        const auto emit = [&](const glm::dvec4& c) {
            t.s[t.count++] = glm::dvec3(aaGrid(c.x, c.w, width), aaGrid(c.y, c.w, height), aaLightDepth(c, perspective));
        };
        if (a.w >= w_min) emit(a);
        if ((a.w >= w_min) != (b.w >= w_min)) {
            const double f = (w_min - a.w) / (b.w - a.w);
            emit(glm::dvec4(a.x + mulRounded(b.x - a.x, f), a.y + mulRounded(b.y - a.y, f), a.z + mulRounded(b.z - a.z, f),
                            a.w + mulRounded(b.w - a.w, f)));
        }
    }
    if (t.count < 3) return false;
    t.dmin = std::numeric_limits<double>::infinity();
    t.dmax = -t.dmin;
    t.lo = glm::dvec2(1e300);
    t.hi = glm::dvec2(-1e300);
    double area = 0.0;
    for (int j = 0; j < t.count; ++j) {
        const glm::dvec3& q = t.s[(j + 1) % t.count];
        t.dmin = std::min(t.dmin, t.s[j].z);
        t.dmax = std::max(t.dmax, t.s[j].z);
        t.lo = glm::min(t.lo, glm::dvec2(t.s[j]));
        t.hi = glm::max(t.hi, glm::dvec2(t.s[j]));
        area = area + (mulRounded(t.s[j].x, q.y) - mulRounded(q.x, t.s[j].y));
    }
    t.orientation = area > 0.0 ? 1.0 : -1.0;
    double best = 0.0;
    t.ga = t.gb = 0.0;
    t.g0 = t.dmin;  // edge-on from the light: the vertices' minimum
    for (int j = 1; j + 1 < t.count; ++j) {
        const glm::dvec3 e1 = t.s[j] - t.s[0], e2 = t.s[j + 1] - t.s[0];
        const double det = mulRounded(e1.x, e2.y) - mulRounded(e1.y, e2.x);
        if (std::abs(det) > best) {
            best = std::abs(det);
            t.ga = (mulRounded(e1.z, e2.y) - mulRounded(e2.z, e1.y)) / det;
            t.gb = (mulRounded(e2.z, e1.x) - mulRounded(e1.z, e2.x)) / det;
            t.g0 = (t.s[0].z - mulRounded(t.ga, t.s[0].x)) - mulRounded(t.gb, t.s[0].y);
        }
    }
    return true;
}

/// Whether the clipped triangle overlaps texel (x, y) by more than 2^-10 texel along every
/// separating axis (a contact thinner than that is left out: the GPU's hull comes from float
/// coordinates), and if so the triangle's least depth over the texel (the plane's corner minimum,
/// no lower than its nearest vertex, minus a relative 1e-6) and its cover value (the largest depth
/// over the texel when all four corners are strictly inside the triangle, else +inf).
inline bool aaDepthTexel(const AaDepthTriangle& t, int x, int y, double& d, double& c) {
    constexpr double margin = 1.0 / 1024.0;
    const double x0 = x, y0 = y, x1 = x + 1.0, y1 = y + 1.0;
    if (!(t.hi.x > x0 + margin && t.lo.x < x1 - margin && t.hi.y > y0 + margin && t.lo.y < y1 - margin)) return false;
    for (int j = 0; j < t.count; ++j) {
        const glm::dvec3& a = t.s[j];
        const glm::dvec3& b = t.s[(j + 1) % t.count];
        const double nx = b.y - a.y, ny = a.x - b.x;  // edge normal
        double poly_lo = 1e300, poly_hi = -1e300;
        for (int k = 0; k < t.count; ++k) {
            const double v = mulRounded(nx, t.s[k].x) + mulRounded(ny, t.s[k].y);
            poly_lo = std::min(poly_lo, v);
            poly_hi = std::max(poly_hi, v);
        }
        const double bx0 = mulRounded(nx, x0), bx1 = mulRounded(nx, x1), by0 = mulRounded(ny, y0), by1 = mulRounded(ny, y1);
        const double box_lo = std::min(bx0, bx1) + std::min(by0, by1), box_hi = std::max(bx0, bx1) + std::max(by0, by1);
        const double slack = mulRounded(margin, std::abs(nx) + std::abs(ny));
        if (!(poly_hi > box_lo + slack && poly_lo < box_hi - slack)) return false;
    }
    const double corner = (t.g0 + std::min(mulRounded(t.ga, x0), mulRounded(t.ga, x1))) +
                          std::min(mulRounded(t.gb, y0), mulRounded(t.gb, y1));
    d = std::max(corner, t.dmin);
    d = d - mulRounded(1e-6, (std::abs(d) + std::abs(t.ga)) + std::abs(t.gb));
    c = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 4; ++k) {
        const double cx = (k & 1) ? x1 : x0, cy = (k >> 1) ? y1 : y0;
        for (int j = 0; j < t.count; ++j) {
            const glm::dvec3& a = t.s[j];
            const glm::dvec3& b = t.s[(j + 1) % t.count];
            const double e = mulRounded(b.x - a.x, cy - a.y) - mulRounded(b.y - a.y, cx - a.x);
            const double scale = ((std::abs(b.x - a.x) + std::abs(b.y - a.y)) + std::abs(cx - a.x)) + std::abs(cy - a.y);
            if (!(mulRounded(e, t.orientation) > mulRounded(mulRounded(1e-9, scale), scale))) return true;
        }
    }
    const double far_corner = (t.g0 + std::max(mulRounded(t.ga, x0), mulRounded(t.ga, x1))) +
                              std::max(mulRounded(t.gb, y0), mulRounded(t.gb, y1));
    c = std::min(far_corner, t.dmax);
    c = c + mulRounded(1e-6, (std::abs(c) + std::abs(t.ga)) + std::abs(t.gb));
    return true;
}
}  // namespace detail

/// Builds the moment map over options.grid_width x grid_height with light.view_projection (the
/// same frustum the stencil reads with), casters culled as the hard pipeline culls them.
inline MomentMapCpu conservativeMomentMapCpu(const AliasFreeHardOptions& options, const SampleListsLight& light,
                                             const AfhCasters& casters) {
    validateAliasFreeHardOptions(options, light.light);
    PENUMBRA_CHECK(casters.positions && casters.indices && casters.closed &&
                       casters.closed->size() * 3 == casters.indices->size(),
                   "penumbra::conservativeMomentMapCpu: casters need positions, indices and one closed flag per triangle");
    MomentMapCpu m;
    m.width = options.grid_width;
    m.height = options.grid_height;
    m.perspective = light.light.w != 0.0f;
    m.d_far = m.perspective ? 0.0f : 2.0f;  // -1/w < 0 in front of a perspective light; z_ndc <= 1
    std::vector<double> depth(size_t(m.width) * m.height, double(m.d_far));
    std::vector<double> cover(depth.size(), std::numeric_limits<double>::infinity());
    const glm::dmat4 vp(light.view_projection);
    const auto& P = *casters.positions;
    const auto& I = *casters.indices;
    for (size_t t = 0; t < casters.closed->size(); ++t) {
        const glm::vec3 v[3] = {P[I[3 * t]], P[I[3 * t + 1]], P[I[3 * t + 2]]};
        if (detail::degenerateTriangle(glm::dvec3(v[0]), glm::dvec3(v[1]), glm::dvec3(v[2]))) continue;
        if (detail::afhCulled(options, (*casters.closed)[t] != 0, v, light.light)) continue;
        detail::AaDepthTriangle tri;
        if (!detail::aaDepthTriangle(vp, glm::dvec3(v[0]), glm::dvec3(v[1]), glm::dvec3(v[2]), m.width, m.height, m.perspective,
                                     tri))
            continue;
        const int x0 = std::max(0, int(std::floor(tri.lo.x))), y0 = std::max(0, int(std::floor(tri.lo.y)));
        const int x1 = std::min(int(m.width) - 1, int(std::floor(tri.hi.x)));
        const int y1 = std::min(int(m.height) - 1, int(std::floor(tri.hi.y)));
        for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) {
                double d = 0.0, c = 0.0;
                if (!detail::aaDepthTexel(tri, x, y, d, c)) continue;
                double& texel = depth[size_t(y) * m.width + x];
                texel = std::min(texel, d);
                double& covered = cover[size_t(y) * m.width + x];
                covered = std::min(covered, c);
            }
        }
    }
    m.cover.emplace_back(cover.begin(), cover.end());  // +inf stays +inf in float
    m.levels.emplace_back(depth.size());
    for (size_t i = 0; i < depth.size(); ++i) {
        const double d = double(float(depth[i]));  // the GPU keeps the float (atomicMin on its bits)
        m.levels[0][i] = glm::vec2(float(d), float(detail::mulRounded(d, d)));
    }
    for (uint32_t l = 1; m.levelWidth(l - 1) > 1 || m.levelHeight(l - 1) > 1; ++l) {
        const uint32_t pw = m.levelWidth(l - 1), ph = m.levelHeight(l - 1), w = m.levelWidth(l), h = m.levelHeight(l);
        const std::vector<glm::vec2>& prev = m.levels[l - 1];
        std::vector<glm::vec2> next(size_t(w) * h);
        std::vector<float> next_cover(size_t(w) * h);
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x) {
                glm::dvec2 sum(0.0);
                float covered = -std::numeric_limits<float>::infinity();
                for (uint32_t k = 0; k < 4; ++k) {
                    const uint32_t sx = std::min(pw - 1, 2 * x + (k & 1)), sy = std::min(ph - 1, 2 * y + (k >> 1));
                    sum += glm::dvec2(prev[size_t(sy) * pw + sx]);
                    covered = std::max(covered, m.cover[l - 1][size_t(sy) * pw + sx]);
                }
                next[size_t(y) * w + x] = glm::vec2(float(sum.x * 0.25), float(sum.y * 0.25));
                next_cover[size_t(y) * w + x] = covered;
            }
        m.levels.push_back(std::move(next));
        m.cover.push_back(std::move(next_cover));
    }
    return m;
}

/// Value-initialised = galoppo2010's settings.
struct ChebyshevStencilOptions {
    float threshold = 0.01f;      ///< flag unless a bound says lit or shadowed with probability >= 1 - threshold
    /// The lit test compares at t_min - bias_scale * (the receiver's estimated depth spread over the
    /// texels read): the receiver is in the map too. Chebyshev needs the margin >~ 10 sigma for 1%.
    float bias_scale = 4.0f;
    float min_variance = 1e-12f;  ///< galoppo2010's gMinVariance, in depth units squared
    /// false (galoppo2010): "fully shadowed" from Chebyshev's bound. The map's conservative
    /// minimum makes a partly covered texel look fully covered, so that claim is wrong wherever a
    /// shadow edge crosses a texel (most misses when texels are larger than pixel footprints).
    /// true: "fully shadowed" only from the inner-coverage channel — every texel read is inside
    /// one caster triangle lying in front of every point (a proof, up to the exact test's
    /// coplanar tolerance); the lit claim stays Chebyshev's.
    bool inner_shadow_proof = false;
};

/// galoppo2010's stencil (Listing 1.6.1) over explicit footprints: the level where the points'
/// light-space box spans at most one texel, the mean moments of the <= 2x2 texels it touches,
/// Chebyshev's one-tailed bounds. Pixels with no surface stay 0; points outside the map are flagged.
inline std::vector<uint8_t> chebyshevEdgeStencilCpu(const MomentMapCpu& m, const SampleListsLight& light,
                                                    const AaFootprints& f, const ChebyshevStencilOptions& o = {},
                                                    bool cull_back_facing = true) {
    PENUMBRA_CHECK(o.threshold > 0.0f && o.threshold < 1.0f && o.bias_scale >= 0.0f && o.min_variance > 0.0f,
                   "penumbra::chebyshevEdgeStencilCpu: threshold ", o.threshold, " must be in (0, 1), bias_scale ",
                   o.bias_scale, " >= 0, min_variance ", o.min_variance, " > 0");
    std::vector<uint8_t> flags(f.pixels, 0);
    const glm::dmat4 vp(light.view_projection);
    const uint32_t levels = uint32_t(m.levels.size());
    PENUMBRA_CHECK(levels > 0 || f.pixels == 0, "penumbra::chebyshevEdgeStencilCpu: an empty moment map");
    for (uint32_t i = 0; i < f.pixels; ++i) {
        if (f.centres[i].w == 0.0f) continue;
        const glm::vec4* subs = f.subSamples(i);
        if (cull_back_facing) {
            // Facing is geometry, not shadow: the same rule as the provable stencil.
            uint32_t back = detail::aaBackFacing(light.light, f.centres[i], glm::vec3(f.normals[i]));
            for (uint32_t k = 0; k < f.samples; ++k) back += detail::aaBackFacing(light.light, subs[k], glm::vec3(f.normals[i]));
            if (back == f.samples + 1) continue;
            if (back != 0) {
                flags[i] = 1;
                continue;
            }
        }
        glm::dvec2 lo(1e300), hi(-1e300);
        double t_min = 1e300, t_max = -1e300;
        bool inside = true;
        for (uint32_t k = 0; k <= f.samples && inside; ++k) {
            const glm::vec4 p = k == 0 ? f.centres[i] : subs[k - 1];
            const glm::dvec4 c = detail::aaTransform(vp, glm::dvec4(glm::dvec3(glm::vec3(p)), 1.0));
            if (!(c.w > 0.0)) {
                inside = false;
                break;
            }
            const glm::dvec2 g(detail::aaGrid(c.x, c.w, m.width), detail::aaGrid(c.y, c.w, m.height));
            if (!(g.x >= 0.0 && g.x <= m.width && g.y >= 0.0 && g.y <= m.height)) inside = false;
            lo = glm::min(lo, g);
            hi = glm::max(hi, g);
            const double d = detail::aaLightDepth(c, m.perspective);
            t_min = std::min(t_min, d);
            t_max = std::max(t_max, d);
        }
        if (!inside) {
            flags[i] = 1;
            continue;
        }
        // The level whose texels are at least the footprint's extent: at most 2x2 texels read.
        const double extent = std::max(hi.x - lo.x, hi.y - lo.y);
        uint32_t level = 0;
        double span = 1.0;
        while (span < extent && level + 1 < levels) {
            span = span * 2.0;
            ++level;
        }
        const uint32_t lw = m.levelWidth(level), lh = m.levelHeight(level);
        const int x0 = std::clamp(int(std::floor(lo.x / span)), 0, int(lw) - 1), x1 = std::clamp(int(std::floor(hi.x / span)), 0, int(lw) - 1);
        const int y0 = std::clamp(int(std::floor(lo.y / span)), 0, int(lh) - 1), y1 = std::clamp(int(std::floor(hi.y / span)), 0, int(lh) - 1);
        double sum_x = 0.0, sum_y = 0.0;
        int n = 0;
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x, ++n) {
                sum_x = sum_x + double(m.levels[level][size_t(y) * lw + x].x);
                sum_y = sum_y + double(m.levels[level][size_t(y) * lw + x].y);
            }
        const double mu = sum_x / double(n);
        const double var = std::max(double(o.min_variance), sum_y / double(n) - detail::mulRounded(mu, mu));
        const double threshold = double(o.threshold);
        bool decided = false;
        if (o.inner_shadow_proof) {
            // Fully shadowed, proven: each texel read lies inside a triangle in front of t_min.
            float covered = -std::numeric_limits<float>::infinity();
            for (int y = y0; y <= y1; ++y)
                for (int x = x0; x <= x1; ++x) covered = std::max(covered, m.cover[level][size_t(y) * lw + x]);
            decided = double(covered) < t_min - detail::mulRounded(1e-6, std::abs(t_min));
        } else if (t_min > mu) {
            // Fully shadowed: even the nearest point has P(x >= t_min) < threshold.
            const double gap = t_min - mu;
            decided = var / (var + detail::mulRounded(gap, gap)) < threshold;
        }
        // Fully lit: P(x < t_min - bias) < threshold. The receiver lies in the map itself: over the
        // <= 2x2 texels read (2 span level-0 texels wide) its depth spreads by about the footprint's
        // depth extent times (region width / footprint width); bias_scale of that.
        const double spread = detail::mulRounded(t_max - t_min, 2.0 * span) / std::max(extent, 0x1.0p-20);
        const double t_lit = t_min - detail::mulRounded(double(o.bias_scale), spread);
        if (!decided && t_lit < mu) {
            const double gap = mu - t_lit;
            decided = var / (var + detail::mulRounded(gap, gap)) < threshold;
        }
        flags[i] = decided ? 0 : 1;
    }
    return flags;
}

/// Levels of the moment map's mip chain for a W x H grid (down to 1 x 1).
inline uint32_t aaMomentLevels(uint32_t width, uint32_t height) {
    uint32_t levels = 1;
    while ((width >> (levels - 1)) > 1 || (height >> (levels - 1)) > 1) ++levels;
    return levels;
}

/// The GPU kernels' parameter block (pure setup): the view, the light (its view_projection must see
/// every centre and sub-sample), the hard pipeline's exact-test settings, the rotated-grid pattern
/// (the GPU runs the rotated grid only: a jittered pattern differs per pixel), the light grid
/// (options.grid_width x grid_height), the list capacity and the limits, the mode of the
/// sample-buffer and resolve kernels, and the Chebyshev stencil's options.
inline AaParams aaParams(const SampleListsView& view, const SampleListsLight& light, const AliasFreeHardOptions& options,
                         const AaPatternOptions& pattern, const ProvableStencilOptions& so, uint32_t list_capacity,
                         uint32_t mode, const ChebyshevStencilOptions& chebyshev = {}) {
    checkAaPatternOptions(pattern);
    PENUMBRA_CHECK(pattern.pattern == AaPattern::RotatedGrid,
                   "penumbra::aaParams: the GPU stencil runs the rotated-grid pattern only (jittered: the CPU path)");
    AaParams p{};
    const glm::dmat4 inverse(view.inverse_view_projection), vp(light.view_projection);
    for (int c = 0; c < 4; ++c) {
        p.inverse_view_projection[c] = inverse[c];
        p.light_view_projection[c] = vp[c];
    }
    p.numbers = glm::dvec4(options.coplanar_epsilon, double(options.directional_reach), view.depth_zero_to_one ? 0.0 : -1.0,
                           options.scene_extent);
    p.light_clip = light.view_projection;
    p.light = light.light;
    for (uint32_t k = 0; k < pattern.samples; ++k) {
        const glm::vec2 o = aaSubSampleOffset(pattern, 0, k);
        if (k % 2 == 0) {
            p.offsets[k / 2].x = o.x;
            p.offsets[k / 2].y = o.y;
        } else {
            p.offsets[k / 2].z = o.x;
            p.offsets[k / 2].w = o.y;
        }
    }
    p.view = glm::uvec4(view.width, view.height, pattern.samples, so.cull_back_facing ? 1u : 0u);
    p.grid = glm::uvec4(options.grid_width, options.grid_height, list_capacity, mode);
    p.limits = glm::uvec4(so.max_footprint_texels, so.maxList(pattern.samples), 0u, 0u);
    const bool perspective = light.light.w != 0.0f;
    p.chebyshev = glm::vec4(chebyshev.threshold, chebyshev.bias_scale, chebyshev.min_variance, perspective ? 0.0f : 2.0f);
    p.moments = glm::uvec4(aaMomentLevels(options.grid_width, options.grid_height), chebyshev.inner_shadow_proof ? 1u : 0u,
                           perspective ? 1u : 0u, 0u);
    return p;
}

}  // namespace penumbra

#endif
