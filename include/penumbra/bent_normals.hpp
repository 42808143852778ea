// penumbra/bent_normals.hpp — bent-normal shading (block 6; sintorn2008 §4.3, Fig. 8): smooth
// shading that gives every light-back-facing triangle exactly no direct light, so accurate
// (alias-free, sample-based) shadows meet the shading terminator without light leaks.
//
// Integration summary
//   Needs:    GLM and the C++17 standard library; no GL (the GLSL is shaders/penumbra/bent_normals/).
//   Input:    an indexed triangle mesh (float positions, 3 indices per triangle), optionally a
//             per-vertex weld id (vertices with equal ids are one vertex for adjacency: split
//             vertices at UV or normal seams; support/include/penumbra/scene/weld.hpp computes it
//             by position with meshoptimizer) and BentNormalOptions (the crease angle).
//   Produces: bentNormalMesh() -> BentNormalMesh, buffers ready to bind (std430). Adjacency is per
//             smooth group: at a vertex, faces joined by edges whose normals differ by at most the
//             crease angle (like normal smoothing groups), so a cube's lit face never sees the
//             faces around its corner. A vertex in several groups gets copies ("bent vertices":
//             source[] says which input vertex, indices[] is the index buffer to draw with; none
//             where nothing is creased, then indices == the input). CSR bent vertex -> faces of its
//             group (offsets[bentVertexCount() + 1], faces[]), unit face normals (vec4, w = 0).
//             Degenerate faces (detail::degenerateTriangle, the library's one rule) are in no list.
//             CPU twins of the GLSL: bentLight() (per bent vertex) and bentShade() / bentDirect()
//             (per fragment).
//   GLSL:     bent_normals.glsl: penumbraBentLight(bent vertex, position, light centre, light
//             radius) through hooks PENUMBRA_BENT_OFFSET(v), PENUMBRA_BENT_FACE(i),
//             PENUMBRA_BENT_FACE_NORMAL(f); penumbraBentShade / penumbraBentDirect for the
//             fragment stage; bent_normals.comp.glsl writes l_bend per bent vertex into a buffer
//             (one dispatch when the light moves) for engines that would rather read an attribute.
//
// The shading (sintorn2008 §4.3). Per (bent) vertex v with adjacent faces F (its smooth group):
//     l_bend(v) = min over F of dot(l, n_F),   l = normalize(light centre - v)
// or, with a light radius R > 0, the minimum over every direction towards the light's bounding
// sphere: min over F of cos(angle(l, n_F) + asin(R / |c - v|)) (-1 when that angle reaches pi, and
// -1 for a vertex inside the sphere). Per fragment, with l_bend interpolated and l_f the engine's
// usual diffuse term (e.g. dot(n_interpolated, l)):
//     alpha = clamp(c * l_bend, 0, 1),   shade = alpha * l_f + (1 - alpha) * l_bend,   c = 3,
// and the direct light is max(shade, 0). Why back faces get exactly 0: a light-back-facing
// triangle is in the group of each of its corners, so all three l_bend are < 0, hence every convex
// combination the rasterizer interpolates is < 0 (float interpolation with weights >= 0 summing to
// 1 cannot leave [min, max]), alpha = 0 and shade = l_bend < 0. Vertices with no (non-degenerate)
// adjacent face get l_bend = 1 (plain Phong).
//
// Bad input (penumbra::Error naming the value): an index beyond the vertices, an index count not a
// multiple of 3, a non-finite position, a weld id beyond the vertex count, a crease angle outside
// [0, 180] (NaN included), more than 2^32 - 1 adjacency entries or bent vertices. bentLight() with
// a non-finite light or R < 0 is a PENUMBRA_ASSERT (per frame).
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
#include <unordered_map>
#include <utility>
#include <vector>

namespace penumbra {

static_assert(sizeof(shared::PenumbraBentParams) == 32, "bent_normals_shared.h: PenumbraBentParams is 32 bytes");

/// sintorn2008 §4.3: "c := 3 works well".
inline constexpr float kBentDefaultSharpness = 3.0f;

/// bentNormalMesh() settings; value-initialised = the defaults.
struct BentNormalOptions {
    /// Degrees in [0, 180], default 60: faces meeting at a vertex across an edge whose normals differ
    /// by more than this are in different smooth groups (180: no creases). 60 splits cubes (90) and
    /// tetrahedra (109.5) and not the torus knot (23) or most of spot.obj (a few edges up to 77).
    float crease_degrees = 60.0f;
};

/// The smooth groups' adjacency and the face normals of one mesh, as the shaders read them (std430).
/// Bent vertex b < vertex_count is input vertex b; b >= vertex_count a copy made at a crease.
struct BentNormalMesh {
    uint32_t vertex_count = 0;            ///< input vertices
    uint32_t crease_copies = 0;           ///< bent vertices added where creases split a vertex
    uint32_t face_count = 0;              ///< triangles of the input (degenerate ones included)
    uint32_t degenerate_faces = 0;        ///< in no adjacency list
    std::vector<uint32_t> offsets;        ///< bentVertexCount() + 1: faces of b are faces[offsets[b] .. offsets[b+1])
    std::vector<uint32_t> faces;          ///< adjacent face ids (the bent vertex's smooth group)
    std::vector<glm::vec4> face_normals;  ///< face_count: unit normal (counter-clockwise = front), w = 0
    std::vector<uint32_t> source;         ///< bentVertexCount(): the input vertex each bent vertex copies
    std::vector<uint32_t> indices;        ///< 3 per face: the bent vertex of each corner (draw / interpolate with these)

