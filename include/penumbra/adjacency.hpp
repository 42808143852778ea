// penumbra/adjacency.hpp — triangles with adjacency (GL_TRIANGLES_ADJACENCY index order) for the
// soft pipeline's silhouette skip (SoftSkips::silhouettes): per triangle (a, b, c) the six indices
// a, n_ab, b, n_bc, c, n_ca, where n_xy is the vertex of the neighbour across edge xy that is not
// on the edge. Vertices are matched by position (bitwise equal floats), so split vertices (UV or
// normal seams) still join. An edge without exactly one neighbour (an open boundary, or shared by
// three or more triangles) gets n_xy = x: a degenerate neighbour, which the pipeline treats as a
// silhouette (open and non-manifold edges count as silhouettes). Orientation is not needed: the
// skip's test works from positions alone.
//
// Integration summary
//   Needs:    GLM and the C++17 standard library.
//   Input:    float positions and a triangle index list (3 per triangle).
//   Produces: triangleAdjacency() -> 6 indices per triangle into the same positions; upload as an
//             element buffer and draw with GL_TRIANGLES_ADJACENCY.
// Bad input (penumbra::Error naming the value): an index count not a multiple of 3, an index
// beyond the vertices, more than 2^32 - 1 indices.
#ifndef PENUMBRA_ADJACENCY_HPP
#define PENUMBRA_ADJACENCY_HPP

#include "penumbra/error.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <tuple>
#include <vector>

namespace penumbra {

inline std::vector<uint32_t> triangleAdjacency(const glm::vec3* positions, size_t vertex_count, const uint32_t* indices,
                                               size_t index_count) {
    PENUMBRA_CHECK(index_count % 3 == 0, "penumbra::triangleAdjacency: index count ", index_count, " is not a multiple of 3");
    PENUMBRA_CHECK(index_count <= 0xFFFFFFFFull / 2, "penumbra::triangleAdjacency: ", index_count, " indices are too many");
    PENUMBRA_CHECK(index_count == 0 || (positions != nullptr && indices != nullptr),
                   "penumbra::triangleAdjacency: positions and indices must not be null");
    for (size_t i = 0; i < index_count; ++i)
        PENUMBRA_CHECK(indices[i] < vertex_count, "penumbra::triangleAdjacency: index ", i, " is ", indices[i], ", beyond the ",
                       vertex_count, " vertices");
    // Position ids: vertices with bitwise-equal positions share one.
    auto key = [&](uint32_t v) {
        uint32_t k[3];
        std::memcpy(k, &positions[v], sizeof k);
        return std::make_tuple(k[0], k[1], k[2]);
    };
    std::vector<uint32_t> order(vertex_count);
    for (uint32_t v = 0; v < vertex_count; ++v) order[v] = v;
    std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
    std::vector<uint32_t> id(vertex_count);
    for (size_t i = 0; i < order.size(); ++i)
        id[order[i]] = i > 0 && key(order[i]) == key(order[i - 1]) ? id[order[i - 1]] : static_cast<uint32_t>(i);
    // Every edge (by position ids, smaller first) with its triangle and corner.
    struct Edge {
        uint32_t lo, hi, triangle, corner;  // corner: the edge starts at corner `corner`
    };
    const size_t triangles = index_count / 3;
    std::vector<Edge> edges;
    edges.reserve(index_count);
    for (size_t t = 0; t < triangles; ++t)
        for (uint32_t c = 0; c < 3; ++c) {
            const uint32_t a = id[indices[3 * t + c]], b = id[indices[3 * t + (c + 1) % 3]];
            edges.push_back({std::min(a, b), std::max(a, b), static_cast<uint32_t>(t), c});
        }
    std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
        return std::tie(x.lo, x.hi, x.triangle, x.corner) < std::tie(y.lo, y.hi, y.triangle, y.corner);
    });
    std::vector<uint32_t> out(triangles * 6);
    for (size_t t = 0; t < triangles; ++t)
        for (uint32_t c = 0; c < 3; ++c) {
            out[6 * t + 2 * c] = indices[3 * t + c];
            out[6 * t + 2 * c + 1] = indices[3 * t + c];  // degenerate until a single neighbour is found
        }
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
        if (j - i == 2 && edges[i].lo != edges[i].hi) {
            for (int s = 0; s < 2; ++s) {
                const Edge& e = edges[i + s];
                const Edge& other = edges[i + 1 - s];
                out[6 * size_t(e.triangle) + 2 * e.corner + 1] = indices[3 * size_t(other.triangle) + (other.corner + 2) % 3];
            }
        }
        i = j;
    }
    return out;
}

}  // namespace penumbra

#endif
