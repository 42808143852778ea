// penumbra — deep shadow maps (lokovic2000 §3-§5): per light texel a piecewise-linear visibility
// function of depth, built from S jittered sub-samples per texel, filtered over the texel, compressed
// to within a tolerance in L-infinity and looked up like a texture. This header is the GL-free part:
// options, pure setup, the sub-sample patterns, the CPU twin of the build (rasterization, per
// sub-sample transmittance, merge, compression, mip-maps) and the lookup.
//
// Integration summary
//   input:    casters as float positions + uint32 indices (3 per triangle) with an opacity per mesh,
//             per triangle, per vertex or from a hook (e.g. an alpha texture at interpolated texture
//             coordinates; one channel, or RGB for coloured transmittance); the light
//             as a view-projection (clip space) plus its depth row (light depth = distance along the
//             light's axis: -z of the light's view space, for perspective and orthographic lights).
//   produces: per level (0 = R x R, then halving) a texel offset table (exclusive scan of the vertex
//             counts, R*R + 1 entries) and the vertices: float z and V per channel in 16 bits
//             (6 bytes per grey vertex, 10 per RGB one on the GPU; DsmMapCpu holds them decoded,
//             (1 + channels) floats). V is non-increasing in z.
//   lookup:   dsmVisibility (one texel, left-continuous: a receiver exactly at a surface's depth is
//             not shadowed by it), dsmLookup (bilinear over texels, trilinear over levels) — the CPU
//             twins of shaders/penumbra/deep_shadow_map/lookup.glsl.
//
// The function of one texel (lokovic2000 §3.1-§3.2, §5.1). Sub-sample j of texel (x, y) sits at
// window position (x + o.x, y + o.y), o from one of PENUMBRA_DSM_PATTERNS host-generated jittered
// stratified patterns (g x g cells, g = ceil(sqrt S); a hash of (x, y) picks the pattern), so the
// GPU and the CPU use the same float positions. Its transmittance function is the product of
// (1 - opacity) over every caster fragment along its ray: a step function with one step per surface.
// The texel's function is the weighted average of the sub-sample functions within the filter
// radius (box: |dx|, |dy| <= r around the texel centre, weight 1; Gaussian: dx^2 + dy^2 <= r^2,
// weight exp(-2 d^2 / r^2) from a 256-entry table indexed by d^2 / r^2), merged in depth order
// (§5.1: a heap over the sub-sample lists; each event subtracts the sub-sample's old contribution:
// V -= (w_j T_j) alpha, T_j *= 1 - alpha). Events at the same depth form one vertical step: two
// vertices (z, V before), (z, V after).
//
// A texel whose filter support holds no sub-sample (a Gaussian of radius < ~0.7 can miss all of
// them) has an empty function: V = 1. Use radius >= 1 with the Gaussian.
//
// Rasterization (the rule the GPU's fragment stage applies inside the conservative hull): the
// triangle's clip coordinates h_i = (x, y, w) give homogeneous edge functions E_i = n_i . (px, py, 1)
// with n_0 = h_1 x h_2, n_1 = h_2 x h_0, n_2 = h_0 x h_1 (Olano & Greer 1997: no clipping, correct
// behind the light's eye plane). Normalised to a positive determinant, a sub-sample is covered when
// every E_i > 0, or E_i == 0 and (n_i.x > 0 or n_i.x == 0 and n_i.y > 0) (a top-left rule: two
// triangles sharing an edge compute exactly opposite n, so a sub-sample on the edge is covered
// exactly once; a sub-sample lying exactly on a vertex shared by several triangles is not covered by
// the argument — the spokes' rounded edge functions need not agree — and may be covered 0 or 2
// times: tests/deep_shadow_map_test.cpp measures it), and E_0 + E_1 + E_2 > 0. Its depth is (E_0 d_0 + E_1 d_1 + E_2 d_2) / (E_0 + E_1
// + E_2) (perspective-correct: E_i / sum are the barycentrics), per-vertex opacity likewise. Every
// product is rounded on its own (no FMA; GLSL `precise`), so on drivers with correctly rounded
// float32 arithmetic (llvmpipe) the GPU's fragments, depths, vertices and lookups equal this twin's
// bit for bit; elsewhere they differ by rounding (the tests' portable tier bounds it).
//
// Storage: per vertex float z and, per channel, V in 16 bits (q / 32768, exact for dyadic values;
// 6 bytes per grey vertex), each texel's count padded to even (a copy of its last vertex). The
// rounding (<= 2^-16) comes out of the tolerance first, so stored values keep the bound below.
//
// Compression (§3.3, the greedy L-infinity algorithm): keep the slope window [lo, hi] of the
// current segment open as long as every input vertex since its origin lies within the tolerance of
// the segment; hi starts at 0, so the output is non-increasing; outputs z are input z; a window
// that closes ends the segment at the last input vertex it accepted; a drop at the origin's own
// depth that no slope can follow becomes a vertical step (to the drop's exact value when it can).
// Unlike lokovic2000, whose origin is the previous window's middle slope at that depth, a segment's
// origin stays free within what the previous window allows there: PENUMBRA_DSM_CANDIDATES (4)
// origins are tried at once, each with its own window, and the one open longest (widest window)
// fixes the previous segment's end when this one closes (DsmCompressor). Same bound, 8-12 %
// fewer vertices on hairball and grass (docs/design.md). The windows use
// the tolerance minus 1/64 of it, which covers float rounding (tolerance >= 2^-12), and never reach
// below 0 (a window [max(V - eps, 0), V + eps]: clamping a segment's end afterwards would move its
// inside by more than the tolerance), so the output is
// within the tolerance of its input at every depth, both one-sided limits included — tested on every
// texel in double. Colour (§5.2): one vertex sequence, a new segment as soon as any channel's window
// closes.
//
// Mip-maps (§5.3): texel (x, y) of level k + 1 is the average of texels (2x, 2y) .. (2x+1, 2y+1) of
// level k (their functions evaluated at the union of their depths, both one-sided limits), recompressed
// with tolerance eps / 2^(k+1): level k lies within eps (1 + 1/2 + ... + 1/2^k) < 2 eps of the exact
// average of its level-0 block. R must be a power of two for more than one level.
#ifndef PENUMBRA_DEEP_SHADOW_MAP_HPP
#define PENUMBRA_DEEP_SHADOW_MAP_HPP

#include "penumbra/detail/shared.hpp"
#if defined(__has_include) && __has_include(<penumbra/deep_shadow_map/deep_shadow_map_shared.h>)
#include <penumbra/deep_shadow_map/deep_shadow_map_shared.h>
#else
#include "../../shaders/penumbra/deep_shadow_map/deep_shadow_map_shared.h"
#endif

#include "penumbra/detail/float_ops.hpp"
#include "penumbra/error.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace penumbra {

using DsmParams = shared::PenumbraDsmParams;
static_assert(sizeof(DsmParams) == 272, "PenumbraDsmParams must be 272 bytes (std140 == std430)");

inline constexpr uint32_t kDsmMaxResolution = PENUMBRA_DSM_MAX_RESOLUTION;
inline constexpr uint32_t kDsmMaxSamples = PENUMBRA_DSM_MAX_SAMPLES;
inline constexpr uint32_t kDsmPatterns = PENUMBRA_DSM_PATTERNS;
inline constexpr uint32_t kDsmMaxMergeLists = PENUMBRA_DSM_MAX_MERGE_LISTS;
inline constexpr uint32_t kDsmGaussTable = PENUMBRA_DSM_GAUSS_TABLE;
/// The smallest tolerance: below it float rounding of V (~1e-7) is no longer small against the
/// 1/64 of the tolerance the compressor keeps in reserve.
inline constexpr float kDsmMinTolerance = 1.0f / 4096.0f;
/// Stored V: 16 bits, V = q / 32768 (q in [0, 32768]): dyadic values (1, 1/2, 3/4 ...) stay exact and
/// decoding is one exact multiplication on every platform; the rounding (<= 2^-16) is taken out of
/// the tolerance before compressing (dsmInnerTolerance).
inline constexpr float kDsmVScale = 32768.0f;
inline constexpr float kDsmQuantization = 1.0f / 65536.0f;

/// The tolerance the compressor's windows use for a level of tolerance `tol`: minus 1/64 of it
/// (float rounding) and minus the 16-bit rounding of the stored values (DsmParams::numbers.w).
inline float dsmInnerTolerance(float tol) { return (tol - tol * (1.0f / 64.0f)) - kDsmQuantization; }

/// The stored value of V (twin of penumbraDsmQuantize / penumbraDsmDecode).
inline uint32_t dsmQuantize(float v) { return static_cast<uint32_t>(v * kDsmVScale + 0.5f); }
inline float dsmDecode(uint32_t q) { return static_cast<float>(q) * (1.0f / kDsmVScale); }

enum class DsmFilter : uint32_t { Box = PENUMBRA_DSM_FILTER_BOX, Gaussian = PENUMBRA_DSM_FILTER_GAUSSIAN };

/// Value-initialised = defaults.
struct DsmOptions {
    uint32_t resolution = 256;       ///< R: the map is R x R texels; [1, 4096]; a power of two when levels > 1
    uint32_t samples = 16;           ///< S: jittered sub-samples per texel; [1, 1024]
    float tolerance = 0.0f;          ///< eps (L-infinity) of level 0; 0 = 1 / (2 S); [2^-12, 1]
    DsmFilter filter = DsmFilter::Box;
    float filter_radius = 0.5f;      ///< texels; 0.5 = the texel's own sub-samples (box); (0, 8]
    uint32_t channels = 1;           ///< 1 (grey transmittance) or 3 (RGB, lokovic2000 §5.2)
    uint32_t levels = 1;             ///< mip levels including level 0; 0 = the full chain down to 1 x 1
    uint32_t pattern_seed = 1;       ///< seeds the sub-sample patterns
};

/// Everything derived from the options (deepShadowMapSetup).
struct DsmSetup {
    DsmOptions options;
    uint32_t resolution = 0, samples = 0, channels = 1, levels = 1;
    uint32_t reach = 0;           ///< neighbour texels the filter reaches: ceil(radius - 0.5)
    uint32_t merge_lists = 0;     ///< (2 reach + 1)^2 S sub-sample lists per texel's merge
    float tolerance = 0.0f;       ///< eps of level 0
    uint64_t texels_total = 0;    ///< texels over all levels
    std::vector<uint32_t> level_resolution;
    std::vector<uint64_t> level_texel_offset;  ///< first texel of each level in the offset tables
    std::vector<glm::vec2> pattern_offsets;    ///< kDsmPatterns * S offsets in [0, 1)^2
    std::vector<float> gauss_table;            ///< kDsmGaussTable weights (Gaussian filter)
    uint32_t vertexFloats() const { return 1 + channels; }
    uint32_t vertexBytes() const { return 4 * vertexFloats(); }
    float levelTolerance(uint32_t level) const { return std::ldexp(tolerance, -static_cast<int>(level)); }
};

