// penumbra/bent_normals.hpp — bent-normal shading (block 6; sintorn2008 §4.3, Fig. 8): smooth
// shading that gives every light-back-facing triangle exactly no direct light, so accurate
// (alias-free, sample-based) shadows meet the shading terminator without light leaks.
//
// Integration summary
//   Needs:    GLM and the C++17 standard library; no GL (the GLSL is shaders/penumbra/bent_normals/).
//   Input:    an indexed triangle mesh (float positions, 3 indices per triangle) and, optionally, a
//             per-vertex weld id (vertices with equal ids are one vertex for adjacency: split
//             vertices at UV or normal seams; support/include/penumbra/scene/weld.hpp computes it
//             by position with meshoptimizer).
//   Produces: bentNormalMesh() -> BentNormalMesh, buffers ready to bind (std430): CSR vertex ->
//             adjacent faces (offsets[vertex_count + 1], faces[]), unit face normals (vec4, w = 0).
//             Degenerate faces (detail::degenerateTriangle, the library's one rule) are in no list.
//             CPU twins of the GLSL: bentLight() (per vertex) and bentShade() / bentDirect() (per
//             fragment).
//   GLSL:     bent_normals.glsl: penumbraBentLight(vertex, position, light centre, light radius)
//             through hooks PENUMBRA_BENT_OFFSET(v), PENUMBRA_BENT_FACE(i),
//             PENUMBRA_BENT_FACE_NORMAL(f); penumbraBentShade / penumbraBentDirect for the
//             fragment stage; bent_normals.comp.glsl writes l_bend per vertex into a buffer (one
//             dispatch when the light moves) for engines that would rather read an attribute.
//
// The shading (sintorn2008 §4.3). Per vertex v with adjacent faces F:
//     l_bend(v) = min over F of dot(l, n_F),   l = normalize(light centre - v)
// or, with a light radius R > 0, the minimum over every direction towards the light's bounding
// sphere: min over F of cos(angle(l, n_F) + asin(R / |c - v|)) (-1 when that angle reaches pi, and
// -1 for a vertex inside the sphere). Per fragment, with l_bend interpolated and l_f the engine's
// usual diffuse term (e.g. dot(n_interpolated, l)):
//     alpha = clamp(c * l_bend, 0, 1),   shade = alpha * l_f + (1 - alpha) * l_bend,   c = 3,
// and the direct light is max(shade, 0). Why back faces get exactly 0: a light-back-facing
// triangle is adjacent to each of its vertices, so all three l_bend are < 0, hence every convex
// combination the rasterizer interpolates is < 0 (float interpolation with weights >= 0 summing to
// 1 cannot leave [min, max]), alpha = 0 and shade = l_bend < 0. Vertices with no (non-degenerate)
// adjacent face get l_bend = 1 (plain Phong).
//
// Bad input (penumbra::Error naming the value): an index beyond the vertices, an index count not a
// multiple of 3, a non-finite position, a weld id beyond the vertex count, more than 2^32 - 1
// adjacency entries. bentLight() with a non-finite light or R < 0 is a PENUMBRA_ASSERT (per frame).
#ifndef PENUMBRA_BENT_NORMALS_HPP
#define PENUMBRA_BENT_NORMALS_HPP

#include "penumbra/detail/float_ops.hpp"
#include "penumbra/detail/geometry.hpp"
#include "penumbra/detail/shared.hpp"
#include "penumbra/error.hpp"

