// penumbra — alias-free hard shadows (sintorn2008 §3, Fig. 2–4): the first pipeline, composed only
// from the blocks' public APIs. This header is the GL-free part — options, pure setup (light
// frustum, conservative setup, parameter blocks) and the CPU twin; the GL executor is
// penumbra/gl/pipelines/alias_free_hard.hpp (its header comment is the integration summary).
//
// Exactness. AfhPrecision::Exact (default) runs the plane tests in double with the oracle's
// coplanar rule (blocker_test.glsl; the epsilon reaches the GPU in double): on every (sample,
// light) pair the oracle does not flag as a tie, the result equals
// reference::VisibilityOracle::segmentBlocked with the same coplanar_epsilon and scene_extent =
// the oracle's sceneExtent() (needed once the light is farther than the scene is wide) — tests check 0
// mismatches, on the same float positions the GPU used (buffer or depth-reconstructed samples).
// AfhPrecision::Fast uses float planes and an optional sample offset toward the light; its
// mismatches are measured, not assumed.
// Casters: every triangle casts by default (back_faces_only = false: exact everywhere). The §3.3
// rule (closed, outward-oriented meshes cast only light-back-facing triangles: half the
// light-pass work, no bias) is an option: exact for every sample outside a closed mesh, it misses
// a sample lying exactly in a concave crease lit at a grazing angle that enters the solid right
// at the sample (measured: 1 of 150 209 samples of the torus knot at 512x384). Samples lying on a
// surface are never shadowed by it (the coplanar rule), so open receivers need no bias either.
// Coordinates: view samples, caster positions and the light share one frame. Far from the
// world origin use a camera- or light-relative frame — subtract a double origin on the host
// (relativePosition) before anything becomes float; floats of 1e6-sized coordinates carry
// only ~0.06 units of precision, and no exact test can recover what the rounding lost.
// Light pass (ConservativeVariant::Fixed6, the default): the casters' geometry stage declares the
// seed's max_vertices = 6 (sintorn2008 §3.2); triangles that need clipping (they cross the light's
// eye plane w = min_w or the guard band: 0-18 per run in the tests) go to a spill pass drawn
// indirectly at max_vertices 13 — the same fragments and states as one pass at 13. Its buffers hold
// spill_capacity triangles (default: max_caster_triangles, else 65 536); a triangle past that is
// not rasterized and counted (AliasFreeHardFrame::spill_overflow): results are exact only when it
// is 0. fixed6_two_pass = false keeps the single pass; ConservativeVariant::Exact always has one.
// Point lights: all samples must lie in front of the light (one frustum; a light inside the
// scene needs one pipeline run per cube face). Directional lights: each sample's light point is
// taken `directional_reach` along the light direction: exact for casters within that distance.
#ifndef PENUMBRA_PIPELINES_ALIAS_FREE_HARD_HPP
#define PENUMBRA_PIPELINES_ALIAS_FREE_HARD_HPP

#include "penumbra/detail/shared.hpp"
#include <penumbra/alias_free_hard/alias_free_hard_shared.h>

#include "penumbra/conservative_raster.hpp"
#include "penumbra/detail/blocker_filter.hpp"
#include "penumbra/detail/geometry.hpp"
#include "penumbra/pipelines/caster_class.hpp"
#include "penumbra/sample_lists.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

