// penumbra/light_volume.hpp — the quadtree light-volume tessellator (block 7; billeter2010): the lit
// region of a spot light (or one cube face of a point light), reconstructed from its shadow map as
// a closed, consistently oriented polygonal volume, so that airlight can be integrated only where
// eye rays cross its boundary instead of ray marching through the fog.
//
// Integration summary
//   Needs:    GLM and the C++17 standard library; no GL. The GPU tessellator (bit for bit the CPU
//             twin's mesh on llvmpipe) is penumbra/gl/light_volume.hpp with the compute shaders in
//             shaders/penumbra/light_volume/; lightVolumeParams() is its constants block.
//   Input:    the light's shadow map: R x R post-projective depths in [0, 1] (GL's window depth,
//             texel (x, y) at depth[y * R + x], 1 = nothing hit before the far plane), R a power of
//             two in [2, kLightVolumeMaxResolution]; the light's view-projection matrix.
//   Produces: lightVolumeSetup(): validated sizes and bounds (every buffer the GPU path will need);
//             lightVolumeCornerDepths(): the (R + 1)^2 lattice depths the volume is displaced to;
//             tessellateLightVolume(): the CPU tessellator — the triangle list of the closed volume,
//             vertices as packed lattice coordinates (x | y << 16) or kLightVolumeApex;
//             lightVolumePosition(): a vertex in world space; lightVolumeFloorError(): the
//             floor's largest deviation from the lattice depths (the static mesh's surface).
//
// Lattice. The volume's floor is a height field over the (R + 1) x (R + 1) texel corners: corner
// (i, j) sits at NDC (2i/R - 1, 2j/R - 1). Its depth is interpolated from the texels separably, in
// float, in a fixed order (so a GPU twin gets the same values): along x in every texel row, then
// along y, each step the mean of the two texels around the corner, or on the border the linear
// extrapolation of the two nearest, then clamped to [0, 1]. Why corners rather than texel centres:
// a quadtree of R x R cells covers them exactly (centres would leave R - 1 cells per side), and on
// a plane the interpolated and extrapolated values are the plane's own, so planes stay planes (an
// extrapolated border corner next to a silhouette may overshoot; the clamp keeps it a depth).
//
// Static tessellation: every unit cell is two triangles (2 R^2 floor triangles), the seed's
// baseline.
//
// Adaptive tessellation (billeter2010, "Adaptive Tessellation"): a quadtree over the cells, where
//   1. a cell of size s = 2^k (k >= 1) *needs subdivision* when some lattice depth in the closed
//      cell is more than `flatness` away from the plane through its corners (x0, y0), (x0 + s, y0)
//      and (x0, y0 + s), evaluated in double. A leaf's triangles interpolate lattice depths of its
//      own cell, each within `flatness` of that plane, and so does the static mesh over the same
//      cell: the adaptive floor is within 2 * flatness of the static one in post-projective depth,
//      everywhere. Planar regions (post-projective depth is affine in screen space on a plane)
//      become large cells; flatness = 0 keeps only what is affine to the last bit.
//      The seed flags cells from a Laplacian edge map instead; the Laplacian is blind to saddles
//      (z = xy has none) and its threshold bounds no error, which is why this criterion replaces it.
//   2. Closure: a cell with a subdivided child is subdivided (the mip hierarchy of the flags).
//   3. Restriction: from the finest level up, a subdivided cell with a subdivided child forces its
//      four edge neighbours of the same size to subdivide, so edge-adjacent leaves differ by at most
//      one level (the seed's "max 1 level of difference between neighbours").
//   4. Emission: a leaf whose four neighbours are no finer is two triangles (diagonal from
//      (x0, y0) to (x0 + s, y0 + s)); otherwise a fan around its centre through its corners and the
//      midpoints of the sides whose neighbour is subdivided — stitched, no T-junction.
// The volume is closed by one triangle per boundary edge of the floor to the apex (the light's
// position). Orientation: outward; the floor triangles are clockwise in NDC xy (seen from the
// light their normals point away from it), each side triangle is (b, a, apex) for a floor boundary
// edge a -> b. Triangle order: the floor by level, coarsest first, then row-major cell order; then
// the sides. Documented results for odd inputs: depth 1 everywhere (nothing in the light's view)
// gives the frustum pyramid; depth 0 everywhere (light inside geometry) gives a volume flattened onto
// the near plane (zero airlight); non-finite depths or depths outside [0, 1] are an error.
#ifndef PENUMBRA_LIGHT_VOLUME_HPP
#define PENUMBRA_LIGHT_VOLUME_HPP

