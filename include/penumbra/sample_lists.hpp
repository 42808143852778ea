// penumbra — view-sample lists per light texel (sintorn2008 §3, §3.1, §4.3, Fig. 2, 3, 9): the
// GL-free part — pure setup, the rules, the CPU twin. The GL executor (SampleListBuilder, its
// bindings, buffers and GL state contract) is penumbra/gl/sample_lists.hpp.
//
// Integration summary
//   input:    view samples, either vec4 world positions (w == 0 marks "no sample") or the view's
//             depth + inverse view-projection; world normals for the light-facing test; the light's
//             view-projection and grid W x H; the light as vec4 (w = 1: xyz = position; w = 0:
//             xyz = direction towards the light).
//   produces: per light texel a list of the samples that project into it (§3.1): counts (list
//             lengths), offsets (exclusive scan of counts), list positions (vec4) and sample ids
//             (uint) stored structure-of-arrays by slot; per sample its slot (or NO_SLOT) and its
//             texel (or REJECTED + reason); counters by rejection reason; the §4.3 fitted light
//             frustum (a SampleListsFrustum block: on the GPU it never leaves the GPU) and the
//             Fig. 9 list statistics.
//   GLSL:     penumbra/sample_lists/sample_lists.glsl walks a texel's list from the integrator's
//             own light pass and penumbra/sample_lists/shadow_bits.glsl addresses the packed
//             per-sample shadow bits; both read the integrator's buffers through hooks. Walk long
//             lists in blocks over several passes (penumbraSampleListsBlock, §3.1 multi-pass):
//             llvmpipe ends an invocation's loops after 65 535 iterations in total. The shadow
//             bits (shadowBitsBytes) are the integrator's buffer; it clears them before its pass.
//   passes:   optional §4.3 fit (fit.comp.glsl reduces keys, fit_resolve.comp.glsl turns them into
//             the frustum block), 1 count (count.comp.glsl: classify, atomicAdd on the texel counter
//             = local index), 2 exclusive scan of the W*H counters (the scan block), 3 scatter
//             (scatter.comp.glsl: slot = offset + local index), optional statistics (Fig. 9).
//   CPU twin: buildSampleListsCpu (counting sort), fitLightFrustumCpu / lightFrustumFitFromHeader,
//             sampleListStatisticsCpu compute the identical structure, frustum and statistics.
//
// Pure setup: sampleListsSetup() validates the grid and the sample count and says how many bytes
// every buffer needs; sampleListsParams() builds the 256-byte uniform block (throwing on bad
// numbers; the executor's per-frame path uses the non-throwing detail::sampleListsParamsValid);
// sampleListsFrustum() is the frustum block of an unfitted build; shadowBitsBytes() sizes the
// shadow bits. planSampleLists() is the whole build as data (FidelityFX-style): the constants
// blocks, the programs (key + defines) and the ordered steps — uploads, clears, dispatches with
// their grids and bindings by role, the scan as an embedded ScanPlan, barriers — so an engine
// with its own RHI records the passes itself ("The plan" below; the GL executor walks the same
// steps).
//
// Rules (identical on GPU and CPU)
//   Projection: t = T * (p, 1) with T = bias * light view-projection (T maps the frustum to
//     0 <= x, y, z <= w), float32, fixed operation order, no FMA (GLSL `precise`; the host
//     blocks contraction with detail::mulRounded), so the texel of every sample agrees bit for
//     bit with the CPU twin on drivers with correctly rounded float32 add/mul/div (llvmpipe).
//   Borders: u = t.x / t.w; 0 <= u <= 1 is inside (closed), x = min(floor(u * W), W - 1): a
//     sample exactly on an inner texel border belongs to the texel with the larger index, u == 1
//     to the last texel; u < 0 or u > 1 (as t.x < 0 or t.x > t.w) is Outside. Same for v and H.
//     t.w <= 0 (behind a point light's eye plane) or a non-finite t is Outside too.
//   Near/far: with LightDepthRange::MinusOneToOne (GL clip z in [-w, w], GLM's default) or
//     ZeroToOne, a sample whose light depth lies outside [near, far] (closed) is rejected as
//     Depth; LightDepthRange::Unclipped keeps them (only the side planes and w > 0 count).
//   Rejection precedence: Background (position w == 0 / depth == 1.0), NonFinite (NaN/Inf in the
//     position, or in the normal when culling), Outside, Depth, BackFacing (!(dot(n, to_light)
//     > 0), to_light = light.xyz - p, or light.xyz for a directional light; Fig. 2). Each
//     rejected sample is counted once, under the first reason that applies.
//   Order within a list: on the GPU the local index comes from atomics, so the order of samples
//     inside one list is nondeterministic; the CPU twin orders every list by sample id. Compare
//     structures modulo order (sampleListsDifference): same counts and offsets, the same set of
//     (id, position) per list, and every sample's slot pointing at its own id.
//   Sample ids: the buffer index, or y * view width + x for the depth input (row 0 = bottom).
//
#ifndef PENUMBRA_SAMPLE_LISTS_HPP
#define PENUMBRA_SAMPLE_LISTS_HPP

#include "penumbra/detail/shared.hpp"
// The shared header lives with the shaders (STYLE.md habit 2): found on the include path when the
// shaders/ directory is on it, else next to this header in the source tree.
#if defined(__has_include) && __has_include(<penumbra/sample_lists/sample_lists_shared.h>)
#include <penumbra/sample_lists/sample_lists_shared.h>
#else
#include "../../shaders/penumbra/sample_lists/sample_lists_shared.h"
#endif

#include "penumbra/detail/dispatch.hpp"
#include "penumbra/detail/float_ops.hpp"
#include "penumbra/error.hpp"
#include "penumbra/scan.hpp"
#include "penumbra/shader_defines.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

using SampleListsParams = shared::PenumbraSampleListsParams;
using SampleListsHeader = shared::PenumbraSampleListsHeader;

using SampleListsFrustum = shared::PenumbraSampleListsFrustum;

// What the shaders assume about the shared structs.
static_assert(sizeof(SampleListsParams) == 256, "PenumbraSampleListsParams must be 256 bytes (std140 == std430)");
static_assert(offsetof(SampleListsParams, light_view_projection) == 64 && offsetof(SampleListsParams, view_inverse) == 128 &&
                  offsetof(SampleListsParams, light) == 192 && offsetof(SampleListsParams, grid) == 208 &&
                  offsetof(SampleListsParams, view) == 224 && offsetof(SampleListsParams, fit) == 240,
              "PenumbraSampleListsParams member offsets must match GLSL std140");
static_assert(sizeof(SampleListsFrustum) == 240 && offsetof(SampleListsFrustum, view_projection) == 64 &&
                  offsetof(SampleListsFrustum, crop) == 128 && offsetof(SampleListsFrustum, box) == 192 &&
                  offsetof(SampleListsFrustum, extent) == 208 && offsetof(SampleListsFrustum, info) == 224,
              "PenumbraSampleListsFrustum member offsets must match GLSL std140");
static_assert(sizeof(SampleListsHeader) == 4 * PENUMBRA_SAMPLE_LISTS_HEADER_WORDS,
              "PenumbraSampleListsHeader size must match PENUMBRA_SAMPLE_LISTS_HEADER_WORDS");
static_assert(offsetof(SampleListsHeader, rejected) == 16 &&
                  offsetof(SampleListsHeader, fit_min_u) == 4 * PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MIN_WORD &&
                  offsetof(SampleListsHeader, fit_max_u) == 4 * PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MAX_WORD &&
                  offsetof(SampleListsHeader, occupied_lists) == 4 * PENUMBRA_SAMPLE_LISTS_HEADER_STATISTICS_WORD,
              "PenumbraSampleListsHeader word offsets must match the PENUMBRA_SAMPLE_LISTS_HEADER_* constants");
static_assert(PENUMBRA_SAMPLE_LISTS_REASON_COUNT <= 8, "rejected[] holds 8 reasons");

inline constexpr uint32_t kSampleListsGroupSize = PENUMBRA_SAMPLE_LISTS_GROUP_SIZE;
inline constexpr uint32_t kSampleListsMaxGridSide = PENUMBRA_SAMPLE_LISTS_MAX_GRID_SIDE;
/// Largest sample count: ids and slots stay below every sentinel and group arithmetic in 32 bits.
inline constexpr uint32_t kSampleListsMaxSamples = 0xFFFFFF00u;
/// sample_slots[id] of a rejected sample.
inline constexpr uint32_t kSampleListsNoSlot = PENUMBRA_SAMPLE_LISTS_NO_SLOT;
/// sample_texels[id] >= kSampleListsRejected: rejected, reason = value - kSampleListsRejected.
inline constexpr uint32_t kSampleListsRejected = PENUMBRA_SAMPLE_LISTS_REJECTED;
inline constexpr uint32_t kSampleListsReasonCount = PENUMBRA_SAMPLE_LISTS_REASON_COUNT;
/// Largest bits-per-sample of the packed shadow state (§4.2 uses 128-1024 light samples).
inline constexpr uint32_t kSampleListsMaxShadowBits = 65536u;

/// Why a sample is not in any list (precedence = declaration order, see "Rules").
enum class SampleRejection : uint32_t {
    Background = PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND,
    NonFinite = PENUMBRA_SAMPLE_LISTS_REASON_NON_FINITE,
    Outside = PENUMBRA_SAMPLE_LISTS_REASON_OUTSIDE,
    Depth = PENUMBRA_SAMPLE_LISTS_REASON_DEPTH,
    BackFacing = PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING,
};

inline const char* sampleRejectionName(SampleRejection reason) {
    switch (reason) {
        case SampleRejection::Background: return "background";
        case SampleRejection::NonFinite: return "non_finite";
        case SampleRejection::Outside: return "outside";
        case SampleRejection::Depth: return "depth";
        case SampleRejection::BackFacing: return "back_facing";
    }
    return "unknown";
}