namespace penumbra {

using AfhParams = shared::PenumbraAfhParams;
static_assert(sizeof(AfhParams) == 80 && offsetof(AfhParams, exact) == 64,
              "PenumbraAfhParams must be 80 bytes with the dvec2 at 64 (std140 == std430)");
static_assert(sizeof(shared::PenumbraAfhSpillWorldHeader) == 16 && sizeof(shared::PenumbraAfhSpillWorld) == 48,
              "std430 layout light_pass.geom.glsl assumes: a uvec4 header, three vec4 per spilled triangle");

enum class AfhPrecision { Exact, Fast };

/// How the light pass finds the (caster triangle, light texel) pairs it tests.
///   Raster:  a draw of your casters per class and list block (DrawCasters callback): vertex,
///            geometry (the conservative emitter) and fragment stages, an occupancy stencil and
///            occlusion-query predicates.
///   Compute: casters as buffers (CasterBuffer, with the caster hook
///            penumbra/sample_based_soft/caster_buffer.glsl); a setup pass per triangle (the same
///            culls and the emitter's pixel-expanded box, bit for bit), a scan, and a tiles pass
///            of one work group per (triangle, 8 x 8 texels of its box): no draw, query, stencil or
///            framebuffer; no geometry shader is compiled. Same shadow bits and states.
enum class AfhLightPass { Raster, Compute };

/// The compute light pass's chunk by default: triangles set up between two tiles passes.
inline constexpr uint32_t kAfhDefaultComputeTriangles = 65536;

/// Value-initialised = defaults, except the grid size, which must be set.
struct AliasFreeHardOptions {
    uint32_t grid_width = 0, grid_height = 0;  ///< light grid W x H (sintorn2008 uses the view size)
    ConservativeVariant variant = ConservativeVariant::Fixed6;
    AfhPrecision precision = AfhPrecision::Exact;
    /// Exact mode only: run every blocker test in double (true) instead of the float filter with a
    /// proven error bound that falls back to double where a sign is uncertain (false, default;
    /// identical results: blocker_test.glsl, detail/blocker_filter.hpp). fp64 runs at 1/32-1/64
    /// rate on consumer GPUs; on llvmpipe it is nearly free, so there the filter costs ~25%.
    bool fp64_only = false;
    double coplanar_epsilon = 1e-7;  ///< the oracle's coplanar rule (relative); above view-sample float noise (~1 ulp)
    /// E of the coplanar rule's scale (world units, > 0): the light's distance counts at most E, as in
    /// the oracle; pass VisibilityOracle::sceneExtent() of the casters. +inf = the uncapped rule
    /// (lights ~1 / coplanar_epsilon scene sizes away then lose their shadows; issue 41).
    double scene_extent = std::numeric_limits<double>::infinity();
    float sample_offset = 0.0f;      ///< world units; see the summary (0 = exact geometry)
    float directional_reach = 0.0f;  ///< directional lights: > 0, at least the scene's extent
    bool fit_frustum = true;         ///< §4.3
    uint32_t list_block = 2048;      ///< samples one fragment walks per pass (llvmpipe caps loops at 65 535)
    /// Documented upper bound on light-pass blocks (the caster callback runs this many times per
    /// class; blocks no list needs are skipped on the GPU by conditional rendering). Samples past
    /// max_list_blocks * list_block in their list come out PENUMBRA_AFH_UNTESTED and are counted
    /// (AliasFreeHardFrame::overflow). In [1, 64].
    uint32_t max_list_blocks = 8;
    bool count_work = false;         ///< atomics counting fragments, tests and emitted triangles
    // Skips (each proven bit-identical by the tests): a fragment does not retest a sample another
    // caster already shadowed; fragments outside the triangle's pixel-expanded box are discarded.
    bool skip_shadowed = true;
    bool clip_to_box = true;
    /// GPU only: an occupancy stencil (one full-screen pass per list block, GL_STENCIL_INDEX8 at
    /// the grid's size) lets the light pass cull, by the early stencil test, the fragments of
    /// texels whose list block holds no sample; such a fragment tests nothing, so the bits are the
    /// same. Most of a sparse run's fragments (anti-aliasing's edge run) are such.
    bool skip_empty_texels = true;
    /// §3.3: closed casters cast only their light-back-facing triangles (about half the light-pass
    /// work). Off by default: it is exact for every sample outside a closed mesh but misses a
    /// sample lying exactly in a concave crease of a closed surface, lit at a grazing angle that
    /// enters the solid right at the sample (the entry is at the segment's excluded endpoint;
    /// measured: 1 of 150 209 samples of the torus knot at 512x384). Use it when closed meshes
    /// are watertight and such creases are rare or invisible; leave it off for exact results.
    bool back_faces_only = false;
    /// The exact cull of closed casters (SoftSkips::closed_casters' argument with a point light):
    /// closed casters cast only their triangles that do not face away from the light; a triangle
    /// with the light strictly behind its plane (beyond the rounding bound of
    /// detail::afhFacesAway) is culled once in the geometry stage. A blocked segment leaves the
    /// solid it crosses through a face with the light in front, so no bit changes (the tests
    /// compare on and off bit for bit); about half of a closed mesh's triangles go. Not with
    /// back_faces_only (the two keep opposite halves).
    bool light_facing_only = false;
    /// ConservativeVariant::Fixed6 only: the two-pass light pass (default) — a direct pass whose
    /// geometry stage declares the seed's max_vertices = 6 (sintorn2008 §3.2; the declared output
    /// size sets GS throughput on real GPUs) and an indirect spill pass (max_vertices 13) for the
    /// triangles that need clipping (they cross the light's eye plane or the guard band); same
    /// fragments, same states. false: the single pass at max_vertices 13 (for comparison).
    /// ConservativeVariant::Exact always runs one pass at 13 (its unclipped hull alone needs 7).
    bool fixed6_two_pass = true;
    /// Two-pass plan: the most caster triangles one call of your DrawCasters callback draws per
    /// list block, both classes together (0 = not given). Sizes the spill buffers so that they can
    /// never overflow, whatever the light.
    uint32_t max_caster_triangles = 0;
    /// Two-pass plan: triangles the spill buffers hold (0 = max_caster_triangles, or
    /// kConservativeDefaultSpillCapacity = 65 536 when that is 0 too; at most
    /// kConservativeMaxSpillCapacity). 112 bytes each, allocated once at construction. A triangle
    /// that needs clipping and finds the buffers full is NOT rasterized — shadows it casts may be
    /// missing; AliasFreeHardFrame::spill_overflow counts such triangles (0 = results exact).
    uint32_t spill_capacity = 0;
    /// Raster (default) or Compute; see AfhLightPass. The raster-only options (variant's hull,
    /// clip_to_box, skip_empty_texels, fixed6_two_pass, the spill sizes) do not change what the
    /// compute pass does.
    AfhLightPass light_pass = AfhLightPass::Raster;
    /// Compute light pass: triangles the setup records hold (64 bytes and 4 bytes each, allocated
    /// at construction; 0 = kAfhDefaultComputeTriangles, in [64, 2^24]). More caster triangles
    /// than that run in several chunks (each a setup, a scan and a tiles pass;
    /// AliasFreeHardFrame::chunks): same bits, nothing dropped. The grid also caps a chunk, so that
    /// its (triangle, tile) items stay below 2^31: afhComputeChunk().
    uint32_t compute_triangles = 0;
};

/// A square light grid's side for `samples` view samples: sintorn2008's light grid of the view's
/// size (one texel per view sample) carried over to runs whose samples are not one per pixel, such
/// as anti-aliasing's full run (P (1 + N) samples) and edge run (the flagged pixels'
/// sub-samples). It is 2^e for the integer e nearest log2(sqrt(samples)) + 1/4, within
/// [16, kSampleListsMaxGridSide]: about one texel per sample, a quarter octave finer, so that
/// 2^(2e - 1.5) <= samples < 2^(2e + 0.5). Too coarse a grid lengthens every texel's list; too
/// fine a one multiplies the light pass's fragments. On llvmpipe at a 512^2 view
/// (BM_ShadowEdgeStencil, 2026-12-05) the edge runs of 21k-120k sub-samples were fastest, or
/// within 5 %, at the side this returns (hairball, 69k: 480 ms at 256^2, 610 ms at 512^2,
/// 1230 ms at 1024^2, 590 ms at 128^2). The 200k-sample single-sample runs were fastest at 512^2.
/// A starting point: the best side depends on the casters and the driver.
inline uint32_t afhGridSideForSamples(uint64_t samples) {
    uint32_t e = 0;  // 2^(2 (e + 1) - 1.5) <= samples: one step up
    while (e < 30 && double(samples) >= std::ldexp(0.35355339059327373, int(2 * (e + 1)))) ++e;
    return static_cast<uint32_t>(std::clamp<uint64_t>(uint64_t(1) << e, 16, kSampleListsMaxGridSide));
}

/// What one run did.
/// What one run did: AliasFreeHardShadows::readFrame() reads it back on request (it waits for the
/// GPU; run() itself reads nothing back).
struct AliasFreeHardFrame {
    glm::mat4 light_view_projection{1.0f};  ///< the (fitted) matrix the lists and the light pass used
    LightFrustumFit fit;                    ///< valid == false when fitting was off or found no sample
    SampleListStatistics statistics;        ///< Fig. 9, of the lists the light pass walked
    uint32_t passes = 0;                    ///< list blocks the GPU drew (<= max_list_blocks)
    uint64_t overflow = 0;                  ///< samples left untested past the last block
    uint64_t fragments = 0, tests = 0, triangles_emitted = 0;  ///< when count_work
    uint64_t fallbacks = 0;  ///< when count_work, exact filtered mode: blocker tests decided in double
    /// What the skips removed (count_work): samples skip_shadowed did not retest, fragments
    /// clip_to_box discarded, closed casters' triangles culled (back_faces_only / light_facing_only).
    uint64_t tests_skipped = 0, fragments_skipped = 0, triangles_culled = 0;
    /// Fixed-6 two-pass light pass (always counted, list block 0; every block draws the same
    /// casters): caster triangles the direct pass handed to the spill pass (those that need
    /// clipping, afhSpilledTriangles() on the CPU), and of them the ones lost because the spill
    /// buffers were full (not rasterized: shadows may be missing; raise spill_capacity).
    uint64_t spilled = 0, spill_overflow = 0;
    /// Compute light pass (always counted): chunks the casters took (set on the host), (triangle,
    /// tile) items the tiles passes ran (each list block reruns them), and caster triangles naming
    /// a vertex past their CasterBuffer's positions (they cast nothing).
    uint64_t chunks = 0, items = 0, caster_indices_out_of_range = 0;
};

/// p - origin computed in double, then rounded once to float: the camera- or light-relative
/// coordinates the GPU path needs far from the world origin (see the file comment).
inline glm::vec3 relativePosition(const glm::dvec3& p, const glm::dvec3& origin) { return glm::vec3(p - origin); }

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
        // Squared lengths of the frustum's float maths overflow near 1.8e19: refuse rather than NaN.
        const double far = glm::length(glm::dvec3(center) - glm::dvec3(eye));
        PENUMBRA_CHECK(far <= 1e18, "penumbra::lightViewProjectionForBounds: the point light (", eye.x, ", ", eye.y, ", ",
                       eye.z, ") is ", far, " from the box centre, beyond the limit of 1e18; use a directional light");
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
            // atan2, not acos(depth / length): acos near 1 in float resolves no angle below ~3e-4
            // rad, so a box 1e4 away came out narrower than the 1e-4 floor and lost its corners.
            const float angle = depth > 0.0f ? std::atan2(glm::length(glm::cross(v, dir)), depth) : 3.2f;
            max_angle = std::max(max_angle, angle);
            min_depth = std::min(min_depth, depth);
            max_depth = std::max(max_depth, depth);
        }
        // A corner at or behind the light's plane has no cone angle: say so rather than print one.
        PENUMBRA_CHECK(min_depth > 0.0f, "penumbra::lightViewProjectionForBounds: the point light (", eye.x, ", ", eye.y,
                       ", ", eye.z, ") lies inside or beside the box (", lo.x, ", ", lo.y, ", ", lo.z, ") .. (", hi.x, ", ",
                       hi.y, ", ", hi.z, "): part of the box is behind it, so no frustum from it sees all of the box; "
                       "move the light out of the box or use one frustum per cube face");
        PENUMBRA_CHECK(max_angle < 1.4835f, "penumbra::lightViewProjectionForBounds: the point light (", eye.x, ", ",
                       eye.y, ", ", eye.z, ") would need a cone of half-angle ", max_angle * 57.2958f,
                       " degrees (> 85) to see the box: inside it or too close; use one frustum per cube face");
        // A box seen under (almost) no angle (one view sample, or all on one point) still gets a
        // finite frustum: at least 1e-4 rad, so that no entry of the matrix exceeds ~1e4.
        max_angle = std::max(max_angle, 1e-4f);
        const glm::vec3 up = std::abs(dir.y) > 0.99f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        const float near_plane = std::max(1e-3f * std::max(min_depth, 0.0f), 1e-6f * max_depth);
        // The cone's half-angle bounds every corner's angle; the square frustum's half-angle per
        // axis must reach it: tan(fov/2) = tan(max_angle) (a slight superset at the diagonals).
        const float fov = 2.0f * std::atan(std::tan(max_angle) * 1.01f);
        // Aim at a point near the box, not eye + dir: from ~1e7 eye + dir rounds to (almost) eye in
        // float, so the axis was quantised, and NaN from 1e8 (eye + dir == eye).
        return glm::perspective(fov, 1.0f, near_plane, max_depth * 1.01f) * glm::lookAt(eye, eye + dir * distance, up);
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
    cr.max_triangles = options.max_caster_triangles;
    cr.spill_capacity = options.spill_capacity;
    return conservativeRasterSetup(cr);
}