#include "penumbra/detail/shared.hpp"
#if defined(__has_include) && __has_include(<penumbra/light_volume/light_volume_shared.h>)
#include <penumbra/light_volume/light_volume_shared.h>
#else
#include "../../shaders/penumbra/light_volume/light_volume_shared.h"
#endif

#include "penumbra/error.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace penumbra {

/// Largest shadow map the tessellator takes: lattice coordinates pack into 16 bits each.
inline constexpr uint32_t kLightVolumeMaxResolution = 16384;  // levels 0 .. 14 < PENUMBRA_LV_MAX_LEVELS
/// The packed vertex that stands for the light's position (the volume's apex).
inline constexpr uint32_t kLightVolumeApex = 0xffffffffu;

enum class LightVolumeTessellation { Adaptive, Static };

/// Value-initialised = the defaults.
struct LightVolumeOptions {
    LightVolumeTessellation tessellation = LightVolumeTessellation::Adaptive;
    /// Adaptive: largest deviation, in post-projective depth, of a leaf's lattice depths from its
    /// corner plane (the floor stays within 2 * flatness of the static one). 0: exact planes only.
    double flatness = 0.0;
};

/// Validated sizes; everything the tessellation needs to know before it sees a depth.
struct LightVolumeSetup {
    uint32_t resolution = 0;  ///< R: shadow-map texels per side
    uint32_t levels = 0;      ///< L = log2 R: cell sizes 2^0 .. 2^L
    LightVolumeOptions options;
    /// Upper bounds (the static tessellation's counts are the largest any tessellation emits, see
    /// lightVolumeSetup): floor triangles 2 R^2 ... plus stitching, side triangles 4 R.
    uint64_t max_floor_triangles = 0;
    uint64_t max_side_triangles = 0;
    uint64_t maxTriangles() const { return max_floor_triangles + max_side_triangles; }
};

/// Throws penumbra::Error naming the value: R not a power of two in [2, kLightVolumeMaxResolution],
/// flatness negative or not finite.
inline LightVolumeSetup lightVolumeSetup(uint32_t resolution, const LightVolumeOptions& options = {}) {
    PENUMBRA_CHECK(resolution >= 2 && resolution <= kLightVolumeMaxResolution && (resolution & (resolution - 1)) == 0,
                   "lightVolumeSetup: the shadow-map resolution must be a power of two in [2, ", kLightVolumeMaxResolution,
                   "] (got ", resolution, ")");
    PENUMBRA_CHECK(std::isfinite(options.flatness) && options.flatness >= 0.0,
                   "lightVolumeSetup: options.flatness must be finite and >= 0 (got ", options.flatness, ")");
    LightVolumeSetup setup;
    setup.resolution = resolution;
    while ((1u << setup.levels) < resolution) ++setup.levels;
    setup.options = options;
    // A leaf of size s >= 2 emits at most 8 triangles (4 + 4 stitched sides) for its s^2 >= 4 unit
    // cells' 2 s^2 >= 8 static ones, so no tessellation exceeds the static count.
    setup.max_floor_triangles = 2ull * resolution * resolution;
    setup.max_side_triangles = 4ull * resolution;
    return setup;
}

using LightVolumeParams = shared::PenumbraLightVolumeParams;
static_assert(sizeof(LightVolumeParams) == 112, "light_volume_shared.h: PenumbraLightVolumeParams is 112 bytes in std140");
static_assert(sizeof(shared::PenumbraLightVolumeRenderParams) == 352, "light_volume_shared.h: the render block is 352 bytes in std140");
static_assert(PENUMBRA_LV_APEX == 0xffffffffu, "light_volume_shared.h and kLightVolumeApex agree");

/// First cell of level k in the GPU's flag and item order (levels coarsest first, row-major).
inline uint64_t lightVolumeLevelOffset(const LightVolumeSetup& setup, uint32_t k) {
    uint64_t offset = 0;
    for (uint32_t level = setup.levels; level > k; --level) offset += uint64_t(setup.resolution >> level) * (setup.resolution >> level);
    return offset;
}
/// Cells of every level (k = 0 .. L).
inline uint64_t lightVolumeCells(const LightVolumeSetup& setup) { return lightVolumeLevelOffset(setup, 0) + uint64_t(setup.resolution) * setup.resolution; }