/// Clip-space depth convention of the light's projection, and whether near/far reject samples.
enum class LightDepthRange {
    MinusOneToOne,  ///< GL / GLM default: -w <= z <= w inside
    ZeroToOne,      ///< GLM_FORCE_DEPTH_ZERO_TO_ONE / glClipControl: 0 <= z <= w inside
    Unclipped,      ///< near and far planes ignored (only the side planes and w > 0 count)
};

/// The light the samples are projected for.
struct SampleListsLight {
    glm::mat4 view_projection{1.0f};    ///< light view-projection (clip space; depth per LightDepthRange)
    glm::vec4 light{0.0f, 0.0f, 0.0f, 1.0f};  ///< w = 1: xyz = position; w = 0: xyz = direction towards the light
};

/// Value-initialised = defaults.
struct SampleListsOptions {
    bool cull_back_facing = true;  ///< Fig. 2: only light-front-facing samples enter the lists
    LightDepthRange depth_range = LightDepthRange::MinusOneToOne;
};

/// The view a depth input comes from.
struct SampleListsView {
    uint32_t width = 0, height = 0;            ///< view (depth texture) size; sample count = width * height
    glm::mat4 inverse_view_projection{1.0f};   ///< clip -> world of the view camera
    bool depth_zero_to_one = false;            ///< view clip z in [0, w] (else GL's [-w, w])
};

/// Value-initialised = defaults.
struct LightFrustumFitOptions {
    float margin = 1e-3f;      ///< added on every side, as a fraction of the box size
    float min_margin = 1e-4f;  ///< at least this much (light-texture units of the original frustum):
                               ///< covers float rounding and a degenerate (single-point) box
    bool fit_far = true;       ///< move the far plane to the farthest sample (+ margin); never beyond the original
};

/// Per-build switches (of the executor's build() and of planSampleLists). Value-initialised =
/// lists only, the light's own frustum.
struct SampleListsBuild {
    bool fit_frustum = false;  ///< §4.3 on the GPU before the lists (writes the frustum block)
    LightFrustumFitOptions fit;
    bool statistics = false;   ///< Fig. 9 words of the header after the lists
};

// ---------------------------------------------------------------------------------------------
// Setup (pure C++)

/// Sizes and dispatch grids of one build. Every *_bytes is what the caller's buffer must hold.
struct SampleListsSetup {
    uint32_t grid_width = 0, grid_height = 0;  ///< light grid W x H
    uint32_t sample_count = 0;                 ///< view samples (ids 0 .. sample_count - 1)
    uint32_t lists = 0;                        ///< W * H
    size_t counts_bytes = 0;          ///< uint[W*H]: list lengths (pass-1 counters)
    size_t offsets_bytes = 0;         ///< uint[W*H]: list offsets (exclusive scan of counts)
    size_t list_positions_bytes = 0;  ///< vec4[sample_count] by slot (worst case: all accepted)
    size_t list_ids_bytes = 0;        ///< uint[sample_count] by slot
    size_t sample_slots_bytes = 0;    ///< uint[sample_count] by sample id
    size_t sample_texels_bytes = 0;   ///< uint[sample_count] by sample id
    size_t header_bytes = 0;          ///< SampleListsHeader
    detail::DispatchGrid sample_groups;  ///< one invocation per sample (count, scatter, fit)
    detail::DispatchGrid list_groups;    ///< one invocation per list (statistics)
};

/// Validates the grid (1 <= W, H <= kSampleListsMaxGridSide) and the sample count
/// (<= kSampleListsMaxSamples); throws penumbra::Error naming the bad value.
inline SampleListsSetup sampleListsSetup(uint32_t grid_width, uint32_t grid_height, uint64_t sample_count) {
    PENUMBRA_CHECK(grid_width >= 1 && grid_width <= kSampleListsMaxGridSide,
                   "penumbra::sampleListsSetup: grid width ", grid_width, " is outside [1, ", kSampleListsMaxGridSide, "]");
    PENUMBRA_CHECK(grid_height >= 1 && grid_height <= kSampleListsMaxGridSide,
                   "penumbra::sampleListsSetup: grid height ", grid_height, " is outside [1, ", kSampleListsMaxGridSide, "]");
    PENUMBRA_CHECK(sample_count <= kSampleListsMaxSamples, "penumbra::sampleListsSetup: sample count ", sample_count,
                   " exceeds ", kSampleListsMaxSamples);
    SampleListsSetup s;
    s.grid_width = grid_width;
    s.grid_height = grid_height;
    s.sample_count = static_cast<uint32_t>(sample_count);
    s.lists = grid_width * grid_height;
    s.counts_bytes = s.offsets_bytes = size_t(s.lists) * 4;
    s.list_positions_bytes = size_t(sample_count) * 16;
    s.list_ids_bytes = s.sample_slots_bytes = s.sample_texels_bytes = size_t(sample_count) * 4;
    s.header_bytes = sizeof(SampleListsHeader);
    s.sample_groups = detail::foldDispatch(detail::divUp(sample_count, kSampleListsGroupSize));
    s.list_groups = detail::foldDispatch(detail::divUp(s.lists, kSampleListsGroupSize));
    return s;
}

/// bias * view_projection: world -> homogeneous light texture space, where the frustum is
/// 0 <= x, y, z <= w (z is biased like x and y unless the projection is ZeroToOne already).
/// The bias is written out in float (twin of penumbraSampleListsBias in fit_resolve.comp.glsl), so
/// the host, the GPU fit and the CPU twin compute the very same matrix.
inline glm::mat4 lightTextureMatrix(const glm::mat4& view_projection, LightDepthRange range) {
    glm::mat4 t;
    for (int j = 0; j < 4; ++j) {
        const glm::vec4& m = view_projection[j];
        const float w = detail::mulRounded(m[3], 0.5f);
        t[j][0] = detail::mulRounded(m[0], 0.5f) + w;
        t[j][1] = detail::mulRounded(m[1], 0.5f) + w;
        t[j][2] = range == LightDepthRange::ZeroToOne ? m[2] : detail::mulRounded(m[2], 0.5f) + w;
        t[j][3] = m[3];
    }
    return t;
}

namespace detail {

inline bool finiteMatrix(const glm::mat4& m) {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            if (!std::isfinite(m[c][r])) return false;
        }
    }
    return true;
}

/// The checks of sampleListsParams without the messages: what a per-frame call (which must not
/// throw) tests before building the block.
inline bool sampleListsParamsValid(const SampleListsSetup& setup, const SampleListsLight& light,
                                   const SampleListsView* view, const LightFrustumFitOptions& fit) {
    const glm::vec4& l = light.light;
    if (!finiteMatrix(light.view_projection) || !std::isfinite(l.x) || !std::isfinite(l.y) || !std::isfinite(l.z)) {
        return false;
    }
    if (!(l.w == 0.0f || l.w == 1.0f) || (l.w == 0.0f && l.x == 0.0f && l.y == 0.0f && l.z == 0.0f)) return false;
    if (setup.lists == 0) return false;
    if (!(std::isfinite(fit.margin) && fit.margin >= 0.0f && std::isfinite(fit.min_margin) && fit.min_margin > 0.0f)) {
        return false;
    }
    if (view) {
        if (view->width < 1 || view->height < 1 || uint64_t(view->width) * view->height != setup.sample_count) {
            return false;
        }
        if (!finiteMatrix(view->inverse_view_projection)) return false;
    }
    return true;
}

/// The block itself, inputs assumed valid (sampleListsParamsValid).
inline SampleListsParams makeSampleListsParams(const SampleListsSetup& setup, const SampleListsLight& light,
                                               const SampleListsOptions& options, const SampleListsView* view,
                                               const LightFrustumFitOptions& fit) {
    SampleListsParams p{};
    p.light_texture = lightTextureMatrix(light.view_projection, options.depth_range);
    p.light_view_projection = light.view_projection;
    p.view_inverse = glm::mat4(1.0f);
    p.light = light.light;
    uint32_t flags = 0;
    if (options.cull_back_facing) flags |= PENUMBRA_SAMPLE_LISTS_FLAG_CULL_BACK_FACING;
    if (options.depth_range != LightDepthRange::Unclipped) flags |= PENUMBRA_SAMPLE_LISTS_FLAG_CLIP_DEPTH;
    if (options.depth_range == LightDepthRange::ZeroToOne) flags |= PENUMBRA_SAMPLE_LISTS_FLAG_LIGHT_DEPTH_ZERO_TO_ONE;
    if (fit.fit_far) flags |= PENUMBRA_SAMPLE_LISTS_FLAG_FIT_FAR;
    const uint32_t groups = static_cast<uint32_t>(divUp(setup.sample_count, kSampleListsGroupSize));
    p.view = glm::uvec4(0u, 0u, groups, 0u);
    if (view) {
        p.view_inverse = view->inverse_view_projection;
        p.view = glm::uvec4(view->width, view->height, groups, 0u);
        if (view->depth_zero_to_one) flags |= PENUMBRA_SAMPLE_LISTS_FLAG_VIEW_DEPTH_ZERO_TO_ONE;
    }
    p.grid = glm::uvec4(setup.grid_width, setup.grid_height, setup.sample_count, flags);
    p.fit = glm::vec4(fit.margin, fit.min_margin, 0.0f, 0.0f);
    return p;
}

}  // namespace detail