/// True when the light pass runs the Fixed-6 two-pass plan (direct pass at max_vertices 6 + spill).
inline bool afhTwoPass(const AliasFreeHardOptions& options) {
    return options.variant == ConservativeVariant::Fixed6 && options.fixed6_two_pass;
}

/// Bytes of the spill-world buffer for `capacity` spilled triangles (16-byte header + 48 each).
inline uint64_t afhSpillWorldBytes(uint32_t capacity) {
    return sizeof(shared::PenumbraAfhSpillWorldHeader) + uint64_t(capacity) * sizeof(shared::PenumbraAfhSpillWorld);
}

/// The compute light pass's chunk: compute_triangles (or its default), lowered so that the
/// chunk's (triangle, 8 x 8 tile) items stay below 2^31 when every triangle covers the grid.
inline uint32_t afhComputeChunk(const AliasFreeHardOptions& o) {
    const uint64_t wanted = o.compute_triangles != 0 ? o.compute_triangles : kAfhDefaultComputeTriangles;
    const uint64_t tiles = uint64_t((o.grid_width + PENUMBRA_AFH_TILE_WIDTH - 1) / PENUMBRA_AFH_TILE_WIDTH) *
                           ((o.grid_height + PENUMBRA_AFH_TILE_HEIGHT - 1) / PENUMBRA_AFH_TILE_HEIGHT);
    return static_cast<uint32_t>(std::max<uint64_t>(1, std::min<uint64_t>(wanted, (uint64_t(1) << 31) / std::max<uint64_t>(tiles, 1))));
}