/// The constants block of the GPU passes at level k (pure setup: the host uploads one per level).
inline LightVolumeParams lightVolumeParams(const LightVolumeSetup& setup, uint32_t k) {
    LightVolumeParams p{};
    p.size = shared::uvec4(setup.resolution, setup.levels, k, setup.options.tessellation == LightVolumeTessellation::Static ? 1u : 0u);
    const uint64_t cells = lightVolumeCells(setup);
    p.counts = shared::uvec4(static_cast<uint32_t>(cells), static_cast<uint32_t>(cells + 4ull * setup.resolution),
                             static_cast<uint32_t>(uint64_t(setup.resolution >> k) * (setup.resolution >> k)), 0u);
    uint64_t bits = 0;
    static_assert(sizeof(bits) == sizeof(setup.options.flatness), "double is 64 bits");
    std::memcpy(&bits, &setup.options.flatness, sizeof(bits));
    p.flatness = shared::uvec4(static_cast<uint32_t>(bits), static_cast<uint32_t>(bits >> 32), 0u, 0u);
    for (uint32_t level = 0; level <= setup.levels; ++level)
        p.level_offset[level / 4][level % 4] = static_cast<uint32_t>(lightVolumeLevelOffset(setup, level));
    return p;
}

/// Packs lattice corner (i, j), 0 <= i, j <= R, into a vertex.
inline constexpr uint32_t lightVolumePack(uint32_t i, uint32_t j) { return i | (j << 16); }
inline constexpr uint32_t lightVolumeI(uint32_t v) { return v & 0xffffu; }
inline constexpr uint32_t lightVolumeJ(uint32_t v) { return v >> 16; }

/// The (R + 1)^2 lattice depths (corner (i, j) at [j * (R + 1) + i]), interpolated from the texels
/// in float in a fixed order (see the header comment). Throws penumbra::Error
/// for a size mismatch or a depth that is not finite or outside [0, 1], naming the texel.
inline std::vector<float> lightVolumeCornerDepths(const LightVolumeSetup& setup, const std::vector<float>& depth) {
    const uint32_t r = setup.resolution;
    PENUMBRA_CHECK(depth.size() == static_cast<size_t>(r) * r, "lightVolumeCornerDepths: expected R^2 = ",
                   static_cast<size_t>(r) * r, " depths (R = ", r, "), got ", depth.size());
    for (size_t t = 0; t < depth.size(); ++t) {
        PENUMBRA_CHECK(std::isfinite(depth[t]) && depth[t] >= 0.0f && depth[t] <= 1.0f, "lightVolumeCornerDepths: depth of texel (",
                       t % r, ", ", t / r, ") must be finite and in [0, 1] (got ", depth[t], ")");
    }
    const uint32_t n = r + 1;
    // Separable: along x for every texel row, then along y; inside, the mean of the two texels
    // around the corner; on the border, the linear extrapolation of the two nearest (so a plane's
    // border corners stay on the plane); clamped to [0, 1].
    const auto lerp = [](float near_value, float far_value, bool border) {
        return border ? near_value + (near_value - far_value) * 0.5f : (near_value + far_value) * 0.5f;
    };
    std::vector<float> along_x(static_cast<size_t>(n) * r);  // [y * n + i]
    for (uint32_t y = 0; y < r; ++y) {
        const float* row = depth.data() + static_cast<size_t>(y) * r;
        for (uint32_t i = 0; i < n; ++i) {
            float value;
            if (i == 0) value = lerp(row[0], row[1], true);
            else if (i == r) value = lerp(row[r - 1], row[r - 2], true);
            else value = lerp(row[i - 1], row[i], false);
            along_x[static_cast<size_t>(y) * n + i] = value;
        }
    }
    std::vector<float> corners(static_cast<size_t>(n) * n);
    for (uint32_t j = 0; j < n; ++j) {
        for (uint32_t i = 0; i < n; ++i) {
            const auto at = [&](uint32_t y) { return along_x[static_cast<size_t>(y) * n + i]; };
            float value;
            if (j == 0) value = lerp(at(0), at(1), true);
            else if (j == r) value = lerp(at(r - 1), at(r - 2), true);
            else value = lerp(at(j - 1), at(j), false);
            corners[static_cast<size_t>(j) * n + i] = std::min(1.0f, std::max(0.0f, value));
        }
    }
    return corners;
}