namespace detail {

inline uint32_t dsmHash(uint32_t x) {  // lowbias32 (C. Wellons): a bijection with good avalanche
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

/// Twin of penumbraDsmPattern: which pattern texel (x, y) uses.
inline uint32_t dsmPattern(uint32_t x, uint32_t y) {
    return dsmHash(x * 0x9E3779B9u ^ dsmHash(y + 0x632BE5ABu)) % kDsmPatterns;
}

inline uint64_t dsmSplitMix(uint64_t& state) {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

inline bool isPowerOfTwo(uint32_t v) { return v != 0 && (v & (v - 1)) == 0; }

}  // namespace detail

/// Validates the options (penumbra::Error names the bad value) and derives sizes, the patterns and
/// the filter table.
inline DsmSetup deepShadowMapSetup(const DsmOptions& options) {
    DsmSetup s;
    s.options = options;
    PENUMBRA_CHECK(options.resolution >= 1 && options.resolution <= kDsmMaxResolution,
                   "deepShadowMapSetup: resolution ", options.resolution, " is outside [1, ", kDsmMaxResolution, "]");
    PENUMBRA_CHECK(options.samples >= 1 && options.samples <= kDsmMaxSamples, "deepShadowMapSetup: samples ",
                   options.samples, " is outside [1, ", kDsmMaxSamples, "] (S = 0 has no sub-sample to build from)");
    PENUMBRA_CHECK(options.channels == 1 || options.channels == 3, "deepShadowMapSetup: channels ", options.channels,
                   " must be 1 or 3");
    const float eps = options.tolerance == 0.0f ? 0.5f / static_cast<float>(options.samples) : options.tolerance;
    PENUMBRA_CHECK(std::isfinite(eps) && eps >= kDsmMinTolerance && eps <= 1.0f, "deepShadowMapSetup: tolerance ",
                   options.tolerance, " is outside [2^-12, 1] (0 selects 1 / (2 S)); it must be finite and > 0");
    PENUMBRA_CHECK(std::isfinite(options.filter_radius) && options.filter_radius > 0.0f && options.filter_radius <= 8.0f,
                   "deepShadowMapSetup: filter_radius ", options.filter_radius, " is outside (0, 8] texels");
    PENUMBRA_CHECK(options.filter == DsmFilter::Box || options.filter == DsmFilter::Gaussian,
                   "deepShadowMapSetup: filter ", static_cast<uint32_t>(options.filter), " is not a DsmFilter");
    const uint64_t sub_samples = uint64_t(options.resolution) * options.resolution * options.samples;
    PENUMBRA_CHECK(sub_samples < 0xFFFFFFFFull, "deepShadowMapSetup: resolution ", options.resolution, "^2 x samples ",
                   options.samples, " = ", sub_samples, " sub-sample lists exceed the 2^32 - 1 a uint32 list index addresses");
    s.resolution = options.resolution;
    s.samples = options.samples;
    s.channels = options.channels;
    s.tolerance = eps;
    s.reach = static_cast<uint32_t>(std::ceil(std::max(0.0f, options.filter_radius - 0.5f)));
    const uint64_t side = 2ull * s.reach + 1;
    const uint64_t lists = side * side * s.samples;
    PENUMBRA_CHECK(lists <= kDsmMaxMergeLists, "deepShadowMapSetup: the filter (radius ", options.filter_radius,
                   ", reach ", s.reach, ") with samples ", s.samples, " merges ", lists,
                   " sub-sample lists per texel, more than ", kDsmMaxMergeLists);
    s.merge_lists = static_cast<uint32_t>(lists);

    uint32_t full = 1;
    for (uint32_t r = s.resolution; r > 1; r >>= 1) ++full;
    uint32_t levels = options.levels == 0 ? full : options.levels;
    PENUMBRA_CHECK(levels == 1 || detail::isPowerOfTwo(s.resolution), "deepShadowMapSetup: levels ", options.levels,
                   " need a power-of-two resolution, not ", s.resolution);
    PENUMBRA_CHECK(levels >= 1 && levels <= full, "deepShadowMapSetup: levels ", options.levels, " exceeds the ", full,
                   " levels of a ", s.resolution, "^2 map");
    s.levels = levels;
    uint64_t texels = 0;
    for (uint32_t l = 0; l < levels; ++l) {
        const uint32_t r = s.resolution >> l;
        s.level_resolution.push_back(r);
        s.level_texel_offset.push_back(texels);
        texels += static_cast<uint64_t>(r) * r;
    }
    s.texels_total = texels;

    // Jittered stratified patterns: g x g cells, S of them (a random subset when S is not a square),
    // one point per cell at a jitter quantised to 2^-16 of the cell (exact in float).
    const uint32_t g = static_cast<uint32_t>(std::ceil(std::sqrt(static_cast<double>(s.samples)) - 1e-9));
    uint64_t state = 0x5EEDD5A0ull ^ (static_cast<uint64_t>(options.pattern_seed) << 32);
    s.pattern_offsets.resize(static_cast<size_t>(kDsmPatterns) * s.samples);
    std::vector<uint32_t> cells(static_cast<size_t>(g) * g);
    for (uint32_t p = 0; p < kDsmPatterns; ++p) {
        for (uint32_t c = 0; c < cells.size(); ++c) cells[c] = c;
        for (size_t c = cells.size(); c > 1; --c) std::swap(cells[c - 1], cells[detail::dsmSplitMix(state) % c]);
        if (g * g == s.samples) std::sort(cells.begin(), cells.end());
        for (uint32_t j = 0; j < s.samples; ++j) {
            const uint64_t bits = detail::dsmSplitMix(state);
            const double jx = static_cast<double>(bits & 0xFFFFu) / 65536.0;
            const double jy = static_cast<double>((bits >> 16) & 0xFFFFu) / 65536.0;
            const uint32_t cx = cells[j] % g, cy = cells[j] / g;
            s.pattern_offsets[static_cast<size_t>(p) * s.samples + j] =
                glm::vec2(static_cast<float>((cx + jx) / g), static_cast<float>((cy + jy) / g));
        }
    }
    s.gauss_table.resize(kDsmGaussTable);
    for (uint32_t i = 0; i < kDsmGaussTable; ++i) {
        const double q = (i + 0.5) / kDsmGaussTable;  // d^2 / r^2 at the bin's middle
        s.gauss_table[i] = static_cast<float>(std::exp(-2.0 * q));
    }
    return s;
}

/// The light: clip = view_projection * (p, 1), depth = -(view * (p, 1)).z.
struct DsmLight {
    glm::mat4 view{1.0f};
    glm::mat4 projection{1.0f};
};

/// Opacity of the casters: the hook wins over per_vertex (size = vertex count), which wins over
/// per_triangle (size = triangle count), which wins over the per-mesh value. Channels beyond the
/// map's are ignored; with 3 channels a grey opacity is (a, a, a). Every value of mesh,
/// per_triangle and per_vertex must be finite and in [0, 1] (checked: penumbra::Error naming it).
///
/// The hook (PENUMBRA_DSM_OPACITY_HOOK) is the CPU twin of penumbraDsmOpacityHook
/// (shaders/penumbra/deep_shadow_map/opacity_hook.glsl, which an engine replaces with its own
/// material read): called for every covered sub-sample with the triangle's index and
/// hook_attribute (one vec3 per vertex, e.g. texture coordinates) interpolated like the depth. Its
/// result is clamped to [0, 1] per channel, NaN -> 0 — documented clamping, not an error, because
/// the GPU cannot report per-sample values without a read-back. The default GLSL hook's twin is
/// DsmOpacityTexture: `hook = [&t](uint32_t, const glm::vec3& a) { return dsmOpacityTexel(t, a); }`.
struct DsmOpacity {
    glm::vec3 mesh{1.0f};
    std::vector<glm::vec3> per_triangle;
    std::vector<glm::vec3> per_vertex;
    std::function<glm::vec3(uint32_t triangle, const glm::vec3& attribute)> hook;
    std::vector<glm::vec3> hook_attribute;  ///< with the hook: one per vertex
};

/// An opacity texture as the default hook reads it (twin of the texture on unit
/// PENUMBRA_DSM_OPACITY_TEXTURE_UNIT): width x height texels, row 0 first (GL's first row), rgb.
/// The GPU value equals it for float textures (GL_RGB32F, GL_RGBA32F); for normalised formats the
/// driver's conversion of the stored value applies.
struct DsmOpacityTexture {
    uint32_t width = 0, height = 0;
    std::vector<glm::vec3> texels;
};

/// The default hook's read (twin of penumbraDsmOpacityHook in opacity_hook.glsl): uv =
/// attribute.xy, repeat wrapping (the fraction u - floor(u) in float; NaN, Inf and a fraction that
/// rounds to 1 read texel 0), nearest texel min(int(f * size), size - 1). An empty texture gives 0.
inline glm::vec3 dsmOpacityTexel(const DsmOpacityTexture& texture, const glm::vec3& attribute) {
    if (texture.width == 0 || texture.height == 0 ||
        texture.texels.size() < static_cast<size_t>(texture.width) * texture.height)
        return glm::vec3(0.0f);
    const uint32_t size[2] = {texture.width, texture.height};
    uint32_t texel[2];
    for (int a = 0; a < 2; ++a) {
        float f = attribute[a] - std::floor(attribute[a]);
        if (!(f >= 0.0f && f < 1.0f)) f = 0.0f;
        const float g = f * static_cast<float>(size[a]);
        texel[a] = std::min(static_cast<uint32_t>(g), size[a] - 1);
    }
    return texture.texels[static_cast<size_t>(texel[1]) * texture.width + texel[0]];
}

/// An optional homogeneous participating medium (lokovic2000 §3.2: smoke, fog): an axis-aligned
/// box with extinction sigma_t; along each sub-sample's ray, from the light's eye plane on, the
/// transmittance exp(-sigma_t L) of the path L inside the box, sampled at `samples` + 1 depths
/// between entry and exit and linear in between (its error against the exponential is measured
/// by the tests). Active when sigma_t > 0. Grey: it multiplies every channel alike.
struct DsmMedium {
    glm::vec3 lo{0.0f}, hi{0.0f};
    float sigma_t = 0.0f;   ///< extinction per world unit; 0 = no medium
    uint32_t samples = 8;   ///< segments per sub-sample ray; [1, 64]
    bool active() const { return sigma_t > 0.0f; }
};

/// Throws penumbra::Error naming the bad value (non-finite or inverted box, sigma_t < 0 or NaN,
/// samples outside [1, 64]).
inline void checkDsmMedium(const DsmMedium& m) {
    PENUMBRA_CHECK(std::isfinite(m.sigma_t) && m.sigma_t >= 0.0f, "deep shadow map: medium sigma_t ", m.sigma_t,
                   " must be finite and >= 0");
    if (!m.active()) return;
    for (int a = 0; a < 3; ++a)
        PENUMBRA_CHECK(std::isfinite(m.lo[a]) && std::isfinite(m.hi[a]) && m.lo[a] <= m.hi[a], "deep shadow map: medium box axis ",
                       a, " [", m.lo[a], ", ", m.hi[a], "] must be finite with lo <= hi");
    PENUMBRA_CHECK(m.samples >= 1 && m.samples <= 64, "deep shadow map: medium samples ", m.samples, " is outside [1, 64]");
}

/// The constants block of level `level` (the build's defaults for everything else).
inline DsmParams deepShadowMapParams(const DsmSetup& setup, const DsmLight& light, const DsmOpacity& opacity,
                                     uint32_t level = 0, const DsmMedium& medium = {}) {
    DsmParams p{};
    p.light_view_projection = light.projection * light.view;
    p.inverse_view_projection = glm::inverse(p.light_view_projection);
    p.medium_lo = glm::vec4(medium.lo, medium.active() ? medium.sigma_t : 0.0f);
    p.medium_hi = glm::vec4(medium.hi, 0.0f);
    p.depth_row = -glm::vec4(light.view[0][2], light.view[1][2], light.view[2][2], light.view[3][2]);
    p.opacity = glm::vec4(opacity.mesh, 0.0f);
    p.size = glm::uvec4(setup.resolution, setup.samples, setup.channels, setup.levels);
    p.filtering = glm::uvec4(static_cast<uint32_t>(setup.options.filter), setup.reach, setup.merge_lists, level);
    const float r = setup.options.filter_radius;
    const float tol = setup.levelTolerance(level);
    p.numbers = glm::vec4(2.0f / static_cast<float>(setup.resolution), r, 1.0f / (r * r), dsmInnerTolerance(tol));
    p.capacity = glm::uvec4(0u, 0u, static_cast<uint32_t>(setup.level_texel_offset[level]), setup.level_resolution[level]);
    p.flags = glm::uvec4(opacity.hook                    ? PENUMBRA_DSM_OPACITY_HOOK
                         : !opacity.per_vertex.empty()   ? PENUMBRA_DSM_OPACITY_VERTEX
                         : !opacity.per_triangle.empty() ? PENUMBRA_DSM_OPACITY_TRIANGLE
                                                         : PENUMBRA_DSM_OPACITY_MESH,
                         0u, medium.active() ? medium.samples : 0u, 0u);
    return p;
}

/// One caster fragment of a sub-sample: depth, the triangle, its opacity (rgb; grey uses .r).
struct DsmFragment {
    float z = 0.0f;
    uint32_t triangle = 0;
    glm::vec3 alpha{0.0f};
};

/// The fragments of every sub-sample list, list k = texel * S + j, sorted by (z, triangle).
struct DsmFragmentsCpu {
    std::vector<uint32_t> offsets;  ///< R*R*S + 1
    std::vector<DsmFragment> fragments;
};

/// A compressed (or uncompressed) map: per level an offset table and (z, V...) floats.
struct DsmMapCpu {
    uint32_t resolution = 0, channels = 1, levels = 0;
    std::vector<uint32_t> resolution_of;           ///< per level
    std::vector<std::vector<uint32_t>> offsets;    ///< per level: texels + 1 entries (vertex indices)
    std::vector<std::vector<float>> vertices;      ///< per level: (1 + channels) floats per vertex
    uint64_t vertexCount(uint32_t level) const { return offsets[level].back(); }
    bool packed = false;  ///< compressed: stored as float z + 16-bit V per channel (else float everywhere)
    /// Bytes of level `level` as stored: 4 per offset entry + per vertex 4 (z) + 2 per channel
    /// (packed) or 4 per channel.
    uint64_t levelBytes(uint32_t level) const {
        const uint64_t n = offsets[level].back();
        return 4ull * offsets[level].size() + n * (4ull + (packed ? 2ull : 4ull) * channels);
    }
    uint64_t bytes() const {
        uint64_t b = 0;
        for (uint32_t l = 0; l < levels; ++l) b += levelBytes(l);
        return b;
    }
};

namespace detail {

/// The hook's result in [0, 1] per channel, NaN -> 0 (twin of raster.frag.glsl's clamp).
inline glm::vec3 dsmClampOpacity(const glm::vec3& a) {
    glm::vec3 r;
    for (int c = 0; c < 3; ++c) r[c] = a[c] >= 0.0f ? std::min(a[c], 1.0f) : 0.0f;
    return r;
}

inline void checkOpacity(const glm::vec3& a, const char* what, size_t index) {
    for (int c = 0; c < 3; ++c)
        PENUMBRA_CHECK(std::isfinite(a[c]) && a[c] >= 0.0f && a[c] <= 1.0f, "deep shadow map: opacity ", a[c], " of ",
                       what, " ", index, " (channel ", c, ") is outside [0, 1]");
}

/// n = a x b with every product rounded on its own (twin of penumbraDsmCross).
inline glm::vec3 dsmCross(const glm::vec3& a, const glm::vec3& b) {
    return glm::vec3(mulRounded(a.y, b.z) - mulRounded(a.z, b.y), mulRounded(a.z, b.x) - mulRounded(a.x, b.z),
                     mulRounded(a.x, b.y) - mulRounded(a.y, b.x));
}

/// E = (n.x px + n.y py) + n.z (twin of penumbraDsmEdge).
inline float dsmEdge(const glm::vec3& n, float px, float py) {
    return (mulRounded(n.x, px) + mulRounded(n.y, py)) + n.z;
}

inline bool dsmEdgeCovers(float e, const glm::vec3& n) {
    return e > 0.0f || (e == 0.0f && (n.x > 0.0f || (n.x == 0.0f && n.y > 0.0f)));
}

/// ((E0 a0 + E1 a1) + E2 a2) / ((E0 + E1) + E2) (twin of penumbraDsmInterpolate).
inline float dsmInterpolate(float e0, float e1, float e2, float a0, float a1, float a2) {
    return ((mulRounded(e0, a0) + mulRounded(e1, a1)) + mulRounded(e2, a2)) / ((e0 + e1) + e2);
}

/// m * (p, 1) as ((m0 x + m1 y) + m2 z) + m3, products rounded (twin of penumbraDsmTransform).
inline glm::vec4 transformPointDsm(const glm::mat4& m, const glm::vec3& p) {
    glm::vec4 c;
    for (int r = 0; r < 4; ++r) c[r] = ((mulRounded(m[0][r], p.x) + mulRounded(m[1][r], p.y)) + mulRounded(m[2][r], p.z)) + m[3][r];
    return c;
}
inline float dsmDepth(const glm::vec4& row, const glm::vec3& p) {
    return ((mulRounded(row.x, p.x) + mulRounded(row.y, p.y)) + mulRounded(row.z, p.z)) + row.w;
}

/// The caster triangle as the fragment stage sees it (twin of penumbraDsmTriangle).
struct DsmTriangle {
    glm::vec3 n[3];
    float d[3];
    bool valid = false;
};

inline DsmTriangle dsmTriangle(const glm::vec4 clip[3], const float depth[3]) {
    DsmTriangle t;
    const glm::vec3 h0(clip[0].x, clip[0].y, clip[0].w), h1(clip[1].x, clip[1].y, clip[1].w), h2(clip[2].x, clip[2].y, clip[2].w);
    t.n[0] = dsmCross(h1, h2);
    t.n[1] = dsmCross(h2, h0);
    t.n[2] = dsmCross(h0, h1);
    const float det = (mulRounded(h0.x, t.n[0].x) + mulRounded(h0.y, t.n[0].y)) + mulRounded(h0.z, t.n[0].z);
    if (!(det != 0.0f) || nonFinite(det)) return t;
    if (det < 0.0f)
        for (auto& n : t.n) n = -n;
    for (int i = 0; i < 3; ++i) t.d[i] = depth[i];
    t.valid = true;
    return t;
}

/// NDC of window coordinate s (twin of penumbraDsmNdc): s * (2 / R) - 1.
inline float dsmNdc(float s, float scale) { return mulRounded(s, scale) - 1.0f; }

}  // namespace detail

/// Window position of sub-sample j of texel (x, y) (twin of penumbraDsmSubSample).
inline glm::vec2 dsmSubSample(const DsmSetup& setup, uint32_t x, uint32_t y, uint32_t j) {
    const glm::vec2 o = setup.pattern_offsets[static_cast<size_t>(detail::dsmPattern(x, y)) * setup.samples + j];
    return glm::vec2(static_cast<float>(x) + o.x, static_cast<float>(y) + o.y);
}

/// CPU twin of the GPU's rasterization (count + scan + scatter + sort): every sub-sample's list of
/// caster fragments, sorted by (z, triangle). Throws penumbra::Error for bad opacity, indices out of
/// range or non-finite positions, naming the value.
inline DsmFragmentsCpu buildDsmFragmentsCpu(const DsmSetup& setup, const DsmLight& light,
                                            const std::vector<glm::vec3>& positions,
                                            const std::vector<uint32_t>& indices, const DsmOpacity& opacity) {
    PENUMBRA_CHECK(indices.size() % 3 == 0, "buildDsmFragmentsCpu: index count ", indices.size(), " is not a multiple of 3");
    const size_t triangles = indices.size() / 3;
    PENUMBRA_CHECK(opacity.per_vertex.empty() || opacity.per_vertex.size() == positions.size(),
                   "buildDsmFragmentsCpu: per_vertex opacity has ", opacity.per_vertex.size(), " entries for ",
                   positions.size(), " vertices");
    PENUMBRA_CHECK(opacity.per_triangle.empty() || opacity.per_triangle.size() == triangles,
                   "buildDsmFragmentsCpu: per_triangle opacity has ", opacity.per_triangle.size(), " entries for ",
                   triangles, " triangles");
    PENUMBRA_CHECK(!opacity.hook || opacity.hook_attribute.size() == positions.size(),
                   "buildDsmFragmentsCpu: the opacity hook has ", opacity.hook_attribute.size(),
                   " hook_attribute entries for ", positions.size(), " vertices");
    detail::checkOpacity(opacity.mesh, "the mesh", 0);
    for (size_t i = 0; i < opacity.per_triangle.size(); ++i) detail::checkOpacity(opacity.per_triangle[i], "triangle", i);
    for (size_t i = 0; i < opacity.per_vertex.size(); ++i) detail::checkOpacity(opacity.per_vertex[i], "vertex", i);
    for (size_t i = 0; i < indices.size(); ++i)
        PENUMBRA_CHECK(indices[i] < positions.size(), "buildDsmFragmentsCpu: index ", indices[i], " at ", i,
                       " is out of range (", positions.size(), " vertices)");
    for (size_t i = 0; i < positions.size(); ++i)
        for (int c = 0; c < 3; ++c)
            PENUMBRA_CHECK(std::isfinite(positions[i][c]), "buildDsmFragmentsCpu: position ", i, " has coordinate ",
                           positions[i][c]);

    const DsmParams params = deepShadowMapParams(setup, light, opacity);
    const uint32_t R = setup.resolution, S = setup.samples;
    const float scale = params.numbers.x;
    struct Raw {
        uint32_t key;
        DsmFragment f;
    };
    std::vector<Raw> raw;
    for (size_t t = 0; t < triangles; ++t) {
        glm::vec4 clip[3];
        float depth[3];
        for (int i = 0; i < 3; ++i) {
            const glm::vec3& p = positions[indices[3 * t + i]];
            clip[i] = detail::transformPointDsm(params.light_view_projection, p);
            depth[i] = detail::dsmDepth(params.depth_row, p);
        }
        const detail::DsmTriangle tri = detail::dsmTriangle(clip, depth);
        if (!tri.valid) continue;
        // Texel range: the projected bounding box when every vertex is in front of the light's eye
        // plane, else the whole map (the edge functions stay exact either way).
        uint32_t x0 = 0, y0 = 0, x1 = R - 1, y1 = R - 1;
        if (clip[0].w > 0.0f && clip[1].w > 0.0f && clip[2].w > 0.0f) {
            float lo_x = std::numeric_limits<float>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
            for (int i = 0; i < 3; ++i) {
                const float wx = (clip[i].x / clip[i].w * 0.5f + 0.5f) * static_cast<float>(R);
                const float wy = (clip[i].y / clip[i].w * 0.5f + 0.5f) * static_cast<float>(R);
                lo_x = std::min(lo_x, wx), hi_x = std::max(hi_x, wx), lo_y = std::min(lo_y, wy), hi_y = std::max(hi_y, wy);
            }
            if (!(hi_x >= -1.0f && lo_x <= R + 1.0f && hi_y >= -1.0f && lo_y <= R + 1.0f)) continue;
            x0 = static_cast<uint32_t>(std::max(0.0f, std::floor(lo_x) - 1.0f));
            y0 = static_cast<uint32_t>(std::max(0.0f, std::floor(lo_y) - 1.0f));
            x1 = static_cast<uint32_t>(std::min(static_cast<float>(R - 1), std::floor(hi_x) + 1.0f));
            y1 = static_cast<uint32_t>(std::min(static_cast<float>(R - 1), std::floor(hi_y) + 1.0f));
        }
        const bool interpolated = opacity.hook || !opacity.per_vertex.empty();
        const std::vector<glm::vec3>& attribute = opacity.hook ? opacity.hook_attribute : opacity.per_vertex;
        glm::vec3 a_vertex[3];
        for (int i = 0; i < 3; ++i) a_vertex[i] = interpolated ? attribute[indices[3 * t + i]] : glm::vec3(0.0f);
        const glm::vec3 a_flat = opacity.per_triangle.empty() ? opacity.mesh : opacity.per_triangle[t];
        for (uint32_t y = y0; y <= y1; ++y)
            for (uint32_t x = x0; x <= x1; ++x)
                for (uint32_t j = 0; j < S; ++j) {
                    const glm::vec2 s = dsmSubSample(setup, x, y, j);
                    const float px = detail::dsmNdc(s.x, scale), py = detail::dsmNdc(s.y, scale);
                    const float e0 = detail::dsmEdge(tri.n[0], px, py), e1 = detail::dsmEdge(tri.n[1], px, py),
                                e2 = detail::dsmEdge(tri.n[2], px, py);
                    if (!detail::dsmEdgeCovers(e0, tri.n[0]) || !detail::dsmEdgeCovers(e1, tri.n[1]) ||
                        !detail::dsmEdgeCovers(e2, tri.n[2]) || !((e0 + e1) + e2 > 0.0f))
                        continue;
                    Raw r;
                    r.key = (y * R + x) * S + j;
                    r.f.z = detail::dsmInterpolate(e0, e1, e2, tri.d[0], tri.d[1], tri.d[2]);
                    r.f.triangle = static_cast<uint32_t>(t);
                    if (!interpolated) {
                        r.f.alpha = a_flat;
                    } else {
                        for (int c = 0; c < 3; ++c)
                            r.f.alpha[c] = detail::dsmInterpolate(e0, e1, e2, a_vertex[0][c], a_vertex[1][c], a_vertex[2][c]);
                        if (opacity.hook) r.f.alpha = detail::dsmClampOpacity(opacity.hook(static_cast<uint32_t>(t), r.f.alpha));
                    }
                    raw.push_back(r);
                }
    }
    std::sort(raw.begin(), raw.end(), [](const Raw& a, const Raw& b) {
        if (a.key != b.key) return a.key < b.key;
        if (a.f.z != b.f.z) return a.f.z < b.f.z;
        return a.f.triangle < b.f.triangle;
    });
    DsmFragmentsCpu out;
    const size_t lists = static_cast<size_t>(R) * R * S;
    out.offsets.assign(lists + 1, 0);
    for (const Raw& r : raw) ++out.offsets[r.key + 1];
    for (size_t k = 0; k < lists; ++k) out.offsets[k + 1] += out.offsets[k];
    out.fragments.reserve(raw.size());
    for (const Raw& r : raw) out.fragments.push_back(r.f);
    return out;
}

namespace detail {

/// The streaming greedy L-infinity compressor (lokovic2000 §3.3) with a free segment start, C
/// channels, float, fixed operation order (twin of compress.glsl).
///
/// lokovic2000 fixes each segment's origin at the previous window's middle slope. Here a segment
/// starts anywhere in the interval W of values its predecessor's window allows at their shared
/// depth: PENUMBRA_DSM_CANDIDATES start values spread over W (at (k + 1/2) / K of it), each with
/// its own slope window. The segment lasts while, in every channel, some candidate's window is
/// open; when it closes, each channel keeps the candidate whose window is widest (ties: the lowest),
/// which fixes the predecessor's end, and the next W is that candidate's window at the last
/// accepted depth. A vertical step (and the first vertex) puts candidate 0 at the drop's exact
/// value and keeps it while its window is open, the others spread over [V - eps, V + eps] below the
/// previous value. Every segment's slope lies in a window its inputs allow, so the output is within
/// eps_inner (plus rounding) of the input and non-increasing; 8-12 % fewer vertices than the fixed
/// origin on hairball and grass (docs/design.md).
template <int C>
class DsmCompressor {
public:
    static constexpr int K = PENUMBRA_DSM_CANDIDATES;
    static_assert(K >= 2 && (K & (K - 1)) == 0, "PENUMBRA_DSM_CANDIDATES: a power of two >= 2");

    /// eps_inner: dsmInnerTolerance of the tolerance (DsmParams::numbers.w). Output values are the
    /// stored ones (16-bit, decoded); a texel's vertex count is padded to even with a copy of its
    /// last vertex (so that its 16-bit values fill whole 32-bit words on the GPU).
    explicit DsmCompressor(float eps_inner, std::vector<float>* out) : eps_(eps_inner), out_(out) {}

    void add(float z, const float* v) {
        if (!open_) {
            start(z, v, v, v);
            return;
        }
        for (int attempt = 0; attempt < 2; ++attempt) {
            const bool same = z == zs_;
            const float dz = z - zs_;
            float nlo[K][C], nhi[K][C];
            bool nalive[K][C];
            bool open = true;
            for (int c = 0; c < C; ++c) {
                bool any = false;
                for (int k = 0; k < K; ++k) {
                    nlo[k][c] = lo_[k][c];
                    nhi[k][c] = hi_[k][c];
                    nalive[k][c] = false;
                    if (!alive_[k][c]) continue;
                    if (same) {
                        nalive[k][c] = std::fabs(cand_[k][c] - v[c]) <= eps_;
                    } else {
                        nlo[k][c] = std::max(lo_[k][c], (std::max(v[c] - eps_, 0.0f) - cand_[k][c]) / dz);
                        nhi[k][c] = std::min(hi_[k][c], ((v[c] + eps_) - cand_[k][c]) / dz);
                        nalive[k][c] = nlo[k][c] <= nhi[k][c];
                    }
                    any = any || nalive[k][c];
                }
                open = open && any;
            }
            if (open) {
                for (int c = 0; c < C; ++c)
                    for (int k = 0; k < K; ++k) {
                        lo_[k][c] = nlo[k][c];
                        hi_[k][c] = nhi[k][c];
                        alive_[k][c] = nalive[k][c];
                    }
                z_last_ = z;
                return;
            }
            if (z_last_ == zs_) {  // nothing accepted since the start: a vertical step (or rounding)
                emitStart();
                float wlo[C], whi[C], exact[C];  // exact: the step's value (a channel still within keeps its own)
                for (int c = 0; c < C; ++c) {
                    exact[c] = std::fabs(vo_[c] - v[c]) <= eps_ ? vo_[c] : std::min(vo_[c], v[c]);
                    whi[c] = std::min(v[c] + eps_, vo_[c]);
                    wlo[c] = std::min(std::max(v[c] - eps_, 0.0f), whi[c]);
                }
                start(z, wlo, whi, exact);
                return;
            }
            close();
        }
    }

    /// Ends the last segment and pads to an even vertex count.
    void finish() {
        if (open_) {
            emitStart();
            if (z_last_ != zs_) {
                const float dz = z_last_ - zs_;
                for (int c = 0; c < C; ++c) {
                    const int b = best_[c];
                    const float m = mulRounded(lo_[b][c], 0.5f) + mulRounded(hi_[b][c], 0.5f);
                    vo_[c] = std::max(0.0f, vo_[c] + mulRounded(m, dz));
                }
                zo_ = z_last_;
                emit();
            }
        }
        if (count_ & 1u) emit();
        open_ = false;
    }

    uint32_t count() const { return count_; }

private:
    /// A segment starting at depth z with values in [wlo, whi] per channel: K candidates at
    /// (k + 1/2) / K of the interval or, with `exact` (a vertical step, the first vertex), candidate 0
    /// at that value (preferred while its window stays open) and the others at k / K (K is a power
    /// of two: the fractions are exact, no division whose rounding a driver might change).
    void start(float z, const float* wlo, const float* whi, const float* exact = nullptr) {
        zs_ = z;
        z_last_ = z;
        exact_ = exact != nullptr;
        for (int c = 0; c < C; ++c) {
            const float span = whi[c] - wlo[c];
            for (int k = 0; k < K; ++k) {
                const float f = (static_cast<float>(k) + (exact ? 0.0f : 0.5f)) * (1.0f / static_cast<float>(K));
                cand_[k][c] = exact && k == 0 ? exact[c] : std::min(wlo[c] + mulRounded(span, f), whi[c]);
                lo_[k][c] = -std::numeric_limits<float>::infinity();
                hi_[k][c] = 0.0f;
                alive_[k][c] = true;
            }
        }
        open_ = true;
    }

    /// Picks each channel's candidate (the exact one while open, else the widest open window, ties:
    /// the lowest index) and emits the segment's start vertex with those values (vo_, zo_ hold it).
    void emitStart() {
        for (int c = 0; c < C; ++c) {
            int b = -1;
            float width = 0.0f;
            for (int k = 0; k < K; ++k) {
                if (!alive_[k][c] || (exact_ && b == 0)) continue;
                const float w = hi_[k][c] - lo_[k][c];
                if (b < 0 || w > width) b = k, width = w;
            }
            best_[c] = b;
            vo_[c] = cand_[b][c];
        }
        zo_ = zs_;
        emit();
    }

    /// Ends the segment at the last accepted depth; the next starts there within the chosen
    /// candidates' windows.
    void close() {
        emitStart();
        const float dz = z_last_ - zs_;
        float wlo[C], whi[C];
        for (int c = 0; c < C; ++c) {
            const int b = best_[c];
            wlo[c] = std::max(0.0f, vo_[c] + mulRounded(lo_[b][c], dz));
            whi[c] = std::max(wlo[c], vo_[c] + mulRounded(hi_[b][c], dz));
        }
        start(z_last_, wlo, whi);
    }

    void emit() {
        ++count_;
        if (!out_) return;
        out_->push_back(zo_);
        for (int c = 0; c < C; ++c) out_->push_back(dsmDecode(dsmQuantize(vo_[c])));
    }

    float eps_;
    std::vector<float>* out_;
    bool open_ = false, exact_ = false;
    float zs_ = 0.0f, z_last_ = 0.0f, zo_ = 0.0f;
    float vo_[C] = {};
    float cand_[K][C] = {}, lo_[K][C] = {}, hi_[K][C] = {};
    bool alive_[K][C] = {};
    int best_[C] = {};
    uint32_t count_ = 0;
};

/// Passes every vertex to the compressor, or stores it when eps_inner < 0 (uncompressed).
template <int C>
struct DsmSink {
    DsmCompressor<C>* compressor = nullptr;
    std::vector<float>* raw = nullptr;
    void add(float z, const float* v) {
        if (compressor) {
            compressor->add(z, v);
        } else {
            raw->push_back(z);
            for (int c = 0; c < C; ++c) raw->push_back(v[c]);
        }
    }
};

/// exp(-x) for x >= 0 with + and * only (twin of penumbraDsmExpNeg): x = n ln2 + r, |r| <= ln2/2,
/// a degree-7 Taylor polynomial of e^-r (relative error < 3e-7), scaled by 2^-n; 0 beyond x = 87.
inline float dsmExpNeg(float x) {
    if (!(x < 87.0f)) return 0.0f;
    if (!(x > 0.0f)) return 1.0f;
    const float n = std::floor(mulRounded(x, 1.44269504f) + 0.5f);
    const float r = (x - mulRounded(n, 0.693145752f)) - mulRounded(n, 1.42860677e-06f);
    float p = -1.98412698e-04f;  // -1/5040
    p = mulRounded(p, r) + 1.38888889e-03f;
    p = mulRounded(p, r) - 8.33333333e-03f;
    p = mulRounded(p, r) + 4.16666667e-02f;
    p = mulRounded(p, r) - 1.66666667e-01f;
    p = mulRounded(p, r) + 0.5f;
    p = mulRounded(p, r) - 1.0f;
    p = mulRounded(p, r) + 1.0f;
    return std::ldexp(p, -static_cast<int>(n));
}

/// The part of a sub-sample's ray inside the medium box (twin of penumbraDsmMediumSpan): the ray
/// through NDC (px, py) from the light (two points from the inverse view-projection), clipped to the
/// box (slabs) and to light depth >= 0; depths of entry and exit and sigma_t x path length per unit
/// of light depth.
struct DsmMediumSpan {
    float z_in = 0, z_out = 0, sigma_k = 0;
    bool valid = false;
};

inline glm::vec4 dsmTransform4(const glm::mat4& m, const glm::vec4& p) {
    glm::vec4 c;
    for (int r = 0; r < 4; ++r)
        c[r] = ((mulRounded(m[0][r], p.x) + mulRounded(m[1][r], p.y)) + mulRounded(m[2][r], p.z)) + mulRounded(m[3][r], p.w);
    return c;
}

inline DsmMediumSpan dsmMediumSpan(const DsmParams& params, float px, float py) {
    DsmMediumSpan span;
    const glm::vec4 h0 = dsmTransform4(params.inverse_view_projection, glm::vec4(px, py, -1.0f, 1.0f));
    const glm::vec4 h1 = dsmTransform4(params.inverse_view_projection, glm::vec4(px, py, 1.0f, 1.0f));
    const glm::vec3 p0(h0.x / h0.w, h0.y / h0.w, h0.z / h0.w), p1(h1.x / h1.w, h1.y / h1.w, h1.z / h1.w);
    const float d0 = dsmDepth(params.depth_row, p0), d1 = dsmDepth(params.depth_row, p1);
    const float dd = d1 - d0;
    if (!(dd > 0.0f) || nonFinite(dd)) return span;
    const glm::vec3 D = p1 - p0;
    float tmin = -d0 / dd, tmax = std::numeric_limits<float>::infinity();
    for (int a = 0; a < 3; ++a) {
        const float lo = params.medium_lo[a], hi = params.medium_hi[a];
        if (D[a] == 0.0f) {
            if (p0[a] < lo || p0[a] > hi) return span;
            continue;
        }
        const float t1 = (lo - p0[a]) / D[a], t2 = (hi - p0[a]) / D[a];
        tmin = std::max(tmin, std::min(t1, t2));
        tmax = std::min(tmax, std::max(t1, t2));
    }
    if (!(tmin < tmax)) return span;
    span.z_in = d0 + mulRounded(tmin, dd);
    span.z_out = d0 + mulRounded(tmax, dd);
    const float len = std::sqrt((mulRounded(D.x, D.x) + mulRounded(D.y, D.y)) + mulRounded(D.z, D.z));
    span.sigma_k = mulRounded(params.medium_lo.w, len / dd);
    span.valid = span.z_in < span.z_out && !nonFinite(span.z_in) && !nonFinite(span.z_out) && !nonFinite(span.sigma_k);
    return span;
}

/// The merge of one texel (§5.1; twin of merge.comp.glsl): a binary heap over the contributing
/// sub-sample lists keyed by (z of the list's next event, list); a surface event subtracts the
/// sub-sample's old contribution, V -= (w_j T_j alpha) m_j(z), T_j *= (1 - alpha); with a medium
/// (`medium` non-null, flags.z = K > 0) each list also has K + 1 medium vertices whose events
/// change the slope S of V (V is linear between events: V(z) = V(z_prev) + S (z - z_prev), S
/// clamped to <= 0). One vertical step per distinct z; a kink (slope change) gives one vertex.
template <int C, typename Sink>
void dsmMergeTexel(const DsmSetup& setup, const DsmFragmentsCpu& frags, uint32_t x, uint32_t y, Sink& sink,
                   const DsmParams* medium = nullptr) {
    const int R = static_cast<int>(setup.resolution);
    const int reach = static_cast<int>(setup.reach);
    const uint32_t S = setup.samples;
    const float radius = setup.options.filter_radius;
    const float inv_r2 = 1.0f / (radius * radius);
    const uint32_t K = medium ? medium->flags.z : 0u;
    const float inf = std::numeric_limits<float>::infinity();
    struct List {
        uint32_t cur, end;
        float w;
        float t[C];
        float zin, zspan, sk, seg_z0, seg_m0, seg_s, zm;
        uint32_t mi;
    };
    std::vector<List> lists;
    lists.reserve(setup.merge_lists);
    float total = 0.0f;
    for (int dy = -reach; dy <= reach; ++dy)
        for (int dx = -reach; dx <= reach; ++dx) {
            const int nx = static_cast<int>(x) + dx, ny = static_cast<int>(y) + dy;
            if (nx < 0 || ny < 0 || nx >= R || ny >= R) continue;
            const uint32_t pattern = dsmPattern(static_cast<uint32_t>(nx), static_cast<uint32_t>(ny));
            for (uint32_t j = 0; j < S; ++j) {
                const glm::vec2 o = setup.pattern_offsets[static_cast<size_t>(pattern) * S + j];
                const float rx = (static_cast<float>(dx) + o.x) - 0.5f, ry = (static_cast<float>(dy) + o.y) - 0.5f;
                float w;
                if (setup.options.filter == DsmFilter::Box) {
                    if (!(std::fabs(rx) <= radius && std::fabs(ry) <= radius)) continue;
                    w = 1.0f;
                } else {
                    const float q = mulRounded(mulRounded(rx, rx) + mulRounded(ry, ry), inv_r2);
                    if (!(q <= 1.0f)) continue;
                    w = setup.gauss_table[std::min<uint32_t>(kDsmGaussTable - 1, static_cast<uint32_t>(mulRounded(q, static_cast<float>(kDsmGaussTable))))];
                }
                total = total + w;
                const uint32_t k = (static_cast<uint32_t>(ny) * static_cast<uint32_t>(R) + static_cast<uint32_t>(nx)) * S + j;
                List l;
                l.cur = frags.offsets[k];
                l.end = frags.offsets[k + 1];
                l.w = w;
                for (int c = 0; c < C; ++c) l.t[c] = 1.0f;
                l.zin = l.zspan = l.sk = l.seg_z0 = l.seg_s = 0.0f;
                l.seg_m0 = 1.0f;
                l.zm = inf;
                l.mi = K + 1;
                if (K > 0) {
                    const glm::vec2 sp = glm::vec2(static_cast<float>(nx) + o.x, static_cast<float>(ny) + o.y);
                    const DsmMediumSpan span = dsmMediumSpan(*medium, dsmNdc(sp.x, medium->numbers.x), dsmNdc(sp.y, medium->numbers.x));
                    if (span.valid) {
                        l.zin = span.z_in;
                        l.zspan = span.z_out - span.z_in;
                        l.sk = span.sigma_k;
                        l.mi = 0;
                        l.zm = span.z_in;
                    }
                }
                lists.push_back(l);
            }
        }
    if (lists.empty()) return;
    for (List& l : lists) l.w = l.w / total;
    auto mediumZ = [&](const List& l, uint32_t i) {
        return l.zin + mulRounded(l.zspan, static_cast<float>(i) / static_cast<float>(K));
    };
    auto nextZ = [&](const List& l) {
        const float zf = l.cur < l.end ? frags.fragments[l.cur].z : inf;
        return std::min(zf, l.zm);
    };
    std::vector<uint32_t> heap;
    heap.reserve(lists.size());
    auto less = [&](uint32_t a, uint32_t b) {
        const float za = nextZ(lists[a]), zb = nextZ(lists[b]);
        return za < zb || (za == zb && a < b);
    };
    auto siftDown = [&](size_t i) {
        for (;;) {
            size_t m = i;
            const size_t l = 2 * i + 1, r = l + 1;
            if (l < heap.size() && less(heap[l], heap[m])) m = l;
            if (r < heap.size() && less(heap[r], heap[m])) m = r;
            if (m == i) return;
            std::swap(heap[i], heap[m]);
            i = m;
        }
    };
    for (uint32_t i = 0; i < lists.size(); ++i)
        if (lists[i].cur < lists[i].end || lists[i].zm < inf) heap.push_back(i);
    for (size_t i = heap.size() / 2; i-- > 0;) siftDown(i);
    float v[C], before[C], slope[C];
    for (int c = 0; c < C; ++c) v[c] = 1.0f, before[c] = 1.0f, slope[c] = 0.0f;
    bool pending = false, kink = false, have_prev = false;
    float z_group = 0.0f, z_prev = 0.0f;
    auto flush = [&]() {
        bool step = false;
        for (int c = 0; c < C; ++c) step = step || v[c] != before[c];
        if (step) {
            sink.add(z_group, before);
            sink.add(z_group, v);
        } else if (kink) {
            sink.add(z_group, v);
        }
    };
    while (!heap.empty()) {
        const uint32_t li = heap[0];
        List& l = lists[li];
        const float zf = l.cur < l.end ? frags.fragments[l.cur].z : inf;
        const bool medium_event = l.zm <= zf;
        const float z = medium_event ? l.zm : zf;
        if (pending && z != z_group) {
            flush();
            pending = false;
        }
        if (!pending) {
            pending = true;
            kink = false;
            z_group = z;
            if (K > 0 && have_prev) {  // V is linear between events
                for (int c = 0; c < C; ++c) {
                    const float e = v[c] + mulRounded(std::min(slope[c], 0.0f), z - z_prev);
                    v[c] = std::max(0.0f, std::min(v[c], e));
                }
            }
            z_prev = z;
            have_prev = true;
            for (int c = 0; c < C; ++c) before[c] = v[c];
        }
        bool alive = false;
        if (medium_event) {
            const float m = dsmExpNeg(mulRounded(l.sk, l.zm - l.zin));
            float s_new = 0.0f;
            if (l.mi < K) {
                const float z_next = mediumZ(l, l.mi + 1);
                const float m_next = dsmExpNeg(mulRounded(l.sk, z_next - l.zin));
                const float dz = z_next - l.zm;
                s_new = dz > 0.0f ? (m_next - m) / dz : 0.0f;
            }
            for (int c = 0; c < C; ++c) {
                slope[c] = slope[c] + mulRounded(mulRounded(l.w, l.t[c]), s_new - l.seg_s);
                alive = alive || l.t[c] > 0.0f;
            }
            l.seg_z0 = l.zm;
            l.seg_m0 = m;
            l.seg_s = s_new;
            ++l.mi;
            l.zm = l.mi <= K ? mediumZ(l, l.mi) : inf;
            kink = true;
        } else {
            const DsmFragment& f = frags.fragments[l.cur];
            const float mz = l.mi == 0 ? 1.0f : l.seg_m0 + mulRounded(l.seg_s, z - l.seg_z0);
            for (int c = 0; c < C; ++c) {
                const float a = f.alpha[c];
                const float wta = mulRounded(mulRounded(l.w, l.t[c]), a);
                v[c] = std::max(0.0f, v[c] - mulRounded(wta, mz));
                slope[c] = slope[c] - mulRounded(wta, l.seg_s);
                l.t[c] = mulRounded(l.t[c], 1.0f - a);
                alive = alive || l.t[c] > 0.0f;
            }
            if (l.seg_s != 0.0f) kink = true;
            ++l.cur;
        }
        // A list whose surfaces are opaque adds nothing more (V - 0 == V, S + 0 == S): dropping it
        // leaves every value unchanged.
        if ((l.cur < l.end || l.zm < inf) && alive) {
            siftDown(0);
        } else {
            heap[0] = heap.back();
            heap.pop_back();
            if (!heap.empty()) siftDown(0);
        }
    }
    if (pending) flush();
}

/// Left (V(z-)) and right (V(z+)) limits of one texel's function at z; `i` is the caller's cursor
/// (vertices before it have depth < z); floats per vertex F = 1 + C.
template <int C>
inline void dsmLimits(const float* verts, uint32_t n, uint32_t& i, float z, float* left, float* right) {
    constexpr int F = 1 + C;
    while (i < n && verts[F * i] < z) ++i;
    uint32_t j = i;
    while (j < n && verts[F * j] == z) ++j;
    for (int c = 0; c < C; ++c) {
        if (n == 0) {
            left[c] = right[c] = 1.0f;
            continue;
        }
        if (i < n && verts[F * i] == z) {
            left[c] = verts[F * i + 1 + c];
            right[c] = verts[F * (j - 1) + 1 + c];
        } else if (i == 0) {
            left[c] = right[c] = verts[1 + c];
        } else if (i == n) {
            left[c] = right[c] = verts[F * (n - 1) + 1 + c];
        } else {
            const float* a = verts + F * (i - 1);
            const float* b = verts + F * i;
            const float t = (z - a[0]) / (b[0] - a[0]);
            left[c] = right[c] = a[1 + c] + mulRounded(b[1 + c] - a[1 + c], t);
        }
    }
}

/// Average of the 4 child functions (a mip texel, §5.3), fed to the sink in depth order (twin of
/// mip.comp.glsl). Vertices at the union of the children's depths: the average of the left limits,
/// then the average of the right limits where it differs.
template <int C, typename Sink>
void dsmAverageTexel(const float* const verts[4], const uint32_t counts[4], Sink& sink) {
    constexpr int F = 1 + C;
    uint32_t cursor[4] = {0, 0, 0, 0};
    uint32_t next[4] = {0, 0, 0, 0};  // first vertex not yet passed by the union sweep
    for (;;) {
        float z = std::numeric_limits<float>::infinity();
        bool any = false;
        for (int k = 0; k < 4; ++k)
            if (next[k] < counts[k]) {
                z = std::min(z, verts[k][F * next[k]]);
                any = true;
            }
        if (!any) return;
        float l[4][C], r[4][C];
        for (int k = 0; k < 4; ++k) {
            dsmLimits<C>(verts[k], counts[k], cursor[k], z, l[k], r[k]);
            while (next[k] < counts[k] && verts[k][F * next[k]] <= z) ++next[k];
        }
        float left[C], right[C];
        bool step = false;
        for (int c = 0; c < C; ++c) {
            left[c] = mulRounded((l[0][c] + l[1][c]) + (l[2][c] + l[3][c]), 0.25f);
            right[c] = mulRounded((r[0][c] + r[1][c]) + (r[2][c] + r[3][c]), 0.25f);
            step = step || right[c] != left[c];
        }
        sink.add(z, left);
        if (step) sink.add(z, right);
    }
}

template <int C>
DsmMapCpu buildDsmMapCpuChannels(const DsmSetup& setup, const DsmFragmentsCpu& frags, bool compress,
                                 const DsmParams* medium) {
    constexpr int F = 1 + C;
    DsmMapCpu map;
    map.resolution = setup.resolution;
    map.channels = C;
    map.levels = setup.levels;
    map.packed = compress;
    map.resolution_of = setup.level_resolution;
    map.offsets.resize(setup.levels);
    map.vertices.resize(setup.levels);
    for (uint32_t level = 0; level < setup.levels; ++level) {
        const uint32_t r = setup.level_resolution[level];
        const float tol = setup.levelTolerance(level);
        const float eps_inner = dsmInnerTolerance(tol);
        std::vector<uint32_t>& offsets = map.offsets[level];
        std::vector<float>& out = map.vertices[level];
        offsets.assign(static_cast<size_t>(r) * r + 1, 0);
        for (uint32_t y = 0; y < r; ++y)
            for (uint32_t x = 0; x < r; ++x) {
                const size_t before = out.size();
                DsmCompressor<C> compressor(eps_inner, &out);
                DsmSink<C> sink;
                if (compress) sink.compressor = &compressor; else sink.raw = &out;
                if (level == 0) {
                    dsmMergeTexel<C>(setup, frags, x, y, sink, medium);
                } else {
                    const uint32_t rc = setup.level_resolution[level - 1];
                    const std::vector<uint32_t>& co = map.offsets[level - 1];
                    const std::vector<float>& cv = map.vertices[level - 1];
                    const float* verts[4];
                    uint32_t counts[4];
                    for (int k = 0; k < 4; ++k) {
                        const uint32_t t = (2 * y + (k >> 1)) * rc + (2 * x + (k & 1));
                        verts[k] = cv.data() + static_cast<size_t>(F) * co[t];
                        counts[k] = co[t + 1] - co[t];
                    }
                    dsmAverageTexel<C>(verts, counts, sink);
                }
                compressor.finish();
                offsets[static_cast<size_t>(y) * r + x + 1] = static_cast<uint32_t>((out.size()) / F);
                (void)before;
            }
    }
    return map;
}

}  // namespace detail

/// CPU twin of the whole GPU build after rasterization: merge + compression of level 0, then the
/// mip chain. compress = false keeps every merged vertex (the input the compression is checked
/// against; levels > 0 then average uncompressed children: the exact averages).
inline DsmMapCpu buildDsmMapCpu(const DsmSetup& setup, const DsmFragmentsCpu& frags, bool compress = true) {
    return setup.channels == 3 ? detail::buildDsmMapCpuChannels<3>(setup, frags, compress, nullptr)
                               : detail::buildDsmMapCpuChannels<1>(setup, frags, compress, nullptr);
}

/// The same with a participating medium along the light's rays (DsmMedium; inactive = the above).
inline DsmMapCpu buildDsmMapCpu(const DsmSetup& setup, const DsmFragmentsCpu& frags, bool compress, const DsmLight& light,
                                const DsmMedium& medium) {
    checkDsmMedium(medium);
    if (!medium.active()) return buildDsmMapCpu(setup, frags, compress);
    const DsmParams params = deepShadowMapParams(setup, light, DsmOpacity{}, 0, medium);
    return setup.channels == 3 ? detail::buildDsmMapCpuChannels<3>(setup, frags, compress, &params)
                               : detail::buildDsmMapCpuChannels<1>(setup, frags, compress, &params);
}

/// V(z) of texel `texel` of `level`, channel c: left-continuous (a receiver exactly at a step's depth
/// gets the value before it), V = first vertex's value before it, last after it, 1 for an empty
/// texel; binary search (twin of penumbraDsmVisibility).
inline float dsmVisibility(const DsmMapCpu& map, uint32_t level, uint32_t texel, float z, uint32_t c = 0) {
    const uint32_t F = 1 + map.channels;
    const uint32_t first = map.offsets[level][texel], last = map.offsets[level][texel + 1];
    if (first == last) return 1.0f;
    const float* v = map.vertices[level].data();
    // First vertex with depth >= z.
    uint32_t lo = first, hi = last;
    while (lo < hi) {
        const uint32_t mid = lo + (hi - lo) / 2;
        if (v[F * mid] < z) lo = mid + 1; else hi = mid;
    }
    if (lo == first) return v[F * first + 1 + c];
    if (lo == last) return v[F * (last - 1) + 1 + c];
    const float* a = v + F * (lo - 1);
    const float* b = v + F * lo;
    if (b[0] == z) return b[1 + c];
    const float t = (z - a[0]) / (b[0] - a[0]);
    return a[1 + c] + detail::mulRounded(b[1 + c] - a[1 + c], t);
}

/// Light-image position (u, v in [0, 1] over the map) and light depth of a world point.
struct DsmCoord {
    float u = 0, v = 0, depth = 0;
    bool inside = false;  ///< in front of the light and inside the map
};


inline DsmCoord dsmCoord(const DsmParams& params, const glm::vec3& p) {
    const glm::vec4 c = detail::transformPointDsm(params.light_view_projection, p);
    DsmCoord r;
    r.depth = detail::dsmDepth(params.depth_row, p);
    if (!(c.w > 0.0f)) return r;
    r.u = detail::mulRounded(c.x / c.w, 0.5f) + 0.5f;
    r.v = detail::mulRounded(c.y / c.w, 0.5f) + 0.5f;
    r.inside = r.u >= 0.0f && r.u <= 1.0f && r.v >= 0.0f && r.v <= 1.0f;
    return r;
}

/// Bilinear lookup at level `level` (texel centres at (i + 0.5) / r, clamped at the border).
inline float dsmLookupLevel(const DsmMapCpu& map, uint32_t level, float u, float v, float z, uint32_t c = 0) {
    const uint32_t r = map.resolution_of[level];
    const float fx = detail::mulRounded(u, static_cast<float>(r)) - 0.5f, fy = detail::mulRounded(v, static_cast<float>(r)) - 0.5f;
    const float bx = std::floor(fx), by = std::floor(fy);
    const float tx = fx - bx, ty = fy - by;
    const int ix = static_cast<int>(bx), iy = static_cast<int>(by);
    auto at = [&](int x, int y) {
        x = std::clamp(x, 0, static_cast<int>(r) - 1);
        y = std::clamp(y, 0, static_cast<int>(r) - 1);
        return dsmVisibility(map, level, static_cast<uint32_t>(y) * r + static_cast<uint32_t>(x), z, c);
    };
    const float a = at(ix, iy), b = at(ix + 1, iy), d = at(ix, iy + 1), e = at(ix + 1, iy + 1);
    const float top = a + detail::mulRounded(b - a, tx), bottom = d + detail::mulRounded(e - d, tx);
    return top + detail::mulRounded(bottom - top, ty);
}

/// Trilinear lookup: lod = log2 of the footprint in level-0 texels, clamped to the chain.
inline float dsmLookup(const DsmMapCpu& map, float u, float v, float z, float lod, uint32_t c = 0) {
    const float l = std::clamp(lod, 0.0f, static_cast<float>(map.levels - 1));
    const uint32_t l0 = static_cast<uint32_t>(l);
    const uint32_t l1 = std::min(l0 + 1, map.levels - 1);
    const float t = l - static_cast<float>(l0);
    const float a = dsmLookupLevel(map, l0, u, v, z, c);
    if (t == 0.0f || l1 == l0) return a;
    const float b = dsmLookupLevel(map, l1, u, v, z, c);
    return a + detail::mulRounded(b - a, t);
}

/// L-infinity distance between two texel functions over every depth, both one-sided limits at
/// every vertex of either (in double: the check of the compression bound).
inline double dsmFunctionDistance(const float* a, uint32_t na, const float* b, uint32_t nb, uint32_t channels) {
    const uint32_t F = 1 + channels;
    auto limits = [F](const float* v, uint32_t n, double z, uint32_t c, double& left, double& right) {
        if (n == 0) {
            left = right = 1.0;
            return;
        }
        uint32_t i = 0, j = n;  // i: first vertex with depth >= z; j: first with depth > z
        for (uint32_t hi = n; i < hi;) {
            const uint32_t mid = i + (hi - i) / 2;
            if (v[F * mid] < z) i = mid + 1; else hi = mid;
        }
        for (uint32_t lo = i; lo < j;) {
            const uint32_t mid = lo + (j - lo) / 2;
            if (v[F * mid] <= z) lo = mid + 1; else j = mid;
        }
        if (i < n && v[F * i] == z) {
            left = v[F * i + 1 + c];
            right = v[F * (j - 1) + 1 + c];
        } else if (i == 0) {
            left = right = v[1 + c];
        } else if (i == n) {
            left = right = v[F * (n - 1) + 1 + c];
        } else {
            const double za = v[F * (i - 1)], zb = v[F * i];
            const double t = (z - za) / (zb - za);
            left = right = v[F * (i - 1) + 1 + c] + (static_cast<double>(v[F * i + 1 + c]) - v[F * (i - 1) + 1 + c]) * t;
        }
    };
    double worst = 0.0;
    for (int side = 0; side < 2; ++side) {
        const float* v = side ? b : a;
        const uint32_t n = side ? nb : na;
        for (uint32_t i = 0; i < n; ++i)
            for (uint32_t c = 0; c < channels; ++c) {
                double al, ar, bl, br;
                limits(a, na, v[F * i], c, al, ar);
                limits(b, nb, v[F * i], c, bl, br);
                worst = std::max(worst, std::max(std::fabs(al - bl), std::fabs(ar - br)));
            }
    }
    if (na == 0 || nb == 0) {  // before any vertex: 1 vs the first value
        for (uint32_t c = 0; c < channels; ++c) {
            const double va = na ? a[1 + c] : 1.0, vb = nb ? b[1 + c] : 1.0;
            worst = std::max(worst, std::fabs(va - vb));
        }
    }
    return worst;
}

namespace detail {

/// One depth of a texel function: its value just before (left) and just after (right) z (a step
/// has several vertices at one z: the first is the left limit, the last the right one).
struct DsmDepthLimits {
    double z, left, right;
};

/// A convex polygon in the plane of (b, c): a line's values at z0 (b) and z1 (c). Half-plane
/// clipping keeps the lines whose value at relative depth s = (z - z0) / (z1 - z0) lies in
/// [lo, hi]; `slack` widens every test (rounding may only keep lines, never drop them).
struct DsmLinePolygon {
    std::vector<glm::dvec2> points, scratch;
    void rectangle(double b_lo, double b_hi, double c_lo, double c_hi) {
        points.assign({{b_lo, c_lo}, {b_hi, c_lo}, {b_hi, c_hi}, {b_lo, c_hi}});
    }
    bool empty() const { return points.empty(); }
    /// Keeps the points where (1 - s) b + s c >= lo (sign = 1) or <= hi (sign = -1).
    void clipSide(double s, double bound, double sign, double slack) {
        scratch.clear();
        const size_t n = points.size();
        for (size_t i = 0; i < n; ++i) {
            const glm::dvec2& p = points[i];
            const glm::dvec2& q = points[(i + 1) % n];
            const double dp = sign * ((1.0 - s) * p.x + s * p.y - bound) + slack;
            const double dq = sign * ((1.0 - s) * q.x + s * q.y - bound) + slack;
            if (dp >= 0.0) scratch.push_back(p);
            if ((dp >= 0.0) != (dq >= 0.0)) scratch.push_back(p + (q - p) * (dp / (dp - dq)));
        }
        points.swap(scratch);
    }
    void clip(double s, double lo, double hi, double slack) {
        clipSide(s, lo, 1.0, slack);
        if (!points.empty()) clipSide(s, hi, -1.0, slack);
    }
};

}  // namespace detail

/// A lower bound on the vertices of any function (dsmVisibility's meaning: linear between
/// vertices, constant before the first and after the last, vertical steps as vertices sharing a
/// depth) within `eps` of texel function (v, n) at every depth, both one-sided limits (channel
/// `channel` of `channels`). No compressor, whatever depths it puts its vertices at, can do with
/// fewer; the benchmark sets it beside DsmCompressor's count (BM_DsmCompressionTable).
///
/// The argument (after Imai & Iri's tube view of L-infinity approximation): the function's eps-tube
/// over [first depth, last depth] must be crossed by the pieces of the approximation, one line
/// each. Greedily, the first line reaches at most z_1 = the farthest any line within the tube from
/// the start gets; any piece that goes on past z_k crosses the tube's cross-section at z_k, so it
/// ends at most where the farthest line from that whole cross-section ends (z_{k+1}). The k-th
/// piece of any approximation therefore ends at or before z_k, and covering the tube takes at least
/// as many pieces as the greedy. Reaches are computed in double with the tube widened by 1e-9
/// (rounding can only lengthen them, which keeps the bound a bound). v vertices make v - 1
/// segments and two constant ends, which are horizontal: the greedy is also run with a horizontal
/// first piece and up to the start of the longest horizontal last piece, and the smallest of the
/// four cases is taken. A step higher than 2 eps needs a vertical segment of its own at its depth
/// (one vertex more each). Loose where the function bends often within its tube: the greedy lets
/// each line start anywhere on the previous one's end cross-section (tests/deep_shadow_map_test.cpp
/// checks it on known optima and against arbitrary approximations). Throws penumbra::Error for
/// eps < 0 or not finite, or channel >= channels; (v, n) as dsmFunctionDistance's (finite values).
inline uint32_t dsmVerticesLowerBound(const float* v, uint32_t n, uint32_t channels, uint32_t channel, double eps) {
    PENUMBRA_CHECK(std::isfinite(eps) && eps >= 0.0, "penumbra::dsmVerticesLowerBound: eps = ", eps,
                   " must be finite and >= 0");
    PENUMBRA_CHECK(channel < channels, "penumbra::dsmVerticesLowerBound: channel = ", channel, " must be < channels = ", channels);
    if (n == 0) return 0;
    const uint32_t F = 1 + channels;
    const double e = eps + 1e-9, slack = 1e-12;
    std::vector<detail::DsmDepthLimits> d;
    for (uint32_t i = 0; i < n; ++i) {
        const double z = v[F * i], value = v[F * i + 1 + channel];
        if (!d.empty() && d.back().z == z) d.back().right = value;
        else d.push_back({z, value, value});
    }
    // The whole function within eps of one constant: one horizontal line (0 vertices when it is 1,
    // else 1) — the four cases below assume at least two pieces.
    double all_lo = -1e300, all_hi = 1e300;
    for (const detail::DsmDepthLimits& q : d) {
        all_lo = std::max({all_lo, q.left - e, q.right - e});
        all_hi = std::min({all_hi, q.left + e, q.right + e});
    }
    if (all_lo <= all_hi) return all_lo <= 1.0 && 1.0 <= all_hi ? 0u : 1u;
    const double z_first = d.front().z, z_last = d.back().z;
    // The tube's value at depth t (between depth entries: linear from the right limit of one to the
    // left limit of the next).
    const auto valueAt = [&](size_t k, double t) {  // t in (d[k - 1].z, d[k].z)
        const double a = d[k - 1].right, b = d[k].left;
        return a + (b - a) * ((t - d[k - 1].z) / (d[k].z - d[k - 1].z));
    };
    detail::DsmLinePolygon poly, probe;
    // The farthest depth any line from cross-section [lo, hi] at z0 reaches within the tube
    // (horizontal: constant lines only). next: the first entry deeper than z0. Returns the reach and
    // sets `at_entry` to the entry it ends exactly at (or d.size() when it ends between entries).
    const auto reach = [&](double z0, double lo, double hi, size_t next, bool horizontal, size_t& at_entry) {
        at_entry = d.size();
        if (next >= d.size()) return std::numeric_limits<double>::infinity();
        if (horizontal) {
            for (size_t k = next; k < d.size(); ++k) {
                const double l_lo = std::max(lo, d[k].left - e), l_hi = std::min(hi, d[k].left + e);
                if (l_lo > l_hi) {
                    // Ends between entries k - 1 and k (or at z0's own segment): the tube's value
                    // moves linearly from the previous depth's right limit to d[k].left.
                    double t_lo = k > next ? d[k - 1].z : z0, t_hi = d[k].z;
                    for (int it = 0; it < 60; ++it) {
                        const double t = 0.5 * (t_lo + t_hi);
                        const double w = k > 0 ? valueAt(k, t) : d[k].left;
                        (std::max(lo, w - e) <= std::min(hi, w + e) ? t_lo : t_hi) = t;
                    }
                    return t_hi;
                }
                lo = std::max(l_lo, d[k].right - e);
                hi = std::min(l_hi, d[k].right + e);
                if (lo > hi) {
                    at_entry = k;
                    return d[k].z;
                }
            }
            return std::numeric_limits<double>::infinity();
        }
        const double z1 = d[next].z;
        poly.rectangle(lo, hi, d[next].left - e, d[next].left + e);  // every such line reaches z1
        poly.clip(1.0, d[next].right - e, d[next].right + e, slack);
        if (poly.empty()) {
            at_entry = next;
            return z1;
        }
        for (size_t k = next + 1; k < d.size(); ++k) {
            const double s = (d[k].z - z0) / (z1 - z0);
            probe.points = poly.points;
            probe.clip(s, d[k].left - e, d[k].left + e, slack);
            if (probe.empty()) {
                double t_lo = d[k - 1].z, t_hi = d[k].z;
                for (int it = 0; it < 60; ++it) {
                    const double t = 0.5 * (t_lo + t_hi), w = valueAt(k, t);
                    probe.points = poly.points;
                    probe.clip((t - z0) / (z1 - z0), w - e, w + e, slack);
                    (probe.empty() ? t_hi : t_lo) = t;
                }
                return t_hi;
            }
            probe.clip(s, d[k].right - e, d[k].right + e, slack);
            if (probe.empty()) {
                at_entry = k;
                return d[k].z;
            }
            poly.points.swap(probe.points);
        }
        return std::numeric_limits<double>::infinity();
    };
    // Pieces needed to cover [z_first, target] (0 when target <= z_first); kNever: a horizontal
    // first piece cannot start.
    constexpr uint32_t kNever = 1u << 30;
    const auto pieces = [&](double target, bool horizontal_first) {
        double z0 = z_first, lo = d[0].right - e, hi = d[0].right + e;
        if (horizontal_first) {
            // The constant before the first vertex: within eps of the function before z_first
            // (its first value) and just after it.
            lo = std::max(lo, d[0].left - e);
            hi = std::min(hi, d[0].left + e);
            if (lo > hi) return kNever;
        }
        if (target <= z_first) return 0u;
        size_t next = 1;
        for (uint32_t count = 1;; ++count) {
            size_t at = 0;
            const double t = reach(z0, lo, hi, next, horizontal_first && count == 1, at);
            if (t >= target) return count;
            // The next piece crosses the cross-section just past t (the right limit at an entry).
            if (at < d.size()) {
                z0 = d[at].z;
                lo = d[at].right - e;
                hi = d[at].right + e;
                next = at + 1;
            } else {
                size_t k = next;
                while (k < d.size() && d[k].z <= t) ++k;
                if (k >= d.size()) return count;  // t rounded onto the last entry
                if (k > 0 && d[k - 1].z == t) {
                    z0 = t;
                    lo = d[k - 1].right - e;
                    hi = d[k - 1].right + e;
                } else {
                    const double w = valueAt(k, t);
                    z0 = t;
                    lo = w - e;
                    hi = w + e;
                }
                next = k;
            }
        }
    };
    // The earliest start z_h of a horizontal last piece (a constant within the tube from z_h on;
    // at z_h itself only the right limit counts). Rounded down where it falls between entries: a
    // smaller z_h only weakens the bound.
    double z_h = z_last;
    {
        double lo = d.back().right - e, hi = d.back().right + e;
        for (size_t k = d.size() - 1; k > 0; --k) {
            const double l_lo = std::max(lo, d[k].left - e), l_hi = std::min(hi, d[k].left + e);
            if (l_lo > l_hi) break;  // starts at d[k].z, after its step
            const double r_lo = std::max(l_lo, d[k - 1].right - e), r_hi = std::min(l_hi, d[k - 1].right + e);
            if (r_lo > r_hi) {
                // Starts inside (d[k - 1].z, d[k].z): the tube there is linear, so a constant that
                // fits at t and at d[k].z fits between.
                double t_lo = d[k - 1].z, t_hi = d[k].z;  // fits from t_hi, not from t_lo
                for (int it = 0; it < 60; ++it) {
                    const double t = 0.5 * (t_lo + t_hi), w = valueAt(k, t);
                    (std::max(l_lo, w - e) <= std::min(l_hi, w + e) ? t_hi : t_lo) = t;
                }
                z_h = t_lo;
                break;
            }
            lo = r_lo;
            hi = r_hi;
            z_h = d[k - 1].z;
        }
    }
    // A step higher than 2 eps cannot be passed by a continuous approximation: it needs a vertical
    // segment of its own, at that very depth (its two vertices share it).
    uint32_t jumps = 0;
    for (const detail::DsmDepthLimits& q : d) jumps += std::fabs(q.left - q.right) > 2.0 * e;
    // v vertices make v - 1 segments, `jumps` of them (at least) vertical, and two horizontal
    // constant ends; the non-vertical pieces inside [z_first, z_last] are at least the greedy's.
    // Which ends lie inside:
    const uint32_t neither = pieces(z_last, false) + 1;  // none: segments cover it all
    const uint32_t first = pieces(z_last, true);          // the first end, then segments
    const uint32_t last = pieces(z_h, false) + 1;         // segments cover [z_first, z_h]
    const uint32_t both = pieces(z_h, true);              // the first end, then segments up to z_h
    return std::min({neither, first, last, both}) + jumps;
}

/// A function is non-increasing in V and non-decreasing in z (every channel).
inline bool dsmMonotone(const float* v, uint32_t n, uint32_t channels) {
    const uint32_t F = 1 + channels;
    for (uint32_t i = 1; i < n; ++i) {
        if (!(v[F * i] >= v[F * (i - 1)])) return false;
        for (uint32_t c = 0; c < channels; ++c)
            if (!(v[F * i + 1 + c] <= v[F * (i - 1) + 1 + c]) || v[F * i + 1 + c] < 0.0f) return false;
    }
    return true;
}

}  // namespace penumbra

#endif