/// The uniform block of the count/scatter/fit passes (and of the CPU twin). `view` only for the
/// depth input; `fit` only matters to the GPU fit. Throws penumbra::Error for a non-finite matrix
/// or light, a light w other than 0 or 1, a zero light direction, or bad fit margins.
inline SampleListsParams sampleListsParams(const SampleListsSetup& setup, const SampleListsLight& light,
                                           const SampleListsOptions& options = {},
                                           const SampleListsView* view = nullptr,
                                           const LightFrustumFitOptions& fit = {}) {
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 4; ++r) {
            PENUMBRA_CHECK(std::isfinite(light.view_projection[c][r]), "penumbra::sampleListsParams: light view_projection[",
                           c, "][", r, "] = ", light.view_projection[c][r], " is not finite");
        }
    }
    const glm::vec4& l = light.light;
    PENUMBRA_CHECK(std::isfinite(l.x) && std::isfinite(l.y) && std::isfinite(l.z),
                   "penumbra::sampleListsParams: light (", l.x, ", ", l.y, ", ", l.z, ") is not finite");
    PENUMBRA_CHECK(l.w == 0.0f || l.w == 1.0f, "penumbra::sampleListsParams: light.w = ", l.w,
                   " must be 1 (point light) or 0 (directional light)");
    PENUMBRA_CHECK(l.w == 1.0f || l.x != 0.0f || l.y != 0.0f || l.z != 0.0f,
                   "penumbra::sampleListsParams: directional light direction (0, 0, 0) is zero");
    PENUMBRA_CHECK(setup.lists != 0, "penumbra::sampleListsParams: setup is empty (use sampleListsSetup)");
    if (view) {
        PENUMBRA_CHECK(view->width >= 1 && view->height >= 1, "penumbra::sampleListsParams: view size ", view->width,
                       " x ", view->height, " is empty");
        PENUMBRA_CHECK(uint64_t(view->width) * view->height == setup.sample_count, "penumbra::sampleListsParams: view ",
                       view->width, " x ", view->height, " does not match the setup's sample count ",
                       setup.sample_count);
        for (int c = 0; c < 4; ++c) {
            for (int r = 0; r < 4; ++r) {
                PENUMBRA_CHECK(std::isfinite(view->inverse_view_projection[c][r]),
                               "penumbra::sampleListsParams: view inverse_view_projection[", c, "][", r, "] = ",
                               view->inverse_view_projection[c][r], " is not finite");
            }
        }
    }
    PENUMBRA_CHECK(std::isfinite(fit.margin) && fit.margin >= 0.0f && std::isfinite(fit.min_margin) &&
                       fit.min_margin > 0.0f,
                   "penumbra::sampleListsParams: fit margin ", fit.margin, " / min_margin ", fit.min_margin,
                   " must be finite, margin >= 0 and min_margin > 0");
    return detail::makeSampleListsParams(setup, light, options, view, fit);
}

// ---------------------------------------------------------------------------------------------
// Packed shadow bits (§3.1 Storage, §4.2): sizing and addressing, twin of shadow_bits.glsl

/// Bits each slot owns: N rounded up to a power of two for N <= 16 (no slot straddles a word),
/// to a multiple of 32 for N > 16 (word-aligned slots). Throws for N == 0 or N > 65536.
inline uint32_t shadowStrideBits(uint32_t bits_per_sample) {
    PENUMBRA_CHECK(bits_per_sample >= 1 && bits_per_sample <= kSampleListsMaxShadowBits,
                   "penumbra::shadowStrideBits: bits per sample ", bits_per_sample, " is outside [1, ",
                   kSampleListsMaxShadowBits, "]");
    if (bits_per_sample > 16) return (bits_per_sample + 31) / 32 * 32;
    uint32_t stride = 1;
    while (stride < bits_per_sample) stride *= 2;
    return stride;
}

/// uint words for `slots` slots of `bits_per_sample` bits. Throws when a word index would not
/// fit 32 bits (the GLSL addresses words with uint).
inline uint64_t shadowBitsWords(uint64_t slots, uint32_t bits_per_sample) {
    const uint64_t stride = shadowStrideBits(bits_per_sample);
    const uint64_t words = detail::divUp(slots * stride, 32);
    PENUMBRA_CHECK(slots <= kSampleListsMaxSamples && words <= 0x100000000ull, "penumbra::shadowBitsWords: ", slots,
                   " slots x ", stride, " bits need ", words, " words, more than 32-bit indices address");
    return words;
}

inline size_t shadowBitsBytes(uint64_t slots, uint32_t bits_per_sample) {
    return static_cast<size_t>(shadowBitsWords(slots, bits_per_sample) * 4);
}

struct ShadowBitAddress {
    uint64_t word = 0;  ///< index into the uint array
    uint32_t bit = 0;   ///< bit inside that word
};

/// Where bit `bit` (< bits_per_sample) of `slot` lives; same as penumbraSampleListsShadowAddress.
inline ShadowBitAddress shadowBitAddress(uint32_t slot, uint32_t bit, uint32_t bits_per_sample) {
    const uint32_t stride = shadowStrideBits(bits_per_sample);
    PENUMBRA_ASSERT(bit < stride);
    if (stride >= 32) return {uint64_t(slot) * (stride / 32) + (bit >> 5), bit & 31u};
    const uint32_t per_word = 32 / stride;
    return {slot / per_word, (slot % per_word) * stride + bit};
}

// ---------------------------------------------------------------------------------------------
// CPU twin of project.glsl