/// The tessellation's result: 3 packed vertices per triangle, outward, the floor first.
struct LightVolumeMesh {
    uint32_t resolution = 0;
    std::vector<uint32_t> triangles;  ///< 3 per triangle: lightVolumePack(i, j) or kLightVolumeApex
    uint64_t floor_triangles = 0;     ///< the first floor_triangles triangles; the rest are sides
    uint64_t leaves = 0;              ///< quadtree leaves (static: R^2)
    uint64_t stitched_leaves = 0;     ///< leaves emitted as a fan (a neighbour is finer)
    uint64_t triangleCount() const { return triangles.size() / 3; }
};

namespace detail::light_volume {

/// Subdivision flags of every level: flags[k][cy * (R >> k) + cx] for cells of size 2^k.
using Flags = std::vector<std::vector<uint8_t>>;

/// Steps 1-3 of the header comment on the lattice depths.
inline Flags subdivisionFlags(const LightVolumeSetup& setup, const std::vector<float>& corners) {
    const uint32_t r = setup.resolution, levels = setup.levels, n = r + 1;
    Flags flags(levels + 1);
    for (uint32_t k = 0; k <= levels; ++k) flags[k].assign(static_cast<size_t>(r >> k) * (r >> k), 0);
    if (setup.options.tessellation == LightVolumeTessellation::Static) {
        for (uint32_t k = 1; k <= levels; ++k) std::fill(flags[k].begin(), flags[k].end(), uint8_t{1});
        return flags;
    }
    const double flatness = setup.options.flatness;
    const auto depthAt = [&](uint32_t i, uint32_t j) { return static_cast<double>(corners[static_cast<size_t>(j) * n + i]); };
    for (uint32_t k = 1; k <= levels; ++k) {
        const uint32_t cells = r >> k, s = 1u << k, finer = cells * 2;
        std::vector<uint8_t>& level = flags[k];
        const std::vector<uint8_t>& below = flags[k - 1];
        // Restriction of the level below (step 3) before its closure into this one (step 2).
        if (k >= 2) {
            const std::vector<uint8_t>& below2 = flags[k - 2];
            std::vector<uint8_t> forced(below.size(), 0);
            for (uint32_t cy = 0; cy < finer; ++cy) {
                for (uint32_t cx = 0; cx < finer; ++cx) {
                    if (!below[static_cast<size_t>(cy) * finer + cx]) continue;
                    const uint32_t f2 = finer * 2;
                    bool child = false;
                    for (uint32_t q = 0; q < 4 && !child; ++q)
                        child = below2[static_cast<size_t>(2 * cy + q / 2) * f2 + 2 * cx + q % 2] != 0;
                    if (!child) continue;
                    if (cx > 0) forced[static_cast<size_t>(cy) * finer + cx - 1] = 1;
                    if (cx + 1 < finer) forced[static_cast<size_t>(cy) * finer + cx + 1] = 1;
                    if (cy > 0) forced[static_cast<size_t>(cy - 1) * finer + cx] = 1;
                    if (cy + 1 < finer) forced[static_cast<size_t>(cy + 1) * finer + cx] = 1;
                }
            }
            std::vector<uint8_t>& below_mut = flags[k - 1];
            for (size_t c = 0; c < forced.size(); ++c) below_mut[c] = static_cast<uint8_t>(below_mut[c] | forced[c]);
        }
        for (uint32_t cy = 0; cy < cells; ++cy) {
            for (uint32_t cx = 0; cx < cells; ++cx) {
                bool subdivide = false;
                for (uint32_t q = 0; q < 4 && !subdivide; ++q)
                    subdivide = below[static_cast<size_t>(2 * cy + q / 2) * finer + 2 * cx + q % 2] != 0;
                if (!subdivide) {
                    const uint32_t x0 = cx * s, y0 = cy * s;
                    const double p00 = depthAt(x0, y0);
                    const double gx = (depthAt(x0 + s, y0) - p00) / s, gy = (depthAt(x0, y0 + s) - p00) / s;
                    for (uint32_t j = 0; j <= s && !subdivide; ++j) {
                        const double row = p00 + gy * j;
                        for (uint32_t i = 0; i <= s; ++i) {
                            if (std::abs(depthAt(x0 + i, y0 + j) - (row + gx * i)) > flatness) {
                                subdivide = true;
                                break;
                            }
                        }
                    }
                }
                level[static_cast<size_t>(cy) * cells + cx] = subdivide ? 1 : 0;
            }
        }
    }
    return flags;
}

}  // namespace detail::light_volume

