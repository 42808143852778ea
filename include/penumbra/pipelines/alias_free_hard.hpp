// penumbra — alias-free hard shadows (sintorn2008 §3, Fig. 2–4): the first pipeline, composed only
// from the blocks' public APIs. Use it whole or copy it as a template.
//
// Integration summary
//   needs:    a GL 4.5 context with fp64 in shaders (GL 4.0 core; exact mode) and geometry shaders;
//             PENUMBRA_GL_HEADER (gl/gl.hpp); the blocks penumbra/sample_lists.hpp (+ scan) and
//             penumbra/conservative_raster.hpp; shaders penumbra/alias_free_hard/*.
//   input:    view samples as SSBOs (vec4 world positions, w == 0 = none; vec4 world normals) — e.g.
//             your G-buffer copied to buffers — their count, the light (SampleListsLight: point,
//             light.w = 1, or directional, light.w = 0) with a starting view-projection that sees
//             every sample (lightViewProjectionForBounds() makes one), and a callback that draws
//             your casters of one class (closed or open) with attribute 0 = world position (vec3)
//             while the pipeline's program is bound.
//   produces: one uint state per view-sample id (stateBuffer(): PENUMBRA_AFH_LIT, _SHADOWED,
//             _BACK_FACING, _NO_SAMPLE, _UNTESTED; alias_free_hard_shared.h), the packed shadow
//             bit per list slot, the sample lists themselves, Fig. 9 statistics and work counters.
//   passes:   (1) §4.3 fit the light frustum to the samples (one small read-back), (2) build the
//             per-texel view-sample lists (count, scan, scatter), (3) statistics -> the longest
//             list decides how many list blocks (passes) the light pass needs, (4) light pass: every
//             caster drawn once per block into a W x H framebuffer with no attachments; the
//             geometry stage culls (closed casters: only light-back-facing triangles cast, §3.3 —
//             no bias at all) and emits the triangle's conservative coverage; each fragment walks
//             its texel's list block and ORs the shadow bit of every sample the triangle blocks
//             (4 planes: supporting plane + 3 planes through the light and each edge), (5) resolve.
//
// Exactness. PENUMBRA_AFH_EXACT (AfhPrecision::Exact, default) runs the plane tests in double with
// the oracle's coplanar rule (blocker_test.glsl): on every (sample, light) pair the oracle does
// not flag as a tie, the result equals reference::VisibilityOracle::segmentBlocked with the same
// coplanar_epsilon — tests check 0 mismatches. AfhPrecision::Fast uses float planes and an
// optional sample offset toward the light; its mismatches are measured, not assumed.
// Casters: closed (watertight, outward-oriented) meshes cast only light-back-facing triangles
// (§3.3); open meshes cast every triangle. Samples lying on a surface are never shadowed by it
// (the coplanar rule), so open receivers need no bias either; `sample_offset` (default 0) moves
// each sample toward the light by that distance along the caster's plane normal for Fast mode
// users who prefer a classic bias.
// Point lights: all samples must lie in front of the light (one frustum; a light inside the
// scene needs one pipeline run per cube face). Directional lights: each sample's light point is
// taken `directional_reach` along the light direction: exact for casters within that distance.
//
// GL state: changes without restoring the current program, framebuffer binding, viewport, the
// enables GL_DEPTH_TEST (off), GL_CULL_FACE (off), GL_DEPTH_CLAMP (on), GL_RASTERIZER_DISCARD
// (off), uniform-buffer bindings 0–1, SSBO bindings 0–7 and whatever the sample-list builder and
// scanner bind. Ends with GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT.
#ifndef PENUMBRA_PIPELINES_ALIAS_FREE_HARD_HPP
#define PENUMBRA_PIPELINES_ALIAS_FREE_HARD_HPP

#include "penumbra/detail/shared.hpp"
#include <penumbra/alias_free_hard/alias_free_hard_shared.h>

#include "penumbra/conservative_raster.hpp"
#include "penumbra/detail/geometry.hpp"
#include "penumbra/gl/objects.hpp"
#include "penumbra/gl/shader.hpp"
#include "penumbra/sample_lists.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