namespace detail {

/// Order-preserving key (twin of penumbraSampleListsOrderKey): a < b <=> key(a) < key(b).
inline uint32_t orderKey(float f) {
    const uint32_t bits = floatBits(f);
    return (bits & 0x80000000u) ? ~bits : (bits | 0x80000000u);
}

inline float orderKeyValue(uint32_t key) {
    return floatFromBits((key & 0x80000000u) ? (key & 0x7FFFFFFFu) : ~key);
}

/// m * (x, y, z, 1) as ((m0 x + m1 y) + m2 z) + m3 (twin of penumbraSampleListsTransform).
inline glm::vec4 transformPoint(const glm::mat4& m, float x, float y, float z) {
    glm::vec4 c;
    for (int r = 0; r < 4; ++r) {
        float v = mulRounded(m[0][r], x);
        v = v + mulRounded(m[1][r], y);
        v = v + mulRounded(m[2][r], z);
        v = v + m[3][r];
        c[r] = v;
    }
    return c;
}

/// Twin of penumbraSampleListsViewPosition.
inline glm::vec4 viewPosition(const glm::mat4& view_inverse, uint32_t px, uint32_t py, uint32_t width, uint32_t height,
                              float depth, bool depth_zero_to_one) {
    if (depth == 1.0f) return glm::vec4(0.0f);
    const float x = mulRounded((static_cast<float>(px) + 0.5f) / static_cast<float>(width), 2.0f) - 1.0f;
    const float y = mulRounded((static_cast<float>(py) + 0.5f) / static_cast<float>(height), 2.0f) - 1.0f;
    const float z = depth_zero_to_one ? depth : mulRounded(depth, 2.0f) - 1.0f;
    glm::vec4 h;
    for (int r = 0; r < 4; ++r) {
        float v = mulRounded(view_inverse[0][r], x);
        v = v + mulRounded(view_inverse[1][r], y);
        v = v + mulRounded(view_inverse[2][r], z);
        v = v + view_inverse[3][r];
        h[r] = v;
    }
    return glm::vec4(h.x / h.w, h.y / h.w, h.z / h.w, 1.0f);
}

/// Twin of penumbraSampleListsClassify: the list index, or kSampleListsRejected + reason.
inline uint32_t classifySample(const SampleListsParams& params, const glm::vec4& position, const glm::vec3& normal,
                               glm::vec4* t_out = nullptr) {
    if (t_out) *t_out = glm::vec4(0.0f);
    if (position.w == 0.0f) return kSampleListsRejected + PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND;
    const uint32_t flags = params.grid.w;
    const bool cull = (flags & PENUMBRA_SAMPLE_LISTS_FLAG_CULL_BACK_FACING) != 0;
    if (nonFinite(position.x) || nonFinite(position.y) || nonFinite(position.z) ||
        (cull && (nonFinite(normal.x) || nonFinite(normal.y) || nonFinite(normal.z)))) {
        return kSampleListsRejected + PENUMBRA_SAMPLE_LISTS_REASON_NON_FINITE;
    }
    const glm::vec4 t = transformPoint(params.light_texture, position.x, position.y, position.z);
    if (t_out) *t_out = t;
    if (nonFinite(t.x) || nonFinite(t.y) || nonFinite(t.z) || nonFinite(t.w) || !(t.w > 0.0f) ||
        !(t.x >= 0.0f && t.x <= t.w) || !(t.y >= 0.0f && t.y <= t.w)) {
        return kSampleListsRejected + PENUMBRA_SAMPLE_LISTS_REASON_OUTSIDE;
    }
    if ((flags & PENUMBRA_SAMPLE_LISTS_FLAG_CLIP_DEPTH) && !(t.z >= 0.0f && t.z <= t.w)) {
        return kSampleListsRejected + PENUMBRA_SAMPLE_LISTS_REASON_DEPTH;
    }
    if (cull) {
        const glm::vec4& l = params.light;
        const float lx = l.w == 0.0f ? l.x : l.x - position.x;
        const float ly = l.w == 0.0f ? l.y : l.y - position.y;
        const float lz = l.w == 0.0f ? l.z : l.z - position.z;
        float facing = mulRounded(normal.x, lx) + mulRounded(normal.y, ly);
        facing = facing + mulRounded(normal.z, lz);
        if (!(facing > 0.0f)) return kSampleListsRejected + PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING;
    }
    const float gx = (t.x / t.w) * static_cast<float>(params.grid.x);
    const float gy = (t.y / t.w) * static_cast<float>(params.grid.y);
    const uint32_t x = std::min(static_cast<uint32_t>(std::floor(gx)), params.grid.x - 1);
    const uint32_t y = std::min(static_cast<uint32_t>(std::floor(gy)), params.grid.y - 1);
    return y * params.grid.x + x;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// The structure, as the CPU twin builds it and as downloadSampleLists reads it back

struct SampleListsCpu {
    uint32_t grid_width = 0, grid_height = 0;
    std::vector<uint32_t> counts;             ///< [W*H] list lengths
    std::vector<uint32_t> offsets;            ///< [W*H] exclusive scan of counts
    std::vector<glm::vec4> list_positions;    ///< [accepted] by slot, w = 1
    std::vector<uint32_t> list_ids;           ///< [accepted] by slot
    std::vector<uint32_t> sample_slots;       ///< [samples] slot or kSampleListsNoSlot
    std::vector<uint32_t> sample_texels;      ///< [samples] list index or kSampleListsRejected + reason
    SampleListsHeader header{};               ///< accepted and rejected[] (fit / statistics words 0)
};

namespace detail {

// Counting sort (§3.1 with a sequential counter): local index = running count of the texel in
// sample-id order, offsets = exclusive scan (the scan block's CPU twin), slot = offset + index.
template <typename Source>
SampleListsCpu buildSampleListsCpu(const SampleListsSetup& setup, const SampleListsParams& params, Source&& source) {
    SampleListsCpu out;
    out.grid_width = setup.grid_width;
    out.grid_height = setup.grid_height;
    const uint32_t n = setup.sample_count;
    out.counts.assign(setup.lists, 0u);
    out.offsets.assign(setup.lists, 0u);
    out.sample_slots.assign(n, kSampleListsNoSlot);
    out.sample_texels.assign(n, 0u);
    std::vector<glm::vec4> accepted_positions;
    for (uint32_t id = 0; id < n; ++id) {
        glm::vec4 position;
        glm::vec3 normal;
        source(id, position, normal);
        const uint32_t code = classifySample(params, position, normal);
        out.sample_texels[id] = code;
        if (code < kSampleListsRejected) {
            out.sample_slots[id] = out.counts[code]++;
            ++out.header.accepted;
        } else {
            ++out.header.rejected[code - kSampleListsRejected];
        }
    }
    scanCpu(out.counts.data(), out.offsets.data(), out.counts.size(), ScanKind::Exclusive);
    out.list_positions.assign(out.header.accepted, glm::vec4(0.0f));
    out.list_ids.assign(out.header.accepted, 0u);
    for (uint32_t id = 0; id < n; ++id) {
        const uint32_t code = out.sample_texels[id];
        if (code >= kSampleListsRejected) continue;
        glm::vec4 position;
        glm::vec3 normal;
        source(id, position, normal);
        const uint32_t slot = out.offsets[code] + out.sample_slots[id];
        out.sample_slots[id] = slot;
        out.list_positions[slot] = glm::vec4(position.x, position.y, position.z, 1.0f);
        out.list_ids[slot] = id;
    }
    return out;
}

inline void checkCpuNormals(const void* normals, const SampleListsOptions& options, uint32_t n, const char* function) {
    PENUMBRA_CHECK(normals || !options.cull_back_facing || n == 0, "penumbra::", function,
                   ": normals is null but cull_back_facing is on");
}

}  // namespace detail

/// CPU twin, buffer input: positions[sample_count] (w == 0: no sample), normals[sample_count]
/// (xyz; may be null when options.cull_back_facing is false). Lists ordered by sample id.
inline SampleListsCpu buildSampleListsCpu(const SampleListsSetup& setup, const SampleListsLight& light,
                                          const glm::vec4* positions, const glm::vec4* normals,
                                          const SampleListsOptions& options = {}) {
    PENUMBRA_CHECK(positions || setup.sample_count == 0, "penumbra::buildSampleListsCpu: positions is null");
    detail::checkCpuNormals(normals, options, setup.sample_count, "buildSampleListsCpu");
    const SampleListsParams params = sampleListsParams(setup, light, options);
    const bool cull = options.cull_back_facing;
    return detail::buildSampleListsCpu(setup, params, [&](uint32_t id, glm::vec4& p, glm::vec3& n) {
        p = positions[id];
        n = cull ? glm::vec3(normals[id]) : glm::vec3(0.0f);
    });
}

/// CPU twin, depth input: depth[y * width + x] window depths (row 0 = bottom, as GL textures),
/// normals[y * width + x] (xyz; may be null when culling is off).
inline SampleListsCpu buildSampleListsCpu(const SampleListsSetup& setup, const SampleListsLight& light,
                                          const SampleListsView& view, const float* depth, const glm::vec4* normals,
                                          const SampleListsOptions& options = {}) {
    PENUMBRA_CHECK(depth || setup.sample_count == 0, "penumbra::buildSampleListsCpu: depth is null");
    detail::checkCpuNormals(normals, options, setup.sample_count, "buildSampleListsCpu");
    const SampleListsParams params = sampleListsParams(setup, light, options, &view);
    const bool cull = options.cull_back_facing;
    return detail::buildSampleListsCpu(setup, params, [&](uint32_t id, glm::vec4& p, glm::vec3& n) {
        const uint32_t x = id % view.width, y = id / view.width;
        p = detail::viewPosition(params.view_inverse, x, y, view.width, view.height, depth[id], view.depth_zero_to_one);
        n = cull ? glm::vec3(normals[id]) : glm::vec3(0.0f);
    });
}

/// The positions the depth input reconstructs (twin of penumbraSampleListsViewPosition; w = 0 for
/// background), by sample id y * width + x: bit for bit what the GPU's lists hold for a depth build
/// where floats round correctly and never fuse (llvmpipe). Other drivers may differ in the last
/// bits (GLSL allows 2.5 ulp per division): ask the oracle about listedPositions instead.
inline std::vector<glm::vec4> reconstructViewSamples(const SampleListsView& view, const float* depth) {
    std::vector<glm::vec4> out(size_t(view.width) * view.height);
    for (size_t id = 0; id < out.size(); ++id) {
        out[id] = detail::viewPosition(view.inverse_view_projection, uint32_t(id % view.width),
                                       uint32_t(id / view.width), view.width, view.height, depth[id],
                                       view.depth_zero_to_one);
    }
    return out;
}

/// The positions a build tested, by sample id: list_positions[slot] (w = 1) for every sample the
/// lists hold, `fallback[id]` for the others (background, rejected, or a slot whose list_ids entry
/// names another sample: a broken structure, which sampleListsDifference and the invariants
/// report). For a GPU depth build (downloadSampleLists) these are the GPU's own reconstructions:
/// what the oracle must be asked about on any driver. `fallback` has one entry per sample.
inline std::vector<glm::vec4> listedPositions(const SampleListsCpu& lists, const std::vector<glm::vec4>& fallback) {
    std::vector<glm::vec4> out = fallback;
    for (size_t id = 0; id < out.size() && id < lists.sample_slots.size(); ++id) {
        const uint32_t slot = lists.sample_slots[id];
        if (slot == kSampleListsNoSlot || slot >= lists.list_ids.size() || slot >= lists.list_positions.size() ||
            lists.list_ids[slot] != id) {
            continue;
        }
        out[id] = glm::vec4(glm::vec3(lists.list_positions[slot]), 1.0f);
    }
    return out;
}

/// "" when the two structures are equal modulo the order inside each list (see "Rules"), else
/// the first difference found.
inline std::string sampleListsDifference(const SampleListsCpu& a, const SampleListsCpu& b) {
    auto say = [](auto&&... parts) {
        std::ostringstream out;
        (out << ... << parts);
        return out.str();
    };
    if (a.grid_width != b.grid_width || a.grid_height != b.grid_height) {
        return say("grid ", a.grid_width, "x", a.grid_height, " vs ", b.grid_width, "x", b.grid_height);
    }
    if (a.header.accepted != b.header.accepted) return say("accepted ", a.header.accepted, " vs ", b.header.accepted);
    for (uint32_t r = 0; r < 8; ++r) {
        if (a.header.rejected[r] != b.header.rejected[r]) {
            return say("rejected[", r, "] ", a.header.rejected[r], " vs ", b.header.rejected[r]);
        }
    }
    const size_t lists = size_t(a.grid_width) * a.grid_height;
    if (a.counts.size() != lists || b.counts.size() != lists || a.offsets.size() != lists || b.offsets.size() != lists) {
        return "counts/offsets sizes differ from W*H";
    }
    for (size_t i = 0; i < lists; ++i) {
        if (a.counts[i] != b.counts[i]) return say("counts[", i, "] ", a.counts[i], " vs ", b.counts[i]);
        if (a.offsets[i] != b.offsets[i]) return say("offsets[", i, "] ", a.offsets[i], " vs ", b.offsets[i]);
    }
    if (a.sample_texels != b.sample_texels) {
        for (size_t id = 0; id < std::min(a.sample_texels.size(), b.sample_texels.size()); ++id) {
            if (a.sample_texels[id] != b.sample_texels[id]) {
                return say("sample_texels[", id, "] ", a.sample_texels[id], " vs ", b.sample_texels[id]);
            }
        }
        return say("sample_texels sizes ", a.sample_texels.size(), " vs ", b.sample_texels.size());
    }
    const size_t accepted = a.header.accepted;
    for (const SampleListsCpu* s : {&a, &b}) {
        if (s->list_positions.size() < accepted || s->list_ids.size() < accepted ||
            s->sample_slots.size() != s->sample_texels.size()) {
            return "list arrays shorter than the accepted count";
        }
    }
    // Same set of (id, position bits) per list.
    using Entry = std::array<uint32_t, 5>;
    std::vector<Entry> ea, eb;
    for (size_t i = 0; i < lists; ++i) {
        ea.clear();
        eb.clear();
        for (uint32_t k = 0; k < a.counts[i]; ++k) {
            const size_t slot = size_t(a.offsets[i]) + k;
            if (slot >= accepted) return say("list ", i, " runs past the accepted count");
            const glm::vec4& pa = a.list_positions[slot];
            const glm::vec4& pb = b.list_positions[slot];
            ea.push_back({a.list_ids[slot], detail::floatBits(pa.x), detail::floatBits(pa.y), detail::floatBits(pa.z),
                          detail::floatBits(pa.w)});
            eb.push_back({b.list_ids[slot], detail::floatBits(pb.x), detail::floatBits(pb.y), detail::floatBits(pb.z),
                          detail::floatBits(pb.w)});
        }
        std::sort(ea.begin(), ea.end());
        std::sort(eb.begin(), eb.end());
        if (ea != eb) return say("list ", i, " holds different (id, position) sets");
    }
    // Every sample's slot points at its own id, inside its own list.
    for (const SampleListsCpu* s : {&a, &b}) {
        const char* which = s == &a ? "first" : "second";
        for (size_t id = 0; id < s->sample_slots.size(); ++id) {
            const uint32_t code = s->sample_texels[id], slot = s->sample_slots[id];
            if (code >= kSampleListsRejected) {
                if (slot != kSampleListsNoSlot) return say(which, ": rejected sample ", id, " has slot ", slot);
                continue;
            }
            if (slot < s->offsets[code] || slot - s->offsets[code] >= s->counts[code] || s->list_ids[slot] != id) {
                return say(which, ": sample ", id, " slot ", slot, " does not point at it inside list ", code);
            }
        }
    }
    return {};
}

// ---------------------------------------------------------------------------------------------
// §4.3 light-frustum fitting

struct LightFrustumFit {
    bool valid = false;         ///< false: no sample qualified; crop = identity, view_projection unchanged
    uint32_t samples = 0;       ///< samples that entered the fit (those the build would accept)
    glm::vec2 min_uv{0.0f}, max_uv{0.0f};  ///< box of the samples in the original light texture [0, 1]^2
    float max_depth = 0.0f;     ///< largest light-texture depth z / w of the samples
    float far_distance = 0.0f;  ///< §4.3 farthest sample: point light = distance to it; directional =
                                ///< largest -dot(p, d) for the unit direction d towards the light
    glm::mat4 crop{1.0f};       ///< NDC crop: box + margin -> [-1, 1]^2, [near, max depth + margin] -> [near, far]
    glm::mat4 view_projection{1.0f};  ///< crop * original light view-projection
    SampleListsHeader keys{};   ///< the reduced keys it was computed from (fit_* words)
    SampleListsFrustum frustum{};     ///< the same, as the frustum block the count pass reads
};

/// The frustum block of an unfitted build: the light's own matrices (what the host uploads when
/// fitting is off; twin of fit_resolve.comp.glsl with no samples).
inline SampleListsFrustum sampleListsFrustum(const SampleListsParams& params) {
    SampleListsFrustum f{};
    f.light_texture = params.light_texture;
    f.view_projection = params.light_view_projection;
    f.crop = glm::mat4(1.0f);
    return f;
}

/// The frustum block as a LightFrustumFit (e.g. of a frustum buffer the GPU filled and the caller
/// read back).
inline LightFrustumFit lightFrustumFitFromFrustum(const SampleListsFrustum& f) {
    LightFrustumFit out;
    out.valid = f.info.x != 0;
    out.samples = f.info.y;
    out.min_uv = glm::vec2(f.box.x, f.box.y);
    out.max_uv = glm::vec2(f.box.z, f.box.w);
    out.max_depth = f.extent.x;
    out.far_distance = f.extent.y;
    out.crop = f.crop;
    out.view_projection = f.view_projection;
    out.frustum = f;
    return out;
}

/// Turns the reduced fit keys (GPU header or CPU twin) into the fit: the CPU twin of
/// fit_resolve.comp.glsl, the same double operations in the same order (products kept unfused),
/// so both sides give identical matrices from identical keys where fp64 is correctly rounded.
inline LightFrustumFit lightFrustumFitFromHeader(const SampleListsHeader& header, const SampleListsLight& light,
                                                 const SampleListsOptions& options = {},
                                                 const LightFrustumFitOptions& fit = {}) {
    PENUMBRA_CHECK(std::isfinite(fit.margin) && fit.margin >= 0.0f && std::isfinite(fit.min_margin) &&
                       fit.min_margin > 0.0f,
                   "penumbra::lightFrustumFitFromHeader: margin ", fit.margin, " / min_margin ", fit.min_margin,
                   " must be finite, margin >= 0 and min_margin > 0");
    using detail::mulRounded;
    SampleListsFrustum f{};
    f.crop = glm::mat4(1.0f);
    f.info = glm::uvec4(0u, header.fit_samples, 0u, 0u);
    if (header.fit_samples == 0) {
        f.view_projection = light.view_projection;
        f.light_texture = lightTextureMatrix(light.view_projection, options.depth_range);
        LightFrustumFit out = lightFrustumFitFromFrustum(f);
        out.keys = header;
        return out;
    }
    f.info.x = 1u;
    const float u0 = detail::orderKeyValue(header.fit_min_u), v0 = detail::orderKeyValue(header.fit_min_v);
    const float u1 = detail::orderKeyValue(header.fit_max_u), v1 = detail::orderKeyValue(header.fit_max_v);
    const float max_depth = detail::orderKeyValue(header.fit_max_depth);
    const float distance_key = detail::orderKeyValue(header.fit_max_distance);
    f.box = glm::vec4(u0, v0, u1, v1);
    double far_distance;
    if (light.light.w == 0.0f) {
        const double lx = light.light.x, ly = light.light.y, lz = light.light.z;
        double squared = mulRounded(lx, lx) + mulRounded(ly, ly);
        squared = squared + mulRounded(lz, lz);
        far_distance = double(distance_key) / std::sqrt(squared);
    } else {
        far_distance = std::sqrt(double(distance_key));
    }
    f.extent = glm::vec4(max_depth, static_cast<float>(far_distance), 0.0f, 0.0f);
    // Box in light-texture units, widened by the margin; NDC X = 2u - 1 maps [U0, U1] to [-1, 1]
    // with X' = X / (U1 - U0) + (1 - U0 - U1) / (U1 - U0).
    const double margin = fit.margin, min_margin = fit.min_margin;
    const double mu = std::max(mulRounded(margin, double(u1) - double(u0)), min_margin);
    const double mv = std::max(mulRounded(margin, double(v1) - double(v0)), min_margin);
    const double U0 = double(u0) - mu, U1 = double(u1) + mu;
    const double V0 = double(v0) - mv, V1 = double(v1) + mv;
    const double c00 = 1.0 / (U1 - U0), c30 = ((1.0 - U0) - U1) / (U1 - U0);
    const double c11 = 1.0 / (V1 - V0), c31 = ((1.0 - V0) - V1) / (V1 - V0);
    double c22 = 1.0, c32 = 0.0;
    // Far plane: light depth z' = z / Z (Z = max depth + margin, < 1) keeps the near plane; in
    // clip space z' = z / Z (ZeroToOne) or z' = z / Z + (1 / Z - 1) w (MinusOneToOne).
    if (fit.fit_far && options.depth_range != LightDepthRange::Unclipped) {
        const double zmax = max_depth;
        const double Z = zmax + std::max(mulRounded(margin, zmax), min_margin);
        if (Z < 1.0 && Z > 0.0) {
            c22 = 1.0 / Z;
            if (options.depth_range == LightDepthRange::MinusOneToOne) c32 = c22 - 1.0;
        }
    }
    f.crop[0][0] = static_cast<float>(c00);
    f.crop[3][0] = static_cast<float>(c30);
    f.crop[1][1] = static_cast<float>(c11);
    f.crop[3][1] = static_cast<float>(c31);
    f.crop[2][2] = static_cast<float>(c22);
    f.crop[3][2] = static_cast<float>(c32);
    const glm::mat4& m = light.view_projection;
    for (int j = 0; j < 4; ++j) {
        const double x = mulRounded(c00, double(m[j][0])) + mulRounded(c30, double(m[j][3]));
        const double y = mulRounded(c11, double(m[j][1])) + mulRounded(c31, double(m[j][3]));
        const double z = mulRounded(c22, double(m[j][2])) + mulRounded(c32, double(m[j][3]));
        f.view_projection[j] = glm::vec4(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), m[j][3]);
    }
    f.light_texture = lightTextureMatrix(f.view_projection, options.depth_range);
    LightFrustumFit out = lightFrustumFitFromFrustum(f);
    out.keys = header;
    return out;
}

namespace detail {

// The fit keys of one accepted sample merged into `h` (twin of fit.comp.glsl).
inline void mergeFitSample(SampleListsHeader& h, const glm::vec4& light, const glm::vec4& p, const glm::vec4& t) {
    const float u = t.x / t.w, v = t.y / t.w, depth = t.z / t.w;
    float distance;
    if (light.w == 0.0f) {
        float along = mulRounded(p.x, light.x) + mulRounded(p.y, light.y);
        along = along + mulRounded(p.z, light.z);
        distance = -along;
    } else {
        const float dx = p.x - light.x, dy = p.y - light.y, dz = p.z - light.z;
        const float squared = mulRounded(dx, dx) + mulRounded(dy, dy);
        distance = squared + mulRounded(dz, dz);
    }
    h.fit_min_u = std::min(h.fit_min_u, orderKey(u));
    h.fit_min_v = std::min(h.fit_min_v, orderKey(v));
    h.fit_max_u = std::max(h.fit_max_u, orderKey(u));
    h.fit_max_v = std::max(h.fit_max_v, orderKey(v));
    h.fit_max_depth = std::max(h.fit_max_depth, orderKey(depth));
    h.fit_max_distance = std::max(h.fit_max_distance, orderKey(distance));
    ++h.fit_samples;
}

inline SampleListsHeader emptyFitHeader() {
    SampleListsHeader h{};
    h.fit_min_u = h.fit_min_v = 0xFFFFFFFFu;
    return h;
}

template <typename Source>
SampleListsHeader fitKeysCpu(const SampleListsSetup& setup, const SampleListsParams& params, Source&& source) {
    SampleListsHeader h = emptyFitHeader();
    for (uint32_t id = 0; id < setup.sample_count; ++id) {
        glm::vec4 position, t;
        glm::vec3 normal;
        source(id, position, normal);
        if (classifySample(params, position, normal, &t) < kSampleListsRejected) {
            mergeFitSample(h, params.light, position, t);
        }
    }
    return h;
}

}  // namespace detail

/// CPU twin of the §4.3 fit, buffer input (arguments as buildSampleListsCpu).
inline LightFrustumFit fitLightFrustumCpu(const SampleListsSetup& setup, const SampleListsLight& light,
                                          const glm::vec4* positions, const glm::vec4* normals,
                                          const SampleListsOptions& options = {},
                                          const LightFrustumFitOptions& fit = {}) {
    PENUMBRA_CHECK(positions || setup.sample_count == 0, "penumbra::fitLightFrustumCpu: positions is null");
    detail::checkCpuNormals(normals, options, setup.sample_count, "fitLightFrustumCpu");
    const SampleListsParams params = sampleListsParams(setup, light, options);
    const bool cull = options.cull_back_facing;
    const SampleListsHeader keys = detail::fitKeysCpu(setup, params, [&](uint32_t id, glm::vec4& p, glm::vec3& n) {
        p = positions[id];
        n = cull ? glm::vec3(normals[id]) : glm::vec3(0.0f);
    });
    return lightFrustumFitFromHeader(keys, light, options, fit);
}

/// CPU twin of the §4.3 fit, depth input.
inline LightFrustumFit fitLightFrustumCpu(const SampleListsSetup& setup, const SampleListsLight& light,
                                          const SampleListsView& view, const float* depth, const glm::vec4* normals,
                                          const SampleListsOptions& options = {},
                                          const LightFrustumFitOptions& fit = {}) {
    PENUMBRA_CHECK(depth || setup.sample_count == 0, "penumbra::fitLightFrustumCpu: depth is null");
    detail::checkCpuNormals(normals, options, setup.sample_count, "fitLightFrustumCpu");
    const SampleListsParams params = sampleListsParams(setup, light, options, &view);
    const bool cull = options.cull_back_facing;
    const SampleListsHeader keys = detail::fitKeysCpu(setup, params, [&](uint32_t id, glm::vec4& p, glm::vec3& n) {
        p = detail::viewPosition(params.view_inverse, id % view.width, id / view.width, view.width, view.height,
                                 depth[id], view.depth_zero_to_one);
        n = cull ? glm::vec3(normals[id]) : glm::vec3(0.0f);
    });
    return lightFrustumFitFromHeader(keys, light, options, fit);
}

// ---------------------------------------------------------------------------------------------
// Fig. 9 statistics

struct SampleListStatistics {
    uint32_t lists = 0;            ///< W * H
    uint32_t occupied_lists = 0;   ///< lists with at least one sample
    uint32_t max_list_length = 0;
    uint64_t listed_samples = 0;   ///< sum of list lengths (== accepted)
    uint32_t accepted = 0;
    std::array<uint32_t, kSampleListsReasonCount> rejected{};  ///< by SampleRejection