/// The CPU tessellator: the closed light volume of `corners` (lightVolumeCornerDepths) as a
/// triangle list (see the header comment for the rules, orientation and order).
inline LightVolumeMesh tessellateLightVolume(const LightVolumeSetup& setup, const std::vector<float>& corners) {
    namespace lv = detail::light_volume;
    const uint32_t r = setup.resolution, levels = setup.levels;
    PENUMBRA_CHECK(r >= 2 && (r & (r - 1)) == 0 && (1u << levels) == r, "tessellateLightVolume: the setup is not from lightVolumeSetup (R = ",
                   r, ", levels = ", levels, ")");
    PENUMBRA_CHECK(corners.size() == static_cast<size_t>(r + 1) * (r + 1), "tessellateLightVolume: expected (R + 1)^2 = ",
                   static_cast<size_t>(r + 1) * (r + 1), " lattice depths, got ", corners.size());
    const lv::Flags flags = lv::subdivisionFlags(setup, corners);
    LightVolumeMesh mesh;
    mesh.resolution = r;
    const auto subdivided = [&](uint32_t k, int64_t cx, int64_t cy) {
        const int64_t cells = r >> k;
        if (k == 0 || cx < 0 || cy < 0 || cx >= cells || cy >= cells) return false;
        return flags[k][static_cast<size_t>(cy) * static_cast<size_t>(cells) + static_cast<size_t>(cx)] != 0;
    };
    // Outward = clockwise in NDC xy: each triangle (a, b, c) counter-clockwise is stored (a, c, b).
    const auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
        mesh.triangles.push_back(a);
        mesh.triangles.push_back(c);
        mesh.triangles.push_back(b);
    };
    for (uint32_t k = levels + 1; k-- > 0;) {
        const uint32_t cells = r >> k, s = 1u << k;
        for (uint32_t cy = 0; cy < cells; ++cy) {
            for (uint32_t cx = 0; cx < cells; ++cx) {
                // A leaf: not subdivided, and its parent is (or it is the root).
                if (subdivided(k, cx, cy)) continue;
                if (k < levels && !subdivided(k + 1, cx / 2, cy / 2)) continue;
                ++mesh.leaves;
                const uint32_t x0 = cx * s, y0 = cy * s, h = s / 2;
                const bool finer[4] = {subdivided(k, cx, int64_t(cy) - 1), subdivided(k, int64_t(cx) + 1, cy),
                                       subdivided(k, cx, int64_t(cy) + 1), subdivided(k, int64_t(cx) - 1, cy)};
                if (!finer[0] && !finer[1] && !finer[2] && !finer[3]) {
                    emit(lightVolumePack(x0, y0), lightVolumePack(x0 + s, y0), lightVolumePack(x0 + s, y0 + s));
                    emit(lightVolumePack(x0, y0), lightVolumePack(x0 + s, y0 + s), lightVolumePack(x0, y0 + s));
                    continue;
                }
                ++mesh.stitched_leaves;  // s >= 2 here: a unit cell's neighbours are never finer
                uint32_t ring[8];
                int count = 0;
                const uint32_t corner[4] = {lightVolumePack(x0, y0), lightVolumePack(x0 + s, y0), lightVolumePack(x0 + s, y0 + s),
                                            lightVolumePack(x0, y0 + s)};
                const uint32_t middle[4] = {lightVolumePack(x0 + h, y0), lightVolumePack(x0 + s, y0 + h), lightVolumePack(x0 + h, y0 + s),
                                            lightVolumePack(x0, y0 + h)};
                for (int side = 0; side < 4; ++side) {
                    ring[count++] = corner[side];
                    if (finer[side]) ring[count++] = middle[side];
                }
                const uint32_t centre = lightVolumePack(x0 + h, y0 + h);
                for (int v = 0; v < count; ++v) emit(centre, ring[v], ring[(v + 1) % count]);
            }
        }
    }
    mesh.floor_triangles = mesh.triangles.size() / 3;
    // Sides: the floor's boundary edges, walked along the lattice border; an edge a -> b of the
    // outward floor (clockwise in NDC: along the border clockwise) closes with (b, a, apex).
    // Border leaf sides: split the border into the leaves' sides by walking the leaf sizes.
    const auto leafSizeAt = [&](uint32_t ux, uint32_t uy) {  // the leaf holding unit cell (ux, uy)
        uint32_t k = 0;
        while (k < levels && !subdivided(k + 1, ux >> (k + 1), uy >> (k + 1))) ++k;
        return 1u << k;
    };
    const auto side = [&](uint32_t a, uint32_t b) {
        mesh.triangles.push_back(b);
        mesh.triangles.push_back(a);
        mesh.triangles.push_back(kLightVolumeApex);
    };
    // The floor's counter-clockwise boundary runs bottom (+x), right (+y), top (-x), left (-y); the
    // stored (clockwise) floor has it reversed, so its edges are a -> b with b before a below.
    for (uint32_t x = 0; x < r;) {  // bottom row, y = 0
        const uint32_t s = leafSizeAt(x, 0);
        side(lightVolumePack(x + s, 0), lightVolumePack(x, 0));
        x += s;
    }
    for (uint32_t y = 0; y < r;) {  // right column, x = R
        const uint32_t s = leafSizeAt(r - 1, y);
        side(lightVolumePack(r, y + s), lightVolumePack(r, y));
        y += s;
    }
    for (uint32_t x = 0; x < r;) {  // top row, y = R
        const uint32_t s = leafSizeAt(x, r - 1);
        side(lightVolumePack(x, r), lightVolumePack(x + s, r));
        x += s;
    }
    for (uint32_t y = 0; y < r;) {  // left column, x = 0
        const uint32_t s = leafSizeAt(0, y);
        side(lightVolumePack(0, y), lightVolumePack(0, y + s));
        y += s;
    }
    return mesh;
}

