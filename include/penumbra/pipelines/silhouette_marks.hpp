// penumbra — CPU twin of the soft pipeline's silhouette pass (SoftSkips::silhouettes, laine2005
// §3.3; shaders/penumbra/sample_based_soft/silhouettes.geom.glsl and silhouettes.frag.glsl): the
// light texels some potential silhouette edge's influence region covers.
//
// Integration summary
//   input:    the casters as float positions + penumbra::triangleAdjacency indices (6 per
//             triangle), the light's frame (LightSampleSets::frame, as the pipeline gets it) and
//             the pipeline's influence setup.
//   produces: W x H marks (GL's polygon rule on each emitted region, double on the float
//             vertices) and the texels within `tolerance` pixels of a region's boundary, which a
//             rasterizer's vertex snapping may decide either way. The geometry stage clips each
//             edge with unfused float arithmetic that other compilers may contract; the clip
//             widens each kept end by 2^-12 of the edge, so such differences move a region by
//             far less than a pixel and the tolerance covers them.
//   compare:  bit 0 of SampleBasedSoftShadows::readMarks() (bit 1 marks texels near a coplanar
//             neighbour, SoftSkips::silhouettes) — every texel outside `uncertain` agrees.
#ifndef PENUMBRA_PIPELINES_SILHOUETTE_MARKS_HPP
#define PENUMBRA_PIPELINES_SILHOUETTE_MARKS_HPP

#include "penumbra/error.hpp"
#include "penumbra/influence_region.hpp"
#include "penumbra/light_samples.hpp"
#include "penumbra/pipelines/sample_based_soft.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace penumbra {

/// What sampleBasedSoftSilhouetteMarks found.
struct SilhouetteMarksCpu {
    std::vector<uint8_t> marks;      ///< W x H, row-major: 1 = some region's rule covers the texel
    std::vector<uint8_t> uncertain;  ///< W x H: unmarked, but within the tolerance of a region's boundary
    uint64_t edges = 0;              ///< edges looked at (each once: by the triangle the shader picks)
    uint64_t potential = 0;          ///< of those, potential silhouettes (open and non-manifold included)
    uint64_t emitted = 0;            ///< of those, regions emitted (some part of the edge kept by the clip)
};

namespace detail {

inline bool silhouetteLess(const glm::vec3& a, const glm::vec3& b) {
    return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z)));
}

/// silhouettes.geom.glsl's penumbraSbsEdge: edge (x, y) with this triangle's apex z and the
/// neighbour's apex n. Returns whether a region was emitted (into `region`).
inline bool silhouetteEdge(const glm::vec3& x, const glm::vec3& y, const glm::vec3& z, const glm::vec3& n,
                           const InfluenceRegionSetup& setup, const glm::dvec3& centre, double reach,
                           SilhouetteMarksCpu& out, InfluenceRegion& region) {
    const bool open = n == x || n == y;
    if (!open && silhouetteLess(n, z)) return false;  // the neighbour emits it
    ++out.edges;
    if (!open) {
        const soft::CasterPlane f = soft::casterPlane(glm::dvec3(x), glm::dvec3(y), glm::dvec3(z), centre, reach);
        const soft::CasterPlane g = soft::casterPlane(glm::dvec3(y), glm::dvec3(x), glm::dvec3(n), centre, reach);
        if (f.light_clearance > 0.0 && g.light_clearance > 0.0 && (f.light_side > 0.0) == (g.light_side > 0.0))
            return false;  // the whole light on one side of both faces
    }
    ++out.potential;
    // The clip to the hull of the light and the grid frustum, and short of F (the shader's float
    // operations, in its order).
    const InfluenceRegionParams& P = setup.params;
    const glm::vec3 c(P.center);
    const glm::vec3 dx_world = x - c, dy_world = y - c;
    const glm::vec3 qx(influenceDot3(P.to_local[0], dx_world), influenceDot3(P.to_local[1], dx_world),
                       influenceDot3(P.to_local[2], dx_world));
    const glm::vec3 qy(influenceDot3(P.to_local[0], dy_world), influenceDot3(P.to_local[1], dy_world),
                       influenceDot3(P.to_local[2], dy_world));
    float t0 = 0.0f, t1 = 1.0f;
    const float radius = 1.0625f + std::max(glm::length(qx), glm::length(qy)) / 4096.0f;
    const glm::vec4 rows[4] = {P.to_pixel[0], P.grid.x * P.to_pixel[2] - P.to_pixel[0], P.to_pixel[1],
                               P.grid.y * P.to_pixel[2] - P.to_pixel[1]};
    for (const glm::vec4& row : rows) {
        const glm::vec3 r(row);
        const float shift = radius * glm::length(r);
        const float dx = glm::dot(r, qx) + row.w + shift, dy = glm::dot(r, qy) + row.w + shift;
        if (dx < 0.0f && dy < 0.0f) return false;  // wholly outside
        if (dx < 0.0f) t0 = std::max(t0, std::max(0.0f, dx / (dx - dy) - 1.0f / 4096.0f));
        if (dy < 0.0f) t1 = std::min(t1, std::min(1.0f, dx / (dx - dy) + 1.0f / 4096.0f));
    }
    const float sx = influenceDot3(P.far_plane, qx) + P.far_plane.w;
    const float sy = influenceDot3(P.far_plane, qy) + P.far_plane.w;
    if (!(sx < 0.0f) && !(sy < 0.0f)) return false;  // wholly beyond F
    if (!(sx < 0.0f)) t0 = std::max(t0, (sx - sy / 4096.0f) / (sx - sy));
    if (!(sy < 0.0f)) t1 = std::min(t1, sx * (1.0f - 1.0f / 4096.0f) / (sx - sy));
    if (!(t0 <= t1)) return false;
    const glm::vec3 a = t0 > 0.0f ? x + t0 * (y - x) : x, b = t1 < 1.0f ? x + t1 * (y - x) : y;
    region = influenceRegion(a, b, b, setup);
    ++out.emitted;
    return true;
}

}  // namespace detail