namespace penumbra {

using AfhParams = shared::PenumbraAfhParams;
static_assert(sizeof(AfhParams) == 64, "PenumbraAfhParams must be 64 bytes (std140 == std430)");

enum class AfhPrecision { Exact, Fast };
enum class CasterClass { Closed, Open };

/// Value-initialised = defaults, except the grid size, which must be set.
struct AliasFreeHardOptions {
    uint32_t grid_width = 0, grid_height = 0;  ///< light grid W x H (sintorn2008 uses the view size)
    ConservativeVariant variant = ConservativeVariant::Fixed6;
    AfhPrecision precision = AfhPrecision::Exact;
    /// Exact mode only: run every blocker test in double (true) instead of the float filter that
    /// falls back to double where a sign is uncertain (false, default; identical results).
    bool fp64_only = false;
    double coplanar_epsilon = 1e-7;  ///< the oracle's coplanar rule (relative); above view-sample float noise (~1 ulp)
    float sample_offset = 0.0f;      ///< world units; see the summary (0 = exact geometry)
    float directional_reach = 0.0f;  ///< directional lights: > 0, at least the scene's extent
    bool fit_frustum = true;         ///< §4.3
    uint32_t list_block = 2048;      ///< samples one fragment walks per pass (llvmpipe caps loops at 65 535)
    bool count_work = false;         ///< atomics counting fragments, tests and emitted triangles
    // Skips (each proven bit-identical by the tests): a fragment does not retest a sample another
    // caster already shadowed; fragments outside the triangle's pixel-expanded box are discarded.
    bool skip_shadowed = true;
    bool clip_to_box = true;
    /// §3.3: closed casters cast only their light-back-facing triangles (half the work). Exact for
    /// every sample outside a closed mesh; a sample lying exactly in a concave crease of a closed
    /// surface, lit at a grazing angle that enters the solid right at the sample, is missed (the
    /// entry is at the segment's excluded endpoint; measured: 1 of 150 209 samples of the torus
    /// knot at 512x384, 0 in the 256x256 and 512x512 oracle checks). false: closed casters cast
    /// every triangle like open ones, which equals the oracle there too.
    bool back_faces_only = true;
};

/// What one run did.
struct AliasFreeHardFrame {
    glm::mat4 light_view_projection{1.0f};  ///< the (fitted) matrix the lists and the light pass used
    LightFrustumFit fit;                    ///< valid == false when fitting was off or found no sample
    SampleListStatistics statistics;        ///< Fig. 9, of the lists the light pass walked
    uint32_t passes = 0;                    ///< list blocks = light-pass draws of every caster
    uint64_t fragments = 0, tests = 0, triangles_emitted = 0;  ///< when count_work
    uint64_t fallbacks = 0;  ///< when count_work, exact filtered mode: tests that ran in double
};

// ---------------------------------------------------------------------------------------------
// Pure setup

/// The box of the view samples a light must see: positions with w != 0 (w == 0 marks "no
/// sample"). `count` returns how many there were; with none the box is the point (0, 0, 0).
inline std::pair<glm::vec3, glm::vec3> viewSampleBounds(const glm::vec4* positions, size_t n, size_t* count = nullptr) {
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    size_t samples = 0;
    for (size_t i = 0; i < n; ++i) {
        if (positions[i].w == 0.0f) continue;
        ++samples;
        lo = glm::min(lo, glm::vec3(positions[i]));
        hi = glm::max(hi, glm::vec3(positions[i]));
    }
    if (count) *count = samples;
    if (samples == 0) lo = hi = glm::vec3(0.0f);
    return {lo, hi};
}

/// A starting light view-projection seeing the box [lo, hi] (pass the bounds of the view samples,
/// not of the whole scene: a large ground plane would put the light "inside"). Point light
/// (light.w = 1): a symmetric perspective from the light towards the box centre whose cone holds
/// every box corner (half-angle at most 85 degrees), near = 1e-3 * nearest corner depth; the §4.3
/// fit then crops it to the samples. Directional (light.w = 0): an orthographic box around the
/// box's bounding sphere. Throws penumbra::Error when a point light cannot see the whole box in one
/// frustum (inside it or too wide) or the inputs are not finite.
inline glm::mat4 lightViewProjectionForBounds(const glm::vec4& light, const glm::vec3& lo, const glm::vec3& hi) {
    PENUMBRA_CHECK(std::isfinite(light.x) && std::isfinite(light.y) && std::isfinite(light.z) && std::isfinite(light.w),
                   "penumbra::lightViewProjectionForBounds: light is not finite");
    PENUMBRA_CHECK(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z && std::isfinite(lo.x + lo.y + lo.z + hi.x + hi.y + hi.z),
                   "penumbra::lightViewProjectionForBounds: empty or non-finite bounds");
    const glm::vec3 center = 0.5f * (lo + hi);
    const float radius = std::max(0.5f * glm::length(hi - lo), 1e-6f);
    if (light.w != 0.0f) {
        const glm::vec3 eye(light);
        const float distance = glm::length(center - eye);
        PENUMBRA_CHECK(distance > 1e-6f * radius, "penumbra::lightViewProjectionForBounds: the point light is at the box centre");
        // Cone axis: the mean of the unit vectors to the corners (near the minimal cone's axis; the
        // box centre's direction is a poor axis for a low light over a wide ground).
        glm::vec3 axis(0.0f);
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
            const glm::vec3 v = corner - eye;
            const float length = glm::length(v);
            if (length > 0.0f) axis += v / length;
        }
        const glm::vec3 dir = glm::length(axis) > 1e-6f ? glm::normalize(axis) : (center - eye) / distance;
        float max_angle = 0.0f, min_depth = 1e30f, max_depth = 0.0f;
        for (int k = 0; k < 8; ++k) {
            const glm::vec3 corner((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z);
            const glm::vec3 v = corner - eye;
            const float depth = glm::dot(v, dir);
            const float length = glm::length(v);
            const float angle = depth > 0.0f ? std::acos(std::min(1.0f, depth / length)) : 3.2f;
            max_angle = std::max(max_angle, angle);
            min_depth = std::min(min_depth, depth);
            max_depth = std::max(max_depth, depth);
        }
        PENUMBRA_CHECK(max_angle < 1.4835f, "penumbra::lightViewProjectionForBounds: the point light (", eye.x, ", ",
                       eye.y, ", ", eye.z, ") would need a cone of half-angle ", max_angle * 57.2958f,
                       " degrees (> 85) to see the box: inside it or too close; use one frustum per cube face");
        const glm::vec3 up = std::abs(dir.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        const float near_plane = std::max(1e-3f * std::max(min_depth, 0.0f), 1e-6f * max_depth);
        // The cone's half-angle bounds every corner's angle; the square frustum's half-angle per
        // axis must reach it: tan(fov/2) = tan(max_angle) (a slight superset at the diagonals).
        const float fov = 2.0f * std::atan(std::tan(max_angle) * 1.01f);
        return glm::perspective(fov, 1.0f, near_plane, max_depth * 1.01f) * glm::lookAt(eye, eye + dir, up);
    }
    const glm::vec3 dir = glm::normalize(glm::vec3(light));  // towards the light
    PENUMBRA_CHECK(std::isfinite(dir.x), "penumbra::lightViewProjectionForBounds: zero light direction");
    const glm::vec3 up = std::abs(dir.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    const glm::vec3 eye = center + dir * (2.0f * radius);
    return glm::ortho(-radius, radius, -radius, radius, 0.5f * radius, 3.5f * radius) * glm::lookAt(eye, center, up);
}

/// The conservative-raster setup the light pass uses: the W x H grid, nothing clipped but the
/// light's eye plane (w >= min_w): a caster between the light and the near plane still blocks.
inline ConservativeRasterSetup afhConservativeSetup(const AliasFreeHardOptions& options) {
    ConservativeRasterOptions cr;
    cr.viewport_width = static_cast<int>(options.grid_width);
    cr.viewport_height = static_cast<int>(options.grid_height);
    cr.variant = options.variant;
    cr.clip_to_box = options.clip_to_box;
    cr.near_plane = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    return conservativeRasterSetup(cr);
}

inline void validateAliasFreeHardOptions(const AliasFreeHardOptions& o, const glm::vec4& light) {
    PENUMBRA_CHECK(o.grid_width >= 1 && o.grid_height >= 1 && o.grid_width <= kSampleListsMaxGridSide &&
                       o.grid_height <= kSampleListsMaxGridSide,
                   "penumbra::AliasFreeHardShadows: grid ", o.grid_width, "x", o.grid_height, " is outside [1, ",
                   kSampleListsMaxGridSide, "]");
    PENUMBRA_CHECK(o.coplanar_epsilon >= 0 && o.coplanar_epsilon <= 0.1,
                   "penumbra::AliasFreeHardShadows: coplanar_epsilon ", o.coplanar_epsilon, " is outside [0, 0.1]");
    PENUMBRA_CHECK(o.sample_offset >= 0 && std::isfinite(o.sample_offset),
                   "penumbra::AliasFreeHardShadows: sample_offset ", o.sample_offset, " must be finite and >= 0");
    PENUMBRA_CHECK(o.list_block >= 1 && o.list_block <= 16384,
                   "penumbra::AliasFreeHardShadows: list_block ", o.list_block, " is outside [1, 16384]");
    PENUMBRA_CHECK(std::isfinite(light.x) && std::isfinite(light.y) && std::isfinite(light.z) &&
                       (light.w == 0.0f || light.w == 1.0f),
                   "penumbra::AliasFreeHardShadows: light must be finite with w = 1 (point) or 0 (directional)");
    if (light.w == 0.0f) {
        PENUMBRA_CHECK(std::abs(glm::length(glm::vec3(light)) - 1.0f) < 1e-4f,
                       "penumbra::AliasFreeHardShadows: a directional light's xyz must be a unit vector, got length ",
                       glm::length(glm::vec3(light)));
        PENUMBRA_CHECK(o.directional_reach > 0 && std::isfinite(o.directional_reach),
                       "penumbra::AliasFreeHardShadows: directional lights need directional_reach > 0, got ",
                       o.directional_reach);
    }
}

inline AfhParams afhParams(const AliasFreeHardOptions& o, const glm::vec4& light, uint32_t block, uint32_t flags) {
    AfhParams p{};
    p.light = light;
    p.tolerance = glm::vec4(static_cast<float>(o.coplanar_epsilon), o.sample_offset, o.directional_reach, 0.0f);
    p.grid = glm::uvec4(o.grid_width, o.grid_height, o.list_block, flags);
    p.pass = glm::uvec4(block, 0u, 0u, 0u);
    return p;
}

// ---------------------------------------------------------------------------------------------
// CPU twin

namespace detail {

template <typename Real>
Real afhMaxAbs(const glm::tvec3<Real>& v) {
    return std::max(std::abs(v.x), std::max(std::abs(v.y), std::abs(v.z)));
}

template <typename Real>
Real afhDet(const glm::tvec3<Real>& u, const glm::tvec3<Real>& v, const glm::tvec3<Real>& w) {
    const Real cx = u.y * v.z - u.z * v.y;
    const Real cy = u.z * v.x - u.x * v.z;
    const Real cz = u.x * v.y - u.y * v.x;
    return cx * w.x + cy * w.y + cz * w.z;
}

}  // namespace detail

/// The blocker test of blocker_test.glsl, same operations in the same order (Real = double for
/// the exact mode, float for the fast one).
template <typename Real>
bool afhBlocks(const glm::tvec3<Real>& a, const glm::tvec3<Real>& b, const glm::tvec3<Real>& c,
               const glm::tvec3<Real>& p, const glm::tvec3<Real>& l, Real coplanar_epsilon, Real offset) {
    const glm::tvec3<Real> ab = b - a, ac = c - a;
    const Real nx = ab.y * ac.z - ab.z * ac.y;
    const Real ny = ab.z * ac.x - ab.x * ac.z;
    const Real nz = ab.x * ac.y - ab.y * ac.x;
    const glm::tvec3<Real> ap = p - a, al = l - a;
    const Real dp = nx * ap.x + ny * ap.y + nz * ap.z;
    const Real dl = nx * al.x + ny * al.y + nz * al.z;
    if (!((dp < 0 && dl > 0) || (dp > 0 && dl < 0))) return false;
    const Real nn = nx * nx + ny * ny + nz * nz;
    const Real scale = std::max(std::max(detail::afhMaxAbs<Real>(a - p), detail::afhMaxAbs<Real>(b - p)),
                                std::max(detail::afhMaxAbs<Real>(c - p), detail::afhMaxAbs<Real>(l - p)));
    const Real tol = coplanar_epsilon * scale;
    const Real threshold = tol * tol * nn;
    if (dp * dp <= threshold && detail::pointTriangleDistance2<Real>(p, a, b, c) <= tol * tol) return false;
    if (dl * dl <= threshold && detail::pointTriangleDistance2<Real>(l, a, b, c) <= tol * tol) return false;
    if (offset > 0 && dp * dp <= offset * offset * nn) return false;
    const glm::tvec3<Real> la = a - l, lb = b - l, lc = c - l, lp = p - l;
    const Real e0 = detail::afhDet(la, lb, lp), e1 = detail::afhDet(lb, lc, lp), e2 = detail::afhDet(lc, la, lp);
    const bool nonnegative = e0 >= 0 && e1 >= 0 && e2 >= 0;
    const bool nonpositive = e0 <= 0 && e1 <= 0 && e2 <= 0;
    const bool zero = e0 == 0 && e1 == 0 && e2 == 0;
    return (nonnegative || nonpositive) && !zero;
}

/// A caster triangle soup for the CPU twin: triangle t = indices[3t..3t+2]; closed[t] = its mesh
/// is closed.
struct AfhCasters {
    const std::vector<glm::vec3>* positions = nullptr;
    const std::vector<uint32_t>* indices = nullptr;
    const std::vector<uint8_t>* closed = nullptr;
};

/// CPU twin of AliasFreeHardShadows::run after the fit: builds the same lists (buildSampleListsCpu
/// with `light`, whose view_projection must be the frame's light_view_projection), tests every
/// caster against the samples of the texels its clipped projection's bounding box touches (a
/// superset of the GPU's conservative coverage: the test itself decides) and returns one state per
/// sample id, equal to the GPU's stateBuffer().
inline std::vector<uint32_t> aliasFreeHardCpu(const AliasFreeHardOptions& options, const SampleListsLight& light,
                                              const glm::vec4* positions, const glm::vec4* normals,
                                              uint32_t sample_count, const AfhCasters& casters) {
    validateAliasFreeHardOptions(options, light.light);
    PENUMBRA_CHECK(casters.positions && casters.indices && casters.closed &&
                       casters.closed->size() * 3 == casters.indices->size(),
                   "penumbra::aliasFreeHardCpu: casters need positions, indices and one closed flag per triangle");
    const SampleListsSetup setup = sampleListsSetup(options.grid_width, options.grid_height, sample_count);
    SampleListsOptions list_options;
    list_options.depth_range = LightDepthRange::Unclipped;
    const SampleListsCpu lists = buildSampleListsCpu(setup, light, positions, normals, list_options);
    std::vector<uint8_t> shadowed(sample_count, 0);
    const ConservativeRasterSetup cr = afhConservativeSetup(options);
    const bool point = light.light.w != 0.0f;
    const glm::dvec3 lpos(light.light);
    const double reach = options.directional_reach;
    const auto& P = *casters.positions;
    const auto& I = *casters.indices;
    for (size_t t = 0; t < casters.closed->size(); ++t) {
        const glm::vec3 v[3] = {P[I[3 * t]], P[I[3 * t + 1]], P[I[3 * t + 2]]};
        if ((*casters.closed)[t] && options.back_faces_only) {
            const glm::dvec3 a(v[0]), b(v[1]), c(v[2]);
            const glm::dvec3 to_light = point ? lpos - a : lpos;
            if (glm::dot(glm::cross(b - a, c - a), to_light) >= 0.0) continue;
        }
        const glm::vec4 clip[3] = {light.view_projection * glm::vec4(v[0], 1.0f),
                                   light.view_projection * glm::vec4(v[1], 1.0f),
                                   light.view_projection * glm::vec4(v[2], 1.0f)};
        const std::vector<glm::dvec2> polygon = conservativeReferencePolygon(clip[0], clip[1], clip[2], cr);
        if (polygon.empty()) continue;
        glm::dvec2 lo(1e300), hi(-1e300);
        for (const auto& q : polygon) {
            lo = glm::min(lo, q);
            hi = glm::max(hi, q);
        }
        const int x0 = std::max(0, static_cast<int>(std::floor(lo.x)) - 1);
        const int y0 = std::max(0, static_cast<int>(std::floor(lo.y)) - 1);
        const int x1 = std::min(static_cast<int>(options.grid_width) - 1, static_cast<int>(std::floor(hi.x)) + 1);
        const int y1 = std::min(static_cast<int>(options.grid_height) - 1, static_cast<int>(std::floor(hi.y)) + 1);
        const glm::dvec3 a(v[0]), b(v[1]), c(v[2]);
        const glm::vec3 af(v[0]), bf(v[1]), cf(v[2]);
        for (int y = y0; y <= y1; ++y) {
            for (int x = x0; x <= x1; ++x) {
                const size_t list = size_t(y) * options.grid_width + size_t(x);
                for (uint32_t k = 0; k < lists.counts[list]; ++k) {
                    const uint32_t slot = lists.offsets[list] + k;
                    const uint32_t id = lists.list_ids[slot];
                    if (shadowed[id]) continue;
                    const glm::vec3 pf(lists.list_positions[slot]);
                    bool blocked;
                    if (options.precision == AfhPrecision::Exact) {
                        const glm::dvec3 p(pf);
                        const glm::dvec3 l = point ? lpos : p + lpos * reach;
                        blocked = afhBlocks<double>(a, b, c, p, l, options.coplanar_epsilon, double(options.sample_offset));
                    } else {
                        const glm::vec3 lf = point ? glm::vec3(light.light) : pf + glm::vec3(light.light) * options.directional_reach;
                        blocked = afhBlocks<float>(af, bf, cf, pf, lf, static_cast<float>(options.coplanar_epsilon),
                                                   options.sample_offset);
                    }
                    if (blocked) shadowed[id] = 1;
                }
            }
        }
    }
    std::vector<uint32_t> states(sample_count);
    for (uint32_t id = 0; id < sample_count; ++id) {
        if (lists.sample_slots[id] != kSampleListsNoSlot) {
            states[id] = shadowed[id] ? PENUMBRA_AFH_SHADOWED : PENUMBRA_AFH_LIT;
        } else {
            const uint32_t reason = lists.sample_texels[id] - PENUMBRA_SAMPLE_LISTS_REJECTED;
            states[id] = reason == PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND    ? PENUMBRA_AFH_NO_SAMPLE
                         : reason == PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING ? PENUMBRA_AFH_BACK_FACING
                                                                              : PENUMBRA_AFH_UNTESTED;
        }
    }
    return states;
}

// ---------------------------------------------------------------------------------------------
// GL execution

/// The pipeline: owns its programs and the list/shadow/state buffers (RAII, movable).
class AliasFreeHardShadows {
public:
    using DrawCasters = std::function<void(CasterClass)>;

    explicit AliasFreeHardShadows(const AliasFreeHardOptions& options,
                                  const ShaderLibrary& library = ShaderLibrary::embedded())
        : options_(options), builder_(library) {
        validateAliasFreeHardOptions(options_, glm::vec4(0, 0, 0, 1));
        conservative_ = afhConservativeSetup(options_);
        ShaderDefines defines = conservative_.defines;
        defines.push_back({"PENUMBRA_AFH_EXACT", options_.precision == AfhPrecision::Exact ? "1" : "0"});
        // blocker_test.glsl: float filter with a proven bound in front of the double test (same bits).
        defines.push_back({"PENUMBRA_AFH_FILTERED", options_.fp64_only ? "0" : "1"});
        defines.push_back({"PENUMBRA_AFH_COUNT_WORK", options_.count_work ? "1" : "0"});
        defines.push_back({"PENUMBRA_AFH_SKIP_SHADOWED", options_.skip_shadowed ? "1" : "0"});
        light_pass_ = gl::buildProgram({"penumbra/alias_free_hard/light_pass.vert.glsl",
                                        "penumbra/alias_free_hard/light_pass.geom.glsl",
                                        "penumbra/alias_free_hard/light_pass.frag.glsl"},
                                       defines, library);
        resolve_ = gl::buildComputeProgram("penumbra/alias_free_hard/resolve.comp.glsl", {}, library);
        conservative_params_ = gl::Buffer(sizeof(ConservativeRasterParams), &conservative_.params, GL_DYNAMIC_STORAGE_BIT);
        afh_params_ = gl::Buffer(sizeof(AfhParams), nullptr, GL_DYNAMIC_STORAGE_BIT);
        work_ = gl::Buffer(PENUMBRA_AFH_WORK_WORDS * 4);
        glCreateFramebuffers(1, &framebuffer_);
        glNamedFramebufferParameteri(framebuffer_, GL_FRAMEBUFFER_DEFAULT_WIDTH, static_cast<GLint>(options_.grid_width));
        glNamedFramebufferParameteri(framebuffer_, GL_FRAMEBUFFER_DEFAULT_HEIGHT, static_cast<GLint>(options_.grid_height));
        gl::checkErrors("penumbra::AliasFreeHardShadows");
    }
    // Owns a raw GL name (framebuffer): not movable; hold it in a std::unique_ptr to move it.
    AliasFreeHardShadows(AliasFreeHardShadows&&) = delete;
    AliasFreeHardShadows(const AliasFreeHardShadows&) = delete;
    AliasFreeHardShadows& operator=(const AliasFreeHardShadows&) = delete;
    ~AliasFreeHardShadows() {
        if (framebuffer_) glDeleteFramebuffers(1, &framebuffer_);
    }

    const AliasFreeHardOptions& options() const { return options_; }

    /// Runs every pass (see the summary). `light.view_projection` must see all samples that should
    /// be tested (others come out PENUMBRA_AFH_UNTESTED).
    const AliasFreeHardFrame& run(const SampleBufferInput& input, uint32_t sample_count, const SampleListsLight& light,
                                  const DrawCasters& draw_casters) {
        validateAliasFreeHardOptions(options_, light.light);
        PENUMBRA_CHECK(static_cast<bool>(draw_casters), "penumbra::AliasFreeHardShadows::run: no caster callback");
        frame_ = AliasFreeHardFrame{};
        setup_ = sampleListsSetup(options_.grid_width, options_.grid_height, sample_count);
        allocate(setup_);
        SampleListsOptions list_options;
        list_options.depth_range = LightDepthRange::Unclipped;
        SampleListsLight fitted = light;
        if (options_.fit_frustum && sample_count > 0) {
            frame_.fit = builder_.fitLightFrustum(setup_, light, input, header_.id(), list_options);
            if (frame_.fit.valid) fitted.view_projection = frame_.fit.view_projection;
        }
        frame_.light_view_projection = fitted.view_projection;
        builder_.build(setup_, fitted, input, buffers(), list_options);
        frame_.statistics = builder_.statistics(setup_, buffers());
        frame_.passes = static_cast<uint32_t>(detail::divUp(frame_.statistics.max_list_length, options_.list_block));

        shadow_.fill(0u);
        if (options_.count_work) work_.fill(0u);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
        glViewport(0, 0, static_cast<GLsizei>(options_.grid_width), static_cast<GLsizei>(options_.grid_height));
        glDisable(GL_DEPTH_TEST);
        glDisable(GL_CULL_FACE);
        glDisable(GL_RASTERIZER_DISCARD);
        glEnable(GL_DEPTH_CLAMP);  // casters nearer than the near plane or beyond the far plane still cast
        light_pass_.use();
        glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(fitted.view_projection));
        glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_CONSERVATIVE_PARAMS_BINDING, conservative_params_.id());
        glBindBufferBase(GL_UNIFORM_BUFFER, PENUMBRA_AFH_PARAMS_BINDING, afh_params_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_COUNTS_BINDING, counts_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_OFFSETS_BINDING, offsets_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_POSITIONS_BINDING, list_positions_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_SHADOW_BINDING, shadow_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_WORK_BINDING, work_.id());
        for (uint32_t block = 0; block < frame_.passes; ++block) {
            for (CasterClass cls : {CasterClass::Closed, CasterClass::Open}) {
                const bool cull = cls == CasterClass::Closed && options_.back_faces_only;
                const AfhParams params = afhParams(options_, light.light, block, cull ? PENUMBRA_AFH_FLAG_CLOSED : 0u);
                glNamedBufferSubData(afh_params_.id(), 0, sizeof params, &params);
                light_pass_.use();
                draw_casters(cls);
            }
            // Later blocks read the bits earlier ones wrote (the skip of shadowed samples).
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        }
        glDisable(GL_DEPTH_CLAMP);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);

        resolve_.use();
        glUniform1ui(0, sample_count);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_SLOTS_BINDING, sample_slots_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_TEXELS_BINDING, sample_texels_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_SHADOW_BINDING, shadow_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, PENUMBRA_AFH_STATES_BINDING, states_.id());
        const detail::DispatchGrid grid = detail::foldDispatch(detail::divUp(sample_count, 256));
        if (grid.groups) glDispatchCompute(grid.x, grid.y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        if (options_.count_work) {
            const std::vector<uint32_t> work = work_.download<uint32_t>(0, PENUMBRA_AFH_WORK_WORDS);
            frame_.fragments = work[PENUMBRA_AFH_WORK_FRAGMENTS];
            frame_.tests = work[PENUMBRA_AFH_WORK_TESTS];
            frame_.triangles_emitted = work[PENUMBRA_AFH_WORK_TRIANGLES];
            frame_.fallbacks = work[PENUMBRA_AFH_WORK_FALLBACKS];
        }
        gl::checkErrors("penumbra::AliasFreeHardShadows::run");
        return frame_;
    }