/// Largest |floor - lattice depth| over every lattice point (the floor's triangles interpolated in
/// double): 0 for the static mesh, <= 2 * flatness for the adaptive one (header comment). For
/// tools and benchmarks; O(R^2).
inline double lightVolumeFloorError(const LightVolumeMesh& mesh, const std::vector<float>& corners) {
    const int64_t n = int64_t(mesh.resolution) + 1;
    double worst = 0.0;
    for (uint64_t t = 0; t < mesh.floor_triangles; ++t) {
        const uint32_t* v = mesh.triangles.data() + 3 * t;
        int64_t x[3], y[3];
        double d[3];
        for (int k = 0; k < 3; ++k) {
            x[k] = lightVolumeI(v[k]);
            y[k] = lightVolumeJ(v[k]);
            d[k] = corners[static_cast<size_t>(y[k] * n + x[k])];
        }
        const int64_t area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        if (area == 0) continue;
        for (int64_t py = std::min({y[0], y[1], y[2]}); py <= std::max({y[0], y[1], y[2]}); ++py) {
            for (int64_t px = std::min({x[0], x[1], x[2]}); px <= std::max({x[0], x[1], x[2]}); ++px) {
                int64_t w[3];
                for (int k = 0; k < 3; ++k) {
                    const int a = (k + 1) % 3, b = (k + 2) % 3;
                    w[k] = (x[b] - x[a]) * (py - y[a]) - (px - x[a]) * (y[b] - y[a]);
                }
                if (area > 0 ? (w[0] < 0 || w[1] < 0 || w[2] < 0) : (w[0] > 0 || w[1] > 0 || w[2] > 0)) continue;
                const double value = (double(w[0]) * d[0] + double(w[1]) * d[1] + double(w[2]) * d[2]) / double(area);
                worst = std::max(worst, std::abs(value - double(corners[static_cast<size_t>(py * n + px)])));
            }
        }
    }
    return worst;
}

/// A packed vertex in world space: lattice corner (i, j) at NDC (2i/R - 1, 2j/R - 1, 2 depth - 1)
/// through `inverse_view_projection` (the light's); the apex is `light_position`.
inline glm::dvec3 lightVolumePosition(uint32_t vertex, uint32_t resolution, const std::vector<float>& corners,
                                      const glm::dmat4& inverse_view_projection, const glm::dvec3& light_position) {
    if (vertex == kLightVolumeApex) return light_position;
    const uint32_t i = lightVolumeI(vertex), j = lightVolumeJ(vertex);
    const double depth = corners[static_cast<size_t>(j) * (resolution + 1) + i];
    const glm::dvec4 ndc(2.0 * i / resolution - 1.0, 2.0 * j / resolution - 1.0, 2.0 * depth - 1.0, 1.0);
    const glm::dvec4 world = inverse_view_projection * ndc;
    return glm::dvec3(world) / world.w;
}

}  // namespace penumbra

#endif