    uint32_t bentVertexCount() const { return vertex_count + crease_copies; }
    uint64_t bytes() const {
        return (offsets.size() + faces.size() + source.size() + indices.size()) * sizeof(uint32_t) +
               face_normals.size() * sizeof(glm::vec4);
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

/// Builds the smooth groups, their adjacency (welded by `weld` when given: weld[v] = the id all
/// copies of v share, an index < vertex_count) and the face normals. Throws penumbra::Error for bad
/// input (see header).
inline BentNormalMesh bentNormalMesh(const glm::vec3* positions, size_t vertex_count, const uint32_t* indices,
                                     size_t index_count, const uint32_t* weld = nullptr,
                                     const BentNormalOptions& options = {}) {
    PENUMBRA_CHECK(index_count % 3 == 0, "bentNormalMesh: index count ", index_count, " is not a multiple of 3");
    PENUMBRA_CHECK(vertex_count < 0xFFFFFFFFull && index_count / 3 < 0xFFFFFFFFull,
                   "bentNormalMesh: ", vertex_count, " vertices / ", index_count / 3, " triangles exceed 2^32 - 1");
    PENUMBRA_CHECK(vertex_count == 0 || positions != nullptr, "bentNormalMesh: positions must not be null");
    PENUMBRA_CHECK(index_count == 0 || indices != nullptr, "bentNormalMesh: indices must not be null");
    PENUMBRA_CHECK(options.crease_degrees >= 0.0f && options.crease_degrees <= 180.0f,
                   "bentNormalMesh: crease_degrees ", options.crease_degrees, " is not in [0, 180]");
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
    // A face touching two copies of one welded vertex counts once at that id.
    auto repeats = [&](uint32_t f, int k) {
        bool repeat = false;
        for (int j = 0; j < k; ++j) repeat |= id(indices[3 * f + j]) == id(indices[3 * f + k]);
        return repeat;
    };
    // The fan of each weld id: its valid faces in face order, fan[fan_offset[w] ..).
    std::vector<uint64_t> fan_offset(vertex_count + 1, 0);
    for (uint32_t f = 0; f < mesh.face_count; ++f)
        for (int k = 0; k < 3; ++k)
            if (valid[f] && !repeats(f, k)) ++fan_offset[id(indices[3 * f + k]) + 1];
    for (size_t w = 0; w < vertex_count; ++w) fan_offset[w + 1] += fan_offset[w];
    PENUMBRA_CHECK(fan_offset[vertex_count] < 0xFFFFFFFFull, "bentNormalMesh: ", fan_offset[vertex_count],
                   " adjacency entries exceed 2^32 - 1");
    std::vector<uint32_t> fan(fan_offset[vertex_count]);
    std::vector<uint64_t> cursor(fan_offset.begin(), fan_offset.end() - 1);
    for (uint32_t f = 0; f < mesh.face_count; ++f)
        for (int k = 0; k < 3; ++k)
            if (valid[f] && !repeats(f, k)) fan[cursor[id(indices[3 * f + k])]++] = f;

    // Smooth groups: within a fan, two faces join across an edge of that fan that exactly these two
    // faces share, when their normals differ by at most the crease angle (union-find over fan slots;
    // edges of one face or of three or more are creases, which keeps the work linear).
    auto degrees = [](const glm::dvec3& a, const glm::dvec3& b) {  // acos(0) -> 90 exactly: a cube at 90 is whole
        return std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0)) * (180.0 / 3.14159265358979323846);
    };
    std::vector<uint32_t> group(fan.size());  // fan slot -> a slot of its group (its root once found)
    for (uint32_t s = 0; s < group.size(); ++s) group[s] = s;
    auto root = [&](uint32_t s) {
        while (group[s] != s) s = group[s] = group[group[s]];
        return s;
    };
    std::vector<std::pair<uint32_t, uint32_t>> edges;  // (other weld id, fan slot)
    for (size_t w = 0; w < vertex_count; ++w) {
        edges.clear();
        for (uint64_t s = fan_offset[w]; s < fan_offset[w + 1]; ++s)
            for (int k = 0; k < 3; ++k) {
                const uint32_t f = fan[s], u = id(indices[3 * f + k]);
                if (u != w && !repeats(f, k)) edges.emplace_back(u, static_cast<uint32_t>(s));
            }
        std::sort(edges.begin(), edges.end());
        for (size_t e = 0; e < edges.size();) {
            size_t end = e + 1;
            while (end < edges.size() && edges[end].first == edges[e].first) ++end;
            if (end - e == 2) {
                const uint32_t a = edges[e].second, b = edges[e + 1].second;
                const glm::dvec3 na(mesh.face_normals[fan[a]]), nb(mesh.face_normals[fan[b]]);
                if (degrees(na, nb) <= double(options.crease_degrees)) group[root(a)] = root(b);
            }
            e = end;
        }
    }
    for (uint32_t s = 0; s < group.size(); ++s) group[s] = root(s);