    /// Fraction of lists with at least one sample (Fig. 9 "% of occupied lists" / 100).
    double occupancy() const { return lists ? double(occupied_lists) / lists : 0.0; }
    /// Fig. 9 "Av. occup. list size": average over occupied lists.
    double averageOccupiedLength() const { return occupied_lists ? double(listed_samples) / occupied_lists : 0.0; }
    /// Average over all lists.
    double averageLength() const { return lists ? double(listed_samples) / lists : 0.0; }
    uint64_t rejectedTotal() const {
        uint64_t total = 0;
        for (uint32_t r : rejected) total += r;
        return total;
    }
    bool operator==(const SampleListStatistics& o) const {
        return lists == o.lists && occupied_lists == o.occupied_lists && max_list_length == o.max_list_length &&
               listed_samples == o.listed_samples && accepted == o.accepted && rejected == o.rejected;
    }
    bool operator!=(const SampleListStatistics& o) const { return !(*this == o); }
};

/// From a header the GPU filled (count pass + statistics pass).
inline SampleListStatistics sampleListStatisticsFromHeader(const SampleListsSetup& setup,
                                                           const SampleListsHeader& header) {
    SampleListStatistics s;
    s.lists = setup.lists;
    s.occupied_lists = header.occupied_lists;
    s.max_list_length = header.max_list_length;
    s.listed_samples = header.listed_samples;
    s.accepted = header.accepted;
    for (uint32_t r = 0; r < kSampleListsReasonCount; ++r) s.rejected[r] = header.rejected[r];
    return s;
}

/// CPU twin: from the structure's counts and counters.
inline SampleListStatistics sampleListStatisticsCpu(const SampleListsCpu& lists) {
    SampleListStatistics s;
    s.lists = static_cast<uint32_t>(lists.counts.size());
    for (uint32_t c : lists.counts) {
        if (c == 0) continue;
        ++s.occupied_lists;
        s.max_list_length = std::max(s.max_list_length, c);
        s.listed_samples += c;
    }
    s.accepted = lists.header.accepted;
    for (uint32_t r = 0; r < kSampleListsReasonCount; ++r) s.rejected[r] = lists.header.rejected[r];
    return s;
}

// ---------------------------------------------------------------------------------------------
// The plan (FidelityFX-style): what build() records, as data an engine's own RHI records itself
//
// planSampleLists() returns the constants blocks and the ordered steps of one build: uploads of
// the constants blocks, buffer clears, compute dispatches (entry shader, defines, grid, and which
// resource is bound where), the scan of counts into offsets (an embedded ScanPlan), and memory
// barriers. Resources are named by role (SampleListsResource), never by GL object. The GL
// executor (SampleListBuilder::build) walks exactly these steps — detail::planSampleListsSteps
// is the one definition of the pass list; tests/sample_lists_test.cpp replays a plan with raw GL
// calls and gets the executor's lists.
//
// Recording a plan:
//   once: compile every plan.programs[i] (key + defines, plus defines of your own) as a compute
//         program; the scan's kernels as scan.hpp says for plan.scan; a 256-byte uniform buffer
//         for SampleListsResource::Params (the executor owns one; you own yours); the scan's
//         scratch (plan.scan.scratch_bytes) and constants (plan.scan.constants_bytes) buffers.
//   per build, for every step in order:
//     Upload:   write plan.params (resource Params) or plan.frustum (resource Frustum), `bytes`
//               bytes, at the start of that resource's range.
//     Clear:    set uints [first_word, first_word + words) of the resource's range to `value`.
//     Dispatch: bind bindings[0 .. binding_count) (uniform block, shader-storage block or texture
//               unit `point`, `bytes` bytes from the start of the resource's range), then
//               dispatch the program of `kernel` on grid.x * grid.y * 1 work groups.
//     Scan:     record plan.scan (scan.hpp, "Recording a plan"): ScanBuffer::Input = the Counts
//               range, Output = the Offsets range, Scratch / Constants = your scan buffers. Its
//               recording puts a storage barrier before each of its dispatches; the first one
//               makes the count pass's counters visible to it. The scan rebinds its own binding
//               points; every Dispatch step after it lists all of its bindings again.
//     Barrier:  a memory barrier of `barriers` (SampleListsBarrier: the GL bits themselves; an
//               RHI uses its UAV / uniform / transfer / indirect-argument barrier).
//   Dispatches with no work are left out (no count, fit or scatter dispatch for 0 samples).

/// Where the view samples come from: the PENUMBRA_SAMPLE_LISTS_INPUT permutation.
enum class SampleListsInputKind : uint32_t {
    Buffer = PENUMBRA_SAMPLE_LISTS_INPUT_BUFFER,  ///< vec4 positions + normals in buffers (SampleBufferInput)
    Depth = PENUMBRA_SAMPLE_LISTS_INPUT_DEPTH,    ///< depth + normal textures and a SampleListsView (SampleDepthInput)
};

/// Binding points of the builder's kernels; value-initialised = the sample_lists_shared.h
/// defaults. The GL executor's SampleListsBindings is this plus the scanner's bindings.
struct SampleListsBindingPoints {
    uint32_t params = PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS;    ///< uniform block
    uint32_t frustum = PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM;  ///< uniform block (count pass)
    uint32_t positions = PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS;  ///< SSBOs from here on
    uint32_t normals = PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS;
    uint32_t counts = PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS;
    uint32_t frustum_out = PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT;
    uint32_t offsets = PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS;
    uint32_t header = PENUMBRA_SAMPLE_LISTS_BINDING_HEADER;
    uint32_t list_positions = PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS;
    uint32_t list_ids = PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS;
    uint32_t sample_slots = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS;
    uint32_t sample_texels = PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS;
    uint32_t depth_unit = PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH;    ///< texture units (depth input)
    uint32_t normal_unit = PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS;
};

/// The builder's entry shaders (compute).
enum class SampleListsKernel : uint32_t {
    Count,       ///< pass 1: classify, count per texel (one invocation per sample)
    Scatter,     ///< pass 3: slot = offset + local index (one invocation per sample)
    Fit,         ///< §4.3: reduce the fit keys into the header (one invocation per sample)
    FitResolve,  ///< §4.3: keys -> the frustum block (one work group)
    Statistics,  ///< Fig. 9: reduce the counts into the header (one invocation per list)
};
inline constexpr uint32_t kSampleListsKernels = 5;

/// The entry shader's key ("penumbra/sample_lists/count.comp.glsl", ...).
inline const char* sampleListsKernelKey(SampleListsKernel kernel) {
    switch (kernel) {
        case SampleListsKernel::Count: return "penumbra/sample_lists/count.comp.glsl";
        case SampleListsKernel::Scatter: return "penumbra/sample_lists/scatter.comp.glsl";
        case SampleListsKernel::Fit: return "penumbra/sample_lists/fit.comp.glsl";
        case SampleListsKernel::FitResolve: return "penumbra/sample_lists/fit_resolve.comp.glsl";
        case SampleListsKernel::Statistics: return "penumbra/sample_lists/statistics.comp.glsl";
    }
    return "";
}

/// Whether the kernel reads the view samples (and so has a PENUMBRA_SAMPLE_LISTS_INPUT permutation).
inline constexpr bool sampleListsKernelPerInput(SampleListsKernel kernel) {
    return kernel == SampleListsKernel::Count || kernel == SampleListsKernel::Scatter ||
           kernel == SampleListsKernel::Fit;
}

/// The defines the kernel is compiled with: every binding point, and PENUMBRA_SAMPLE_LISTS_INPUT
/// for the per-input kernels (what the GL executor compiles, before the caller's extra defines).
inline ShaderDefines sampleListsKernelDefines(SampleListsKernel kernel, SampleListsInputKind input,
                                              const SampleListsBindingPoints& b = {}) {
    ShaderDefines defines = {{"PENUMBRA_SAMPLE_LISTS_BINDING_PARAMS", std::to_string(b.params)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM", std::to_string(b.frustum)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_POSITIONS", std::to_string(b.positions)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_NORMALS", std::to_string(b.normals)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_COUNTS", std::to_string(b.counts)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_FRUSTUM_OUT", std::to_string(b.frustum_out)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_OFFSETS", std::to_string(b.offsets)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_HEADER", std::to_string(b.header)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_LIST_POSITIONS", std::to_string(b.list_positions)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_LIST_IDS", std::to_string(b.list_ids)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_SLOTS", std::to_string(b.sample_slots)},
                             {"PENUMBRA_SAMPLE_LISTS_BINDING_SAMPLE_TEXELS", std::to_string(b.sample_texels)},
                             {"PENUMBRA_SAMPLE_LISTS_UNIT_DEPTH", std::to_string(b.depth_unit)},
                             {"PENUMBRA_SAMPLE_LISTS_UNIT_NORMALS", std::to_string(b.normal_unit)}};
    if (sampleListsKernelPerInput(kernel)) {
        defines.push_back({"PENUMBRA_SAMPLE_LISTS_INPUT", std::to_string(static_cast<uint32_t>(input))});
    }
    return defines;
}

/// What a step touches, by role: the integrator's ranges and textures (the executor's
/// SampleListsBuffers, SampleBufferInput and SampleDepthInput members of the same name) and the
/// constants buffer.
enum class SampleListsResource : uint32_t {
    None,
    Params,         ///< uniform buffer holding plan.params (SampleListsParams, 256 bytes)
    Frustum,        ///< SampleListsBuffers::frustum: SampleListsFrustum, a uniform block (and the fit's SSBO output)
    Positions,      ///< SampleBufferInput::positions: vec4[sample_count]
    Normals,        ///< SampleBufferInput::normals: vec4[sample_count] (bound only when culling)
    DepthTexture,   ///< SampleDepthInput::depth_texture
    NormalTexture,  ///< SampleDepthInput::normal_texture (bound only when culling)
    Counts,         ///< SampleListsBuffers::counts: uint[W*H]
    Offsets,        ///< SampleListsBuffers::offsets: uint[W*H]
    ListPositions,  ///< SampleListsBuffers::list_positions: vec4[sample_count]
    ListIds,        ///< SampleListsBuffers::list_ids: uint[sample_count]
    SampleSlots,    ///< SampleListsBuffers::sample_slots: uint[sample_count]
    SampleTexels,   ///< SampleListsBuffers::sample_texels: uint[sample_count]
    Header,         ///< SampleListsBuffers::header: SampleListsHeader
};

inline const char* sampleListsResourceName(SampleListsResource r) {
    switch (r) {
        case SampleListsResource::None: return "none";
        case SampleListsResource::Params: return "params";
        case SampleListsResource::Frustum: return "frustum";
        case SampleListsResource::Positions: return "positions";
        case SampleListsResource::Normals: return "normals";
        case SampleListsResource::DepthTexture: return "depth_texture";
        case SampleListsResource::NormalTexture: return "normal_texture";
        case SampleListsResource::Counts: return "counts";
        case SampleListsResource::Offsets: return "offsets";
        case SampleListsResource::ListPositions: return "list_positions";
        case SampleListsResource::ListIds: return "list_ids";
        case SampleListsResource::SampleSlots: return "sample_slots";
        case SampleListsResource::SampleTexels: return "sample_texels";
        case SampleListsResource::Header: return "header";
    }
    return "unknown";
}

/// How a dispatch sees a resource.
enum class SampleListsBindingKind : uint32_t {
    UniformBuffer,  ///< uniform block at binding `point` (GL_UNIFORM_BUFFER, glBindBufferRange)
    StorageBuffer,  ///< shader-storage block at binding `point` (GL_SHADER_STORAGE_BUFFER)
    Texture,        ///< sampler2D at texture unit `point`, read with texelFetch at level 0 (nearest, compare mode off)
};

/// One resource bound for one dispatch.
struct SampleListsBinding {
    SampleListsResource resource = SampleListsResource::None;
    SampleListsBindingKind kind = SampleListsBindingKind::StorageBuffer;
    uint32_t point = 0;  ///< binding index or texture unit (from SampleListsBindingPoints)
    uint64_t bytes = 0;  ///< buffers: bytes from the start of the resource's range the pass may touch
                         ///< (> 0; bind at least these); textures: 0
};

/// Memory barriers of a plan: a bit mask whose values are the GL bits themselves
/// (static_cast<GLbitfield>(b) is what glMemoryBarrier takes; penumbra/gl/sample_lists.hpp
/// static_asserts it).
enum class SampleListsBarrier : uint32_t {
    None = 0,
    Uniform = 0x00000004u,       ///< GL_UNIFORM_BARRIER_BIT: shader writes -> reads as a uniform block
    Command = 0x00000040u,       ///< GL_COMMAND_BARRIER_BIT: shader writes -> indirect draw/dispatch arguments
    BufferUpdate = 0x00000200u,  ///< GL_BUFFER_UPDATE_BARRIER_BIT: shader writes -> copies, reads by the host
    Storage = 0x00002000u,       ///< GL_SHADER_STORAGE_BARRIER_BIT: shader writes -> shader-storage reads/atomics
};
inline constexpr SampleListsBarrier operator|(SampleListsBarrier a, SampleListsBarrier b) {
    return static_cast<SampleListsBarrier>(static_cast<uint32_t>(a) | static_cast<uint32_t>(b));
}
inline constexpr SampleListsBarrier operator&(SampleListsBarrier a, SampleListsBarrier b) {
    return static_cast<SampleListsBarrier>(static_cast<uint32_t>(a) & static_cast<uint32_t>(b));
}
/// What build() leaves behind: the lists readable as SSBOs, the frustum as a uniform block, the
/// header as indirect arguments, everything by the host.
inline constexpr SampleListsBarrier kSampleListsEndBarriers =
    SampleListsBarrier::Storage | SampleListsBarrier::Uniform | SampleListsBarrier::BufferUpdate |
    SampleListsBarrier::Command;

enum class SampleListsStepKind : uint32_t {
    Upload,    ///< write a constants block to the start of `resource` (see "Recording a plan")
    Clear,     ///< fill uints of `resource`
    Dispatch,  ///< bind `bindings`, run `kernel` on `grid`
    Scan,      ///< exclusive scan of `elements` uints, `resource` -> `output`: record plan.scan
    Barrier,   ///< memory barrier `barriers`
};

inline const char* sampleListsStepKindName(SampleListsStepKind kind) {
    switch (kind) {
        case SampleListsStepKind::Upload: return "upload";
        case SampleListsStepKind::Clear: return "clear";
        case SampleListsStepKind::Dispatch: return "dispatch";
        case SampleListsStepKind::Scan: return "scan";
        case SampleListsStepKind::Barrier: return "barrier";
    }
    return "unknown";
}

/// Most bindings of one dispatch (the count and scatter passes: constants, input, four buffers).
inline constexpr uint32_t kSampleListsMaxBindings = 8;
/// Most steps of one build (17 with the fit and the statistics; room to spare).
inline constexpr uint32_t kSampleListsMaxSteps = 24;

/// One step of a plan; which fields matter depends on `kind`.
struct SampleListsStep {
    SampleListsStepKind kind = SampleListsStepKind::Barrier;
    SampleListsResource resource = SampleListsResource::None;  ///< Upload, Clear: the target; Scan: its input (Counts)
    SampleListsResource output = SampleListsResource::None;    ///< Scan: its output (Offsets)
    uint32_t bytes = 0;        ///< Upload: bytes of the block (sizeof(SampleListsParams) or sizeof(SampleListsFrustum))
    uint32_t first_word = 0;   ///< Clear: first uint of the resource's range
    uint32_t words = 0;        ///< Clear: uints filled (> 0)
    uint32_t value = 0;        ///< Clear: the value every one gets
    uint32_t elements = 0;     ///< Scan: uints scanned (W * H == plan.scan.n)
    SampleListsKernel kernel = SampleListsKernel::Count;  ///< Dispatch: its program (plan.program(kernel))
    detail::DispatchGrid grid;                             ///< Dispatch: grid.x * grid.y * 1 work groups (never empty)
    SampleListsBarrier barriers = SampleListsBarrier::None;  ///< Barrier: the bits
    uint32_t binding_count = 0;                            ///< Dispatch: bindings[0 .. binding_count)
    std::array<SampleListsBinding, kSampleListsMaxBindings> bindings{};  ///< Dispatch: everything it reads or writes
};

/// The steps of a plan: a fixed-capacity list (planning the steps allocates nothing).
class SampleListsSteps {
public:
    size_t size() const { return size_; }
    bool empty() const { return size_ == 0; }
    const SampleListsStep& operator[](size_t i) const { return steps_[i]; }
    const SampleListsStep* begin() const { return steps_.data(); }
    const SampleListsStep* end() const { return steps_.data() + size_; }
    void clear() { size_ = 0; }
    void push_back(const SampleListsStep& step) {
        PENUMBRA_ASSERT(size_ < kSampleListsMaxSteps);
        if (size_ < kSampleListsMaxSteps) steps_[size_++] = step;
    }

private:
    std::array<SampleListsStep, kSampleListsMaxSteps> steps_{};
    size_t size_ = 0;
};

/// An entry shader of a plan, as the GL executor compiles it.
struct SampleListsProgram {
    SampleListsKernel kernel = SampleListsKernel::Count;
    const char* key = "";   ///< entry shader key (sampleListsKernelKey)
    ShaderDefines defines;  ///< sampleListsKernelDefines(kernel, plan.input, bindings)
};

/// How the integrator binds and scans. Value-initialised = the sample_lists_shared.h binding
/// points, default scan options, the GL minimum limits, ranges at byte offset 0.
struct SampleListsPlanOptions {
    SampleListsBindingPoints bindings;  ///< binding points of the plan's defines and bindings
    ScanOptions scan;                   ///< options of the embedded scan plan (SampleListBuilder: scanner().options())
    ScanLimits scan_limits;             ///< the driver's limits (penumbra::queryScanLimits() on GL)
    uint64_t counts_offset = 0;         ///< byte offset of the Counts range in its buffer (scan bindings are absolute)
    uint64_t offsets_offset = 0;        ///< byte offset of the Offsets range in its buffer
};

/// Everything one build does, without GL (see "Recording a plan").
struct SampleListsPlan {
    SampleListsInputKind input = SampleListsInputKind::Buffer;
    SampleListsParams params{};    ///< constants block: the first step uploads it to Params; every dispatch binds it
    SampleListsFrustum frustum{};  ///< the frustum block an Upload step writes to Frustum when not fitting
                                   ///< (sampleListsFrustum(params)); with build.fit_frustum the
                                   ///< fit_resolve dispatch writes it instead
    std::vector<SampleListsProgram> programs;  ///< the entry shaders the dispatches use, once each, in first-use order
    SampleListsSteps steps;        ///< in recording order
    ScanPlan scan;                 ///< the Scan step: exclusive scan of W * H counts into offsets