/// The compute light pass's tiles items one work group works in turn: 16, fewer for long list
/// blocks so that an invocation's loops stay below 2^15 iterations in all (llvmpipe ends an
/// invocation's loops after 65 535; a tile's item is a search of ~17 steps and one list block).
inline uint32_t afhComputeItemsPerGroup(const AliasFreeHardOptions& o) {
    return std::clamp<uint32_t>(32768u / (o.list_block + 32u), 1u, 16u);
}

inline void validateAliasFreeHardOptions(const AliasFreeHardOptions& o, const glm::vec4& light) {
    PENUMBRA_CHECK(o.grid_width >= 1 && o.grid_height >= 1 && o.grid_width <= kSampleListsMaxGridSide &&
                       o.grid_height <= kSampleListsMaxGridSide,
                   "penumbra::AliasFreeHardShadows: grid ", o.grid_width, "x", o.grid_height, " is outside [1, ",
                   kSampleListsMaxGridSide, "]");
    PENUMBRA_CHECK(!(o.back_faces_only && o.light_facing_only),
                   "penumbra::AliasFreeHardShadows: back_faces_only and light_facing_only keep opposite halves of a "
                   "closed caster; set at most one");
    PENUMBRA_CHECK(o.coplanar_epsilon >= 0 && o.coplanar_epsilon <= 0.1,
                   "penumbra::AliasFreeHardShadows: coplanar_epsilon ", o.coplanar_epsilon, " is outside [0, 0.1]");
    PENUMBRA_CHECK(o.scene_extent > 0,  // NaN fails too; +inf is the uncapped rule
                   "penumbra::AliasFreeHardShadows: scene_extent ", o.scene_extent, " must be > 0 (or +inf)");
    PENUMBRA_CHECK(o.sample_offset >= 0 && std::isfinite(o.sample_offset),
                   "penumbra::AliasFreeHardShadows: sample_offset ", o.sample_offset, " must be finite and >= 0");
    PENUMBRA_CHECK(o.list_block >= 1 && o.list_block <= 16384,
                   "penumbra::AliasFreeHardShadows: list_block ", o.list_block, " is outside [1, 16384]");
    PENUMBRA_CHECK(o.max_list_blocks >= 1 && o.max_list_blocks <= 64,
                   "penumbra::AliasFreeHardShadows: max_list_blocks ", o.max_list_blocks, " is outside [1, 64]");
    PENUMBRA_CHECK(o.spill_capacity <= kConservativeMaxSpillCapacity, "penumbra::AliasFreeHardShadows: spill_capacity ",
                   o.spill_capacity, " is above ", kConservativeMaxSpillCapacity, " triangles");
    PENUMBRA_CHECK(o.spill_capacity != 0 || o.max_caster_triangles <= kConservativeMaxSpillCapacity,
                   "penumbra::AliasFreeHardShadows: max_caster_triangles ", o.max_caster_triangles,
                   " would size spill buffers above ", kConservativeMaxSpillCapacity, " triangles; give a smaller spill_capacity");
    PENUMBRA_CHECK(o.light_pass == AfhLightPass::Raster || o.light_pass == AfhLightPass::Compute,
                   "penumbra::AliasFreeHardShadows: light_pass ", static_cast<int>(o.light_pass), " is neither Raster nor Compute");
    PENUMBRA_CHECK(o.compute_triangles == 0 || (o.compute_triangles >= 64 && o.compute_triangles <= (1u << 24)),
                   "penumbra::AliasFreeHardShadows: compute_triangles ", o.compute_triangles, " is outside [64, 2^24] (0 = ",
                   kAfhDefaultComputeTriangles, ")");
    PENUMBRA_CHECK(o.light_pass == AfhLightPass::Raster || o.light_pass == AfhLightPass::Compute,
                   "penumbra::AliasFreeHardShadows: light_pass ", static_cast<int>(o.light_pass), " is neither Raster nor Compute");
    PENUMBRA_CHECK(o.compute_triangles == 0 || (o.compute_triangles >= 64 && o.compute_triangles <= (1u << 24)),
                   "penumbra::AliasFreeHardShadows: compute_triangles ", o.compute_triangles, " is outside [64, 2^24] (0 = ",
                   kAfhDefaultComputeTriangles, ")");
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

/// The per-frame light check of a run (no throw): finite, w = 1, or w = 0 with a unit direction.
inline bool afhLightValid(const glm::vec4& light) {
    if (!std::isfinite(light.x) || !std::isfinite(light.y) || !std::isfinite(light.z)) return false;
    if (light.w == 1.0f) return true;
    return light.w == 0.0f && std::abs(glm::length(glm::vec3(light)) - 1.0f) < 1e-4f;
}

/// Samples of one list the light pass walks at most (resolve: later ones are UNTESTED).
inline uint32_t afhTestedPerList(const AliasFreeHardOptions& o) { return o.list_block * o.max_list_blocks; }

inline AfhParams afhParams(const AliasFreeHardOptions& o, const glm::vec4& light, uint32_t block, uint32_t flags,
                           uint32_t sample_count = 0) {
    AfhParams p{};
    p.light = light;
    p.tolerance = glm::vec4(0.0f, o.sample_offset, o.directional_reach, 0.0f);
    p.grid = glm::uvec4(o.grid_width, o.grid_height, o.list_block, flags);
    p.pass = glm::uvec4(block, sample_count, afhTestedPerList(o), 0u);
    p.exact = glm::dvec2(o.coplanar_epsilon, o.scene_extent);
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
    using detail::mulRounded;
    const Real cx = mulRounded(u.y, v.z) - mulRounded(u.z, v.y);
    const Real cy = mulRounded(u.z, v.x) - mulRounded(u.x, v.z);
    const Real cz = mulRounded(u.x, v.y) - mulRounded(u.y, v.x);
    return (mulRounded(cx, w.x) + mulRounded(cy, w.y)) + mulRounded(cz, w.z);
}

/// E as the float test takes it: float(min(E, 1e38)) (penumbraAfhFloatExtent; no overflow).
inline float afhFloatExtent(double scene_extent) { return static_cast<float>(std::min(scene_extent, 1e38)); }

}  // namespace detail