#if defined(__has_include) && __has_include(<penumbra/bent_normals/bent_normals_shared.h>)
#include <penumbra/bent_normals/bent_normals_shared.h>
#else
#include "../../shaders/penumbra/bent_normals/bent_normals_shared.h"
#endif

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace penumbra {

static_assert(sizeof(shared::PenumbraBentParams) == 32, "bent_normals_shared.h: PenumbraBentParams is 32 bytes");

/// sintorn2008 §4.3: "c := 3 works well".
inline constexpr float kBentDefaultSharpness = 3.0f;

/// The adjacency and face normals of one mesh, as the shaders read them (std430 arrays).
struct BentNormalMesh {
    uint32_t vertex_count = 0;
    uint32_t face_count = 0;              ///< triangles of the input (degenerate ones included)
    uint32_t degenerate_faces = 0;        ///< in no adjacency list
    std::vector<uint32_t> offsets;        ///< vertex_count + 1: faces of v are faces[offsets[v] .. offsets[v+1])
    std::vector<uint32_t> faces;          ///< adjacent face ids
    std::vector<glm::vec4> face_normals;  ///< face_count: unit normal (counter-clockwise = front), w = 0

    uint64_t bytes() const {
        return (offsets.size() + faces.size()) * sizeof(uint32_t) + face_normals.size() * sizeof(glm::vec4);
    }
};

namespace detail::bent {

/// Unit normal of triangle (a, b, c) in float, the operations face normals are uploaded with.
inline glm::vec3 faceNormal(const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
    const glm::vec3 e1 = b - a, e2 = c - a;
    const glm::vec3 n(mulRounded(e1.y, e2.z) - mulRounded(e1.z, e2.y), mulRounded(e1.z, e2.x) - mulRounded(e1.x, e2.z),
                      mulRounded(e1.x, e2.y) - mulRounded(e1.y, e2.x));
    const float length = std::sqrt(dotRounded(n, n));
    return n / length;
}

}  // namespace detail::bent

/// Builds the adjacency (welded by `weld` when given: weld[v] = the id all copies of v share, an
/// index < vertex_count) and the face normals. Throws penumbra::Error for bad input (see header).
inline BentNormalMesh bentNormalMesh(const glm::vec3* positions, size_t vertex_count, const uint32_t* indices,
                                     size_t index_count, const uint32_t* weld = nullptr) {
    PENUMBRA_CHECK(index_count % 3 == 0, "bentNormalMesh: index count ", index_count, " is not a multiple of 3");
    PENUMBRA_CHECK(vertex_count < 0xFFFFFFFFull && index_count / 3 < 0xFFFFFFFFull,
                   "bentNormalMesh: ", vertex_count, " vertices / ", index_count / 3, " triangles exceed 2^32 - 1");
    PENUMBRA_CHECK(vertex_count == 0 || positions != nullptr, "bentNormalMesh: positions must not be null");
    PENUMBRA_CHECK(index_count == 0 || indices != nullptr, "bentNormalMesh: indices must not be null");
    for (size_t v = 0; v < vertex_count; ++v) {
        const glm::vec3 p = positions[v];
        PENUMBRA_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), "bentNormalMesh: vertex ", v,
                       " is not finite (", p.x, ", ", p.y, ", ", p.z, ")");
        PENUMBRA_CHECK(!weld || weld[v] < vertex_count, "bentNormalMesh: weld id ", weld ? weld[v] : 0u, " of vertex ", v,
                       " is not below the vertex count ", vertex_count);
    }
    for (size_t i = 0; i < index_count; ++i)
        PENUMBRA_CHECK(indices[i] < vertex_count, "bentNormalMesh: index ", i, " is ", indices[i], ", beyond the ",
                       vertex_count, " vertices");

    BentNormalMesh mesh;
    mesh.vertex_count = static_cast<uint32_t>(vertex_count);
    mesh.face_count = static_cast<uint32_t>(index_count / 3);
    mesh.face_normals.assign(mesh.face_count, glm::vec4(0.0f));
    std::vector<uint8_t> valid(mesh.face_count, 0);
    for (uint32_t f = 0; f < mesh.face_count; ++f) {
        const glm::vec3 a = positions[indices[3 * f]], b = positions[indices[3 * f + 1]], c = positions[indices[3 * f + 2]];
        if (detail::degenerateTriangle(glm::dvec3(a), glm::dvec3(b), glm::dvec3(c))) {
            ++mesh.degenerate_faces;
            continue;
        }
        valid[f] = 1;
        mesh.face_normals[f] = glm::vec4(detail::bent::faceNormal(a, b, c), 0.0f);
    }
    auto id = [&](uint32_t v) { return weld ? weld[v] : v; };
    // Count per weld id, then give every vertex its id's list (copies share one list).
    std::vector<uint64_t> count(vertex_count + 1, 0);
    for (uint32_t f = 0; f < mesh.face_count; ++f) {
        if (!valid[f]) continue;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = id(indices[3 * f + k]);
            // A face touching two copies of one welded vertex is listed once.
            bool repeat = false;
            for (int j = 0; j < k; ++j) repeat |= id(indices[3 * f + j]) == v;
            if (!repeat) ++count[v];
        }
    }
    std::vector<uint64_t> id_offset(vertex_count + 1, 0);
    for (size_t v = 0; v < vertex_count; ++v) id_offset[v + 1] = id_offset[v] + count[v];
    std::vector<uint32_t> id_faces(id_offset[vertex_count]);
    std::vector<uint64_t> cursor(id_offset.begin(), id_offset.end() - 1);
    for (uint32_t f = 0; f < mesh.face_count; ++f) {
        if (!valid[f]) continue;
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = id(indices[3 * f + k]);
            bool repeat = false;
            for (int j = 0; j < k; ++j) repeat |= id(indices[3 * f + j]) == v;
            if (!repeat) id_faces[cursor[v]++] = f;
        }
    }
    uint64_t total = 0;
    for (size_t v = 0; v < vertex_count; ++v) total += count[id(static_cast<uint32_t>(v))];
    PENUMBRA_CHECK(total < 0xFFFFFFFFull, "bentNormalMesh: ", total, " adjacency entries exceed 2^32 - 1");
    mesh.offsets.resize(vertex_count + 1);
    mesh.faces.reserve(total);
    for (size_t v = 0; v < vertex_count; ++v) {
        mesh.offsets[v] = static_cast<uint32_t>(mesh.faces.size());
        const uint32_t w = id(static_cast<uint32_t>(v));
        mesh.faces.insert(mesh.faces.end(), id_faces.begin() + static_cast<std::ptrdiff_t>(id_offset[w]),
                          id_faces.begin() + static_cast<std::ptrdiff_t>(id_offset[w + 1]));
    }
    mesh.offsets[vertex_count] = static_cast<uint32_t>(mesh.faces.size());
    return mesh;
}