/// The silhouette pass on the CPU: `adjacency` holds 6 indices per triangle (a, n_ab, b, n_bc, c,
/// n_ca: penumbra::triangleAdjacency) into `positions`; `frame` is the light samples' frame (the
/// pipeline's parameter block takes its centre and reach from it); `influence` is the pipeline's
/// setup (its supporting-plane cut is a triangle's and is not applied, as in the shader).
/// Throws penumbra::Error for an index beyond the vertices or a negative tolerance.
inline SilhouetteMarksCpu sampleBasedSoftSilhouetteMarks(const glm::vec3* positions, size_t vertex_count,
                                                         const uint32_t* adjacency, size_t triangle_count,
                                                         const LightFrame& frame, const InfluenceRegionSetup& influence,
                                                         double tolerance = 1.0 / 256.0) {
    PENUMBRA_CHECK(tolerance >= 0.0, "sampleBasedSoftSilhouetteMarks: tolerance ", tolerance, " is negative");
    PENUMBRA_CHECK(triangle_count == 0 || (positions && adjacency),
                   "sampleBasedSoftSilhouetteMarks: positions and adjacency must not be null");
    for (size_t i = 0; i < 6 * triangle_count; ++i)
        PENUMBRA_CHECK(adjacency[i] < vertex_count, "sampleBasedSoftSilhouetteMarks: adjacency index ", i, " is ",
                       adjacency[i], ", beyond the ", vertex_count, " vertices");
    InfluenceRegionSetup setup = influence;  // the cut is a triangle's: off, as PENUMBRA_INFLUENCE_CUT = 0
    setup.options.cut_by_supporting_plane = false;
    setup.params.config.y &= ~static_cast<uint32_t>(PENUMBRA_INFLUENCE_CONFIG_CUT);
    const int w = setup.width(), h = setup.height();
    SilhouetteMarksCpu out;
    out.marks.assign(size_t(w) * size_t(h), 0);
    out.uncertain.assign(out.marks.size(), 0);
    // The parameter block's centre and reach (sampleBasedSoftParams).
    const double max_scale = std::max(frame.scale.x, std::max(frame.scale.y, frame.scale.z));
    const double reach = max_scale * std::sqrt(3.0);
    InfluenceRegion region;
    for (size_t t = 0; t < triangle_count; ++t) {
        glm::vec3 v[6];
        for (int i = 0; i < 6; ++i) v[i] = positions[adjacency[6 * t + static_cast<size_t>(i)]];
        for (int e = 0; e < 6; e += 2) {  // edge (v[e], v[e + 2]), apex v[e + 4], neighbour's apex v[e + 1]
            if (!detail::silhouetteEdge(v[e], v[(e + 2) % 6], v[(e + 4) % 6], v[e + 1], setup, frame.center, reach, out, region))
                continue;
            const HullRaster raster = influenceRegionTexels(region, setup, tolerance);
            for (const glm::ivec2& p : raster.fragments) out.marks[size_t(p.y) * size_t(w) + size_t(p.x)] = 1;
            for (const glm::ivec2& p : raster.uncertain) out.uncertain[size_t(p.y) * size_t(w) + size_t(p.x)] = 1;
        }
    }
    for (size_t i = 0; i < out.marks.size(); ++i)
        if (out.marks[i]) out.uncertain[i] = 0;
    return out;
}

}  // namespace penumbra

#endif