    const AliasFreeHardFrame& frame() const { return frame_; }
    /// uint per view-sample id: PENUMBRA_AFH_* states.
    const gl::Buffer& stateBuffer() const { return states_; }
    /// The lists of the last run (positions, ids, slots ... see SampleListsBuffers).
    SampleListsBuffers buffers() const {
        return {counts_.id(), offsets_.id(), list_positions_.id(), list_ids_.id(), sample_slots_.id(),
                sample_texels_.id(), header_.id()};
    }
    const SampleListsSetup& setup() const { return setup_; }
    const gl::Buffer& shadowBits() const { return shadow_; }

private:
    AliasFreeHardOptions options_;
    SampleListBuilder builder_;
    ConservativeRasterSetup conservative_;
    gl::Program light_pass_, resolve_;
    gl::Buffer conservative_params_, afh_params_, work_;
    gl::Buffer counts_, offsets_, list_positions_, list_ids_, sample_slots_, sample_texels_, header_, shadow_, states_;
    size_t capacity_ = size_t(-1);
    GLuint framebuffer_ = 0;
    SampleListsSetup setup_;
    AliasFreeHardFrame frame_;

    void allocate(const SampleListsSetup& s) {
        if (!header_.id()) {
            counts_ = gl::Buffer(s.counts_bytes);
            offsets_ = gl::Buffer(s.offsets_bytes);
            header_ = gl::Buffer(s.header_bytes);
        }
        // Buffers of zero bytes are not created; keep at least one element so bindings stay valid.
        const size_t samples = std::max<size_t>(s.sample_count, 1);
        if (capacity_ != size_t(-1) && samples <= capacity_) return;
        list_positions_ = gl::Buffer(samples * 16);
        list_ids_ = gl::Buffer(samples * 4);
        sample_slots_ = gl::Buffer(samples * 4);
        sample_texels_ = gl::Buffer(samples * 4);
        shadow_ = gl::Buffer(std::max<size_t>(shadowBitsBytes(samples, 1), 4));
        states_ = gl::Buffer(samples * 4);
        capacity_ = samples;
    }
};

}  // namespace penumbra

#endif