/// l_bend of `vertex` at `position` for a light at `centre` of bounding radius `radius` (0: toward
/// the centre only). CPU twin of penumbraBentLight (float, the same operations).
inline float bentLight(const BentNormalMesh& mesh, uint32_t vertex, const glm::vec3& position, const glm::vec3& centre,
                       float radius = 0.0f) {
    using detail::dotRounded;
    using detail::mulRounded;
    PENUMBRA_ASSERT(vertex < mesh.vertex_count && radius >= 0.0f);
    const uint32_t first = mesh.offsets[vertex], last = mesh.offsets[vertex + 1];
    if (first == last) return 1.0f;
    const glm::vec3 to_light = centre - position;
    const float distance2 = dotRounded(to_light, to_light);
    const float distance = std::sqrt(distance2);
    if (!(distance > radius)) return -1.0f;  // inside the light's sphere (or on the centre)
    const glm::vec3 l = to_light / distance;
    const float sin_t = radius / distance;
    const float cos_t = std::sqrt(std::max(0.0f, 1.0f - mulRounded(sin_t, sin_t)));
    float least = 1.0f;
    for (uint32_t i = first; i < last; ++i) {
        const glm::vec3 n(mesh.face_normals[mesh.faces[i]]);
        const float d = dotRounded(l, n);
        float value = d;
        if (radius > 0.0f) {
            // cos(alpha + theta) = cos a cos t - sin a sin t, or -1 once alpha + theta >= pi.
            const float sin_a = std::sqrt(std::max(0.0f, 1.0f - mulRounded(d, d)));
            value = d <= -cos_t ? -1.0f : mulRounded(d, cos_t) - mulRounded(sin_a, sin_t);
        }
        least = std::min(least, value);
    }
    return least;
}

/// Per fragment: alpha = clamp(c l_bend, 0, 1), alpha l_f + (1 - alpha) l_bend (sintorn2008 §4.3).
/// CPU twin of penumbraBentShade.
inline float bentShade(float l_bend, float l_f, float sharpness = kBentDefaultSharpness) {
    using detail::mulRounded;
    const float alpha = std::clamp(mulRounded(sharpness, l_bend), 0.0f, 1.0f);
    return mulRounded(alpha, l_f) + mulRounded(1.0f - alpha, l_bend);
}

/// The direct light factor: max(bentShade, 0). CPU twin of penumbraBentDirect.
inline float bentDirect(float l_bend, float l_f, float sharpness = kBentDefaultSharpness) {
    return std::max(bentShade(l_bend, l_f, sharpness), 0.0f);
}

}  // namespace penumbra

#endif