    // Bent vertices: each input vertex v is its first group's bent vertex (its first valid corner's,
    // else its fan's first); further groups of v get copies vertex_count, vertex_count + 1, ...
    auto slot = [&](uint32_t f, uint32_t w) {  // f's slot in w's fan (fans are in face order)
        return static_cast<uint32_t>(std::lower_bound(fan.begin() + static_cast<std::ptrdiff_t>(fan_offset[w]),
                                                      fan.begin() + static_cast<std::ptrdiff_t>(fan_offset[w + 1]), f) -
                                     fan.begin());
    };
    constexpr uint32_t kNone = 0xFFFFFFFFu;
    std::vector<uint32_t> first_group(vertex_count, kNone);
    std::vector<uint32_t> corner_group(index_count, kNone);
    for (uint32_t f = 0; f < mesh.face_count; ++f)
        for (int k = 0; k < 3 && valid[f]; ++k) {
            const uint32_t v = indices[3 * f + k];
            corner_group[3 * f + k] = group[slot(f, id(v))];
            if (first_group[v] == kNone) first_group[v] = corner_group[3 * f + k];
        }
    for (size_t v = 0; v < vertex_count; ++v) {
        const uint32_t w = id(static_cast<uint32_t>(v));
        if (first_group[v] == kNone && fan_offset[w] < fan_offset[w + 1]) first_group[v] = group[fan_offset[w]];
    }
    mesh.source.resize(vertex_count);
    for (size_t v = 0; v < vertex_count; ++v) mesh.source[v] = static_cast<uint32_t>(v);
    std::vector<uint32_t> bent_group(first_group);  // bent vertex -> its group (kNone: no faces)
    std::unordered_map<uint64_t, uint32_t> copies;  // (v << 32) | group -> bent vertex
    mesh.indices.assign(indices, indices + index_count);
    for (size_t c = 0; c < index_count; ++c) {
        const uint32_t v = indices[c], g = corner_group[c];
        if (g == kNone || g == first_group[v]) continue;
        const auto [it, added] = copies.emplace((uint64_t(v) << 32) | g, static_cast<uint32_t>(mesh.source.size()));
        if (added) {
            PENUMBRA_CHECK(mesh.source.size() < 0xFFFFFFFFull, "bentNormalMesh: crease copies exceed 2^32 - 1 vertices");
            mesh.source.push_back(v);
            bent_group.push_back(g);
        }
        mesh.indices[c] = it->second;
    }
    mesh.crease_copies = static_cast<uint32_t>(mesh.source.size() - vertex_count);

    // Each group's faces, in face order: members of a fan sorted by (group, slot).
    std::vector<uint32_t> members(fan.size());
    for (uint32_t s = 0; s < members.size(); ++s) members[s] = s;
    std::stable_sort(members.begin(), members.end(), [&](uint32_t a, uint32_t b) { return group[a] < group[b]; });
    std::vector<uint32_t> group_first(fan.size(), 0), group_size(fan.size(), 0);  // by root slot
    for (size_t i = members.size(); i-- > 0;) {
        group_first[group[members[i]]] = static_cast<uint32_t>(i);
        ++group_size[group[members[i]]];
    }
    uint64_t total = 0;
    for (uint32_t g : bent_group) total += g == kNone ? 0 : group_size[g];
    PENUMBRA_CHECK(total < 0xFFFFFFFFull, "bentNormalMesh: ", total, " adjacency entries exceed 2^32 - 1");
    mesh.offsets.resize(bent_group.size() + 1);
    mesh.faces.reserve(total);
    for (size_t b = 0; b < bent_group.size(); ++b) {
        mesh.offsets[b] = static_cast<uint32_t>(mesh.faces.size());
        const uint32_t g = bent_group[b];
        if (g == kNone) continue;
        for (uint32_t i = group_first[g]; i < group_first[g] + group_size[g]; ++i) mesh.faces.push_back(fan[members[i]]);
    }
    mesh.offsets[bent_group.size()] = static_cast<uint32_t>(mesh.faces.size());
    return mesh;
}

/// l_bend of bent vertex `vertex` (< bentVertexCount()) at `position` (of input vertex
/// source[vertex]) for a light at `centre` of bounding radius `radius` (0: toward the centre only).
/// CPU twin of penumbraBentLight (float, the same operations).
inline float bentLight(const BentNormalMesh& mesh, uint32_t vertex, const glm::vec3& position, const glm::vec3& centre,
                       float radius = 0.0f) {
    using detail::dotRounded;
    using detail::mulRounded;
    PENUMBRA_ASSERT(vertex < mesh.bentVertexCount() && radius >= 0.0f);
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