/// The blocker test of blocker_test.glsl, same operations in the same order (Real = double for
/// the exact mode, float for the fast one); every product opaque, so no compiler flag fuses them.
/// `scene_extent` caps |l - p| in the coplanar scale (the oracle's E; +inf = uncapped).
template <typename Real>
bool afhBlocks(const glm::tvec3<Real>& a, const glm::tvec3<Real>& b, const glm::tvec3<Real>& c,
               const glm::tvec3<Real>& p, const glm::tvec3<Real>& l, Real coplanar_epsilon, Real offset,
               Real scene_extent = std::numeric_limits<Real>::infinity()) {
    using detail::mulRounded;
    const glm::tvec3<Real> ab = b - a, ac = c - a;
    const Real nx = mulRounded(ab.y, ac.z) - mulRounded(ab.z, ac.y);
    const Real ny = mulRounded(ab.z, ac.x) - mulRounded(ab.x, ac.z);
    const Real nz = mulRounded(ab.x, ac.y) - mulRounded(ab.y, ac.x);
    const glm::tvec3<Real> ap = p - a, al = l - a;
    const Real dp = (mulRounded(nx, ap.x) + mulRounded(ny, ap.y)) + mulRounded(nz, ap.z);
    const Real dl = (mulRounded(nx, al.x) + mulRounded(ny, al.y)) + mulRounded(nz, al.z);
    if (!((dp < 0 && dl > 0) || (dp > 0 && dl < 0))) return false;
    const Real nn = (mulRounded(nx, nx) + mulRounded(ny, ny)) + mulRounded(nz, nz);
    const Real scale = std::max(std::max(detail::afhMaxAbs<Real>(a - p), detail::afhMaxAbs<Real>(b - p)),
                                std::max(detail::afhMaxAbs<Real>(c - p), std::min(detail::afhMaxAbs<Real>(l - p), scene_extent)));
    const Real tol = mulRounded(coplanar_epsilon, scale);
    const Real tol2 = mulRounded(tol, tol);
    const Real threshold = mulRounded(tol2, nn);
    if (mulRounded(dp, dp) <= threshold && detail::pointTriangleDistance2<Real>(p, a, b, c) <= tol2) return false;
    if (mulRounded(dl, dl) <= threshold && detail::pointTriangleDistance2<Real>(l, a, b, c) <= tol2) return false;
    if (offset > 0 && mulRounded(dp, dp) <= mulRounded(mulRounded(offset, offset), nn)) return false;
    // det(a - l, b - l, p - l) taken at p (blocker_test.glsl): no |l|^2 cancellation for far lights.
    const glm::tvec3<Real> bp = p - b, cp = p - c, lp = p - l;
    const Real e0 = detail::afhDet(ap, bp, lp), e1 = detail::afhDet(bp, cp, lp), e2 = detail::afhDet(cp, ap, lp);
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

namespace detail {
/// The light pass's class culling (light_pass.geom.glsl): with back_faces_only, a closed caster's
/// triangle that does not face away from the light casts nothing (§3.3).
/// light_facing_only's test (light_pass.geom.glsl, step for step): facing = n . to_light with
/// n = (b - a) x (c - a) in double from floats is off by at most (dn + 8 eps |n|) |to_light|,
/// dn = 8 eps |b - a| |c - a|; the light is strictly behind when facing is below minus that.
inline bool afhFacesAway(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& to_light) {
    constexpr double eps = 0x1.0p-53;
    const glm::dvec3 e0 = b - a, e1 = c - a;
    const glm::dvec3 n(mulRounded(e0.y, e1.z) - mulRounded(e0.z, e1.y), mulRounded(e0.z, e1.x) - mulRounded(e0.x, e1.z),
                       mulRounded(e0.x, e1.y) - mulRounded(e0.y, e1.x));
    const double facing = dotRounded(n, to_light);
    const double bound = (8.0 * eps * std::sqrt(dotRounded(e0, e0)) * std::sqrt(dotRounded(e1, e1)) +
                          8.0 * eps * std::sqrt(dotRounded(n, n))) * std::sqrt(dotRounded(to_light, to_light));
    return facing < -bound * (1.0 + 1e-9);
}

inline bool afhCulled(const AliasFreeHardOptions& options, bool closed, const glm::vec3 (&v)[3], const glm::vec4& light) {
    if (!closed || !(options.back_faces_only || options.light_facing_only)) return false;
    const glm::dvec3 a(v[0]), b(v[1]), c(v[2]);
    const glm::dvec3 to_light = light.w != 0.0f ? glm::dvec3(light) - a : glm::dvec3(light);
    if (options.light_facing_only) return afhFacesAway(a, b, c, to_light);
    return glm::dot(glm::cross(b - a, c - a), to_light) >= 0.0;
}
}  // namespace detail

/// CPU twin of the two-pass light pass's spill count (AliasFreeHardFrame::spilled): the caster
/// triangles that survive the class culling and for which conservativeNeedsSpill() holds,
/// projected with `light.view_projection` (pass the frame's light_view_projection) — those that
/// cross the light's eye plane (w = min_w) or the guard band. Independent of the variant and of
/// fixed6_two_pass (the single passes clip exactly these).
inline uint64_t afhSpilledTriangles(const AliasFreeHardOptions& options, const SampleListsLight& light,
                                    const AfhCasters& casters) {
    PENUMBRA_CHECK(casters.positions && casters.indices && casters.closed &&
                       casters.closed->size() * 3 == casters.indices->size(),
                   "penumbra::afhSpilledTriangles: casters need positions, indices and one closed flag per triangle");
    const ConservativeRasterSetup cr = afhConservativeSetup(options);
    const auto& P = *casters.positions;
    const auto& I = *casters.indices;
    uint64_t spilled = 0;
    for (size_t t = 0; t < casters.closed->size(); ++t) {
        const glm::vec3 v[3] = {P[I[3 * t]], P[I[3 * t + 1]], P[I[3 * t + 2]]};
        if (detail::degenerateTriangle(glm::dvec3(v[0]), glm::dvec3(v[1]), glm::dvec3(v[2]))) continue;
        if (detail::afhCulled(options, (*casters.closed)[t] != 0, v, light.light)) continue;
        spilled += conservativeNeedsSpill(light.view_projection * glm::vec4(v[0], 1.0f),
                                          light.view_projection * glm::vec4(v[1], 1.0f),
                                          light.view_projection * glm::vec4(v[2], 1.0f), cr);
    }
    return spilled;
}

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
        // The shared degenerate-triangle rule (the oracle drops these; the light pass culls them in its geometry stage).
        if (detail::degenerateTriangle(glm::dvec3(v[0]), glm::dvec3(v[1]), glm::dvec3(v[2]))) continue;
        if (detail::afhCulled(options, (*casters.closed)[t] != 0, v, light.light)) continue;
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
                const uint32_t walked = std::min(lists.counts[list], afhTestedPerList(options));
                for (uint32_t k = 0; k < walked; ++k) {
                    const uint32_t slot = lists.offsets[list] + k;
                    const uint32_t id = lists.list_ids[slot];
                    if (shadowed[id]) continue;
                    const glm::vec3 pf(lists.list_positions[slot]);
                    bool blocked;
                    if (options.precision == AfhPrecision::Exact) {
                        const glm::dvec3 p(pf);
                        const glm::dvec3 l = point ? lpos : p + detail::mulRounded(lpos, reach);
                        blocked = afhBlocks<double>(a, b, c, p, l, options.coplanar_epsilon, double(options.sample_offset),
                                                    options.scene_extent);
                    } else {
                        const glm::vec3 lf = point ? glm::vec3(light.light)
                                                   : pf + detail::mulRounded(glm::vec3(light.light), options.directional_reach);
                        blocked = afhBlocks<float>(af, bf, cf, pf, lf, static_cast<float>(options.coplanar_epsilon),
                                                   options.sample_offset, detail::afhFloatExtent(options.scene_extent));
                    }
                    if (blocked) shadowed[id] = 1;
                }
            }
        }
    }
    std::vector<uint32_t> states(sample_count);
    for (uint32_t id = 0; id < sample_count; ++id) {
        const uint32_t slot = lists.sample_slots[id];
        if (slot != kSampleListsNoSlot) {
            const uint32_t local = slot - lists.offsets[lists.sample_texels[id]];
            states[id] = local >= afhTestedPerList(options) ? PENUMBRA_AFH_UNTESTED
                         : shadowed[id]                     ? PENUMBRA_AFH_SHADOWED
                                                            : PENUMBRA_AFH_LIT;
        } else {
            const uint32_t reason = lists.sample_texels[id] - PENUMBRA_SAMPLE_LISTS_REJECTED;
            states[id] = reason == PENUMBRA_SAMPLE_LISTS_REASON_BACKGROUND    ? PENUMBRA_AFH_NO_SAMPLE
                         : reason == PENUMBRA_SAMPLE_LISTS_REASON_BACK_FACING ? PENUMBRA_AFH_BACK_FACING
                                                                              : PENUMBRA_AFH_UNTESTED;
        }
    }
    return states;
}

}  // namespace penumbra

#endif