    /// The program of a kernel, or null when no dispatch uses it.
    const SampleListsProgram* program(SampleListsKernel kernel) const {
        for (const SampleListsProgram& p : programs) {
            if (p.kernel == kernel) return &p;
        }
        return nullptr;
    }
};

namespace detail {

/// The steps of one build: the single definition of the pass list (planSampleLists returns it,
/// SampleListBuilder::build walks it). Allocates and throws nothing; inputs assumed valid.
inline void planSampleListsSteps(const SampleListsSetup& setup, const SampleListsBuild& build,
                                 SampleListsInputKind input, bool cull_back_facing, const SampleListsBindingPoints& b,
                                 SampleListsSteps& steps) {
    using R = SampleListsResource;
    using K = SampleListsBindingKind;
    steps.clear();
    const uint64_t n = setup.sample_count;
    const uint64_t per_sample4 = n * 4, per_sample16 = n * 16;
    auto upload = [&](R resource, uint32_t bytes) {
        SampleListsStep s;
        s.kind = SampleListsStepKind::Upload;
        s.resource = resource;
        s.bytes = bytes;
        steps.push_back(s);
    };
    auto clear = [&](R resource, uint32_t first_word, uint32_t words, uint32_t value) {
        SampleListsStep s;
        s.kind = SampleListsStepKind::Clear;
        s.resource = resource;
        s.first_word = first_word;
        s.words = words;
        s.value = value;
        steps.push_back(s);
    };
    auto barrier = [&](SampleListsBarrier bits) {
        SampleListsStep s;
        s.kind = SampleListsStepKind::Barrier;
        s.barriers = bits;
        steps.push_back(s);
    };
    struct Dispatch {
        SampleListsStep step;
        Dispatch& bind(R resource, K kind, uint32_t point, uint64_t bytes) {
            PENUMBRA_ASSERT(step.binding_count < kSampleListsMaxBindings);
            if (step.binding_count < kSampleListsMaxBindings) {
                step.bindings[step.binding_count++] = SampleListsBinding{resource, kind, point, bytes};
            }
            return *this;
        }
    };
    auto dispatch = [&](SampleListsKernel kernel, const DispatchGrid& grid) {
        Dispatch d;
        d.step.kind = SampleListsStepKind::Dispatch;
        d.step.kernel = kernel;
        d.step.grid = grid;
        d.bind(R::Params, K::UniformBuffer, b.params, sizeof(SampleListsParams));
        return d;
    };
    auto bindInput = [&](Dispatch& d) {
        if (input == SampleListsInputKind::Buffer) {
            d.bind(R::Positions, K::StorageBuffer, b.positions, per_sample16);
            if (cull_back_facing) d.bind(R::Normals, K::StorageBuffer, b.normals, per_sample16);
        } else {
            d.bind(R::DepthTexture, K::Texture, b.depth_unit, 0);
            if (cull_back_facing) d.bind(R::NormalTexture, K::Texture, b.normal_unit, 0);
        }
    };
    const uint64_t frustum_bytes = sizeof(SampleListsFrustum), header_bytes = setup.header_bytes;

    upload(R::Params, sizeof(SampleListsParams));
    // §3.1: "we initialize the local lists' lengths in the SM to zero".
    clear(R::Counts, 0, setup.lists, 0u);
    clear(R::Header, PENUMBRA_SAMPLE_LISTS_HEADER_COUNTERS_WORD, PENUMBRA_SAMPLE_LISTS_HEADER_COUNTERS_WORDS, 0u);
    if (build.fit_frustum) {
        // §4.3 on the GPU: keys -> header, then the crop -> frustum (as an SSBO), read below as a UBO.
        clear(R::Header, PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MIN_WORD, 2, 0xFFFFFFFFu);
        clear(R::Header, PENUMBRA_SAMPLE_LISTS_HEADER_FIT_MAX_WORD, 6, 0u);
        if (n) {
            Dispatch fit = dispatch(SampleListsKernel::Fit, setup.sample_groups);
            bindInput(fit);
            fit.bind(R::Header, K::StorageBuffer, b.header, header_bytes);
            steps.push_back(fit.step);
        }
        barrier(SampleListsBarrier::Storage);
        DispatchGrid one;
        one.x = one.y = 1;
        one.groups = 1;
        Dispatch resolve = dispatch(SampleListsKernel::FitResolve, one);
        resolve.bind(R::Header, K::StorageBuffer, b.header, header_bytes)
            .bind(R::Frustum, K::StorageBuffer, b.frustum_out, frustum_bytes);
        steps.push_back(resolve.step);
        barrier(SampleListsBarrier::Storage | SampleListsBarrier::Uniform);
    } else {
        upload(R::Frustum, sizeof(SampleListsFrustum));
    }
    // Pass 1: count.
    if (n) {
        Dispatch count = dispatch(SampleListsKernel::Count, setup.sample_groups);
        count.bind(R::Frustum, K::UniformBuffer, b.frustum, frustum_bytes);
        bindInput(count);
        count.bind(R::Counts, K::StorageBuffer, b.counts, setup.counts_bytes)
            .bind(R::Header, K::StorageBuffer, b.header, header_bytes)
            .bind(R::SampleSlots, K::StorageBuffer, b.sample_slots, per_sample4)
            .bind(R::SampleTexels, K::StorageBuffer, b.sample_texels, per_sample4);
        steps.push_back(count.step);
    }
    // Pass 2: offsets = exclusive scan of the lengths (§3.1, [HSO07]); the scan's own barriers
    // make pass 1's counts visible.
    SampleListsStep scan;
    scan.kind = SampleListsStepKind::Scan;
    scan.resource = R::Counts;
    scan.output = R::Offsets;
    scan.elements = setup.lists;
    steps.push_back(scan);
    barrier(SampleListsBarrier::Storage);
    // Pass 3: scatter.
    if (n) {
        Dispatch scatter = dispatch(SampleListsKernel::Scatter, setup.sample_groups);
        bindInput(scatter);
        scatter.bind(R::Offsets, K::StorageBuffer, b.offsets, setup.offsets_bytes)
            .bind(R::ListPositions, K::StorageBuffer, b.list_positions, per_sample16)
            .bind(R::ListIds, K::StorageBuffer, b.list_ids, per_sample4)
            .bind(R::SampleSlots, K::StorageBuffer, b.sample_slots, per_sample4)
            .bind(R::SampleTexels, K::StorageBuffer, b.sample_texels, per_sample4);
        steps.push_back(scatter.step);
    }
    if (build.statistics) {
        barrier(SampleListsBarrier::Storage);
        clear(R::Header, PENUMBRA_SAMPLE_LISTS_HEADER_STATISTICS_WORD, 4, 0u);
        Dispatch statistics = dispatch(SampleListsKernel::Statistics, setup.list_groups);
        statistics.bind(R::Counts, K::StorageBuffer, b.counts, setup.counts_bytes)
            .bind(R::Header, K::StorageBuffer, b.header, header_bytes);
        steps.push_back(statistics.step);
    }
    barrier(kSampleListsEndBarriers);
}

}  // namespace detail

/// Pure setup of one build as data (see "Recording a plan"): the constants blocks, the programs,
/// the steps and the scan plan. `view` only (and always) for the depth input. Throws
/// penumbra::Error for what sampleListsParams rejects, a missing or superfluous view, and scan
/// options or limits planScan rejects. Allocates (programs, scan plan): a load-time call.
inline SampleListsPlan planSampleLists(const SampleListsSetup& setup, const SampleListsLight& light,
                                       const SampleListsOptions& options, const SampleListsBuild& build,
                                       SampleListsInputKind input, const SampleListsView* view = nullptr,
                                       const SampleListsPlanOptions& plan_options = {}) {
    PENUMBRA_CHECK(input == SampleListsInputKind::Buffer || input == SampleListsInputKind::Depth,
                   "penumbra::planSampleLists: input kind ", static_cast<uint32_t>(input),
                   " is neither Buffer nor Depth");
    PENUMBRA_CHECK(input == SampleListsInputKind::Depth || view == nullptr,
                   "penumbra::planSampleLists: a view is only for the depth input");
    PENUMBRA_CHECK(input == SampleListsInputKind::Buffer || view != nullptr,
                   "penumbra::planSampleLists: the depth input needs its view (width, height, inverse "
                   "view-projection)");
    SampleListsPlan plan;
    plan.input = input;
    plan.params = sampleListsParams(setup, light, options, view, build.fit);
    plan.frustum = sampleListsFrustum(plan.params);
    plan.scan = planScan(setup.lists, plan_options.scan, plan_options.scan_limits, ScanKind::Exclusive,
                         plan_options.counts_offset, plan_options.offsets_offset);
    detail::planSampleListsSteps(setup, build, input, options.cull_back_facing, plan_options.bindings, plan.steps);
    for (const SampleListsStep& step : plan.steps) {
        if (step.kind != SampleListsStepKind::Dispatch || plan.program(step.kernel)) continue;
        plan.programs.push_back({step.kernel, sampleListsKernelKey(step.kernel),
                                 sampleListsKernelDefines(step.kernel, input, plan_options.bindings)});
    }
    return plan;
}

}  // namespace penumbra

#endif
