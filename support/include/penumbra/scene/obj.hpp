// penumbra::scene OBJ loading — Wavefront OBJ files as penumbra scenes, via tinyobjloader.
//
// Integration: needs tinyobjloader's header <tiny_obj_loader.h> and its compiled library: link
// tinyobjloader (CMake target tinyobjloader::tinyobjloader, or -ltinyobjloader). Do NOT define
// TINYOBJLOADER_IMPLEMENTATION (the library holds it), nor TINYOBJLOADER_USE_DOUBLE unless you
// link tinyobjloader_double instead. Also uses scene.hpp (GLM).
// Produces a Scene like the builtins: {ground, object} (or {object}) with the default camera and
// light, so `load("builtin:grass")` and `load("meshes/spot.obj")` are interchangeable.
// What loadObj does with the file:
//   - every shape/group goes into one object mesh named after the file's stem;
//   - only positions and normals are used (texture coordinates and materials are ignored; a
//     missing .mtl is not an error);
//   - polygons are triangulated keeping their winding: quads along the shorter diagonal (as
//     tinyobjloader does), larger polygons by ear clipping in the polygon's Newell plane;
//   - triangles that repeat a vertex index are dropped, unreferenced vertices are removed;
//   - file normals are kept only if every use of a position names the same normal (one normal
//     per vertex); otherwise, or if absent, smooth angle-weighted normals are computed;
//   - closed = every edge shared by exactly two triangles with opposite orientation; a closed
//     mesh with negative signed volume (inside-out) is flipped so that it faces outward.
// Failures throw penumbra::Error naming the path and the reason.
#ifndef PENUMBRA_SCENE_OBJ_HPP
#define PENUMBRA_SCENE_OBJ_HPP

#include <penumbra/error.hpp>
#include <penumbra/scene/scene.hpp>

#include <tiny_obj_loader.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace penumbra::scene {

/// Value-initialised = defaults.
struct ObjOptions {
    bool ground = true;     // add a ground plane under the object
    bool normalize = true;  // scale uniformly so the largest extent is 1, centre on the y axis
                            // and rest on the ground y = 0; otherwise keep file coordinates and
                            // put the ground (if any) at the object's lowest y
};

/// Loads a Wavefront OBJ file as a Scene (see the summary above for what is kept and how).
/// Throws penumbra::Error naming `path` when the file cannot be opened or parsed, a face uses a
/// vertex index that does not exist, a used vertex has a NaN or infinite coordinate, no
/// triangle is left, or all vertices coincide.
inline Scene loadObj(const std::string& path, const ObjOptions& options = {});

/// "builtin:NAME" -> builtin(NAME); anything else is a path for loadObj with default options.
inline Scene load(const std::string& spec);

// =============================================================================================
// Implementation

namespace detail {

/// Triangulates one polygon given its corner positions, appending corner-index triples
/// (0 .. n-1) that keep the polygon's winding, so closed-mesh orientation survives.
inline void triangulatePolygon(const std::vector<glm::vec3>& corners,
                               std::vector<std::array<uint32_t, 3>>& triangles) {
    const uint32_t n = static_cast<uint32_t>(corners.size());
    if (n < 3) return;
    if (n == 3) {
        triangles.push_back({0, 1, 2});
        return;
    }
    if (n == 4) {
        // Shorter diagonal: the better split of a non-planar quad, and tinyobjloader's choice.
        const glm::vec3 d02 = corners[2] - corners[0], d13 = corners[3] - corners[1];
        if (glm::dot(d02, d02) <= glm::dot(d13, d13)) {
            triangles.push_back({0, 1, 2});
            triangles.push_back({0, 2, 3});
        } else {
            triangles.push_back({0, 1, 3});
            triangles.push_back({1, 2, 3});
        }
        return;
    }
    // Newell's normal is robust for non-planar and concave polygons.
    glm::dvec3 normal(0.0);
    for (uint32_t i = 0; i < n; ++i) {
        const glm::dvec3 a(corners[i]), b(corners[(i + 1) % n]);
        normal += glm::dvec3((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x),
                             (a.x - b.x) * (a.y + b.y));
    }
    std::vector<uint32_t> remaining(n);
    for (uint32_t i = 0; i < n; ++i) remaining[i] = i;
    // Ear clipping is O(n^2) per ear; huge polygons (rare in practice) fall back to a fan.
    const bool clip_ears = glm::length(normal) > 0.0 && n <= 256;
    auto cornerAt = [&](uint32_t k) { return glm::dvec3(corners[remaining[k]]); };
    auto side = [&](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& p) {
        return glm::dot(glm::cross(b - a, p - a), normal);
    };
    while (remaining.size() > 3) {
        const uint32_t m = static_cast<uint32_t>(remaining.size());
        uint32_t ear = 0;  // fan from the first corner if no ear is found
        if (clip_ears) {
            for (uint32_t k = 0; k < m; ++k) {
                const glm::dvec3 a = cornerAt((k + m - 1) % m), b = cornerAt(k), c = cornerAt((k + 1) % m);
                if (side(a, b, c) <= 0.0) continue;  // reflex or degenerate corner
                bool contains_other = false;
                for (uint32_t other = 0; other < m && !contains_other; ++other) {
                    if (other == k || other == (k + 1) % m || other == (k + m - 1) % m) continue;
                    const glm::dvec3 p = cornerAt(other);
                    contains_other = side(a, b, p) >= 0.0 && side(b, c, p) >= 0.0 && side(c, a, p) >= 0.0;
                }
                if (!contains_other) {
                    ear = k;
                    break;
                }
            }
        }
        triangles.push_back({remaining[(ear + m - 1) % m], remaining[ear], remaining[(ear + 1) % m]});
        remaining.erase(remaining.begin() + ear);
    }
    triangles.push_back({remaining[0], remaining[1], remaining[2]});
}

inline std::string trimTrailingSpace(std::string text) {
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' '))
        text.pop_back();
    return text;
}

inline std::string fileStem(const std::string& path) {
    const size_t slash = path.find_last_of("/\\");
    std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    const size_t dot = name.find_last_of('.');
    if (dot != std::string::npos && dot > 0) name.resize(dot);
    return name.empty() ? std::string("obj") : name;
}

}  // namespace detail

inline Scene loadObj(const std::string& path, const ObjOptions& options) {
    const std::string where = "penumbra::scene::loadObj('" + path + "'): ";
    {
        std::ifstream probe(path);
        PENUMBRA_CHECK(probe.is_open(), where, "cannot open file");
    }
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> materials;
    std::string warnings, errors;
    const size_t slash = path.find_last_of("/\\");
    const std::string directory = slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
    // triangulate = false: we triangulate ourselves so winding (hence closedness) is preserved
    // whichever triangulator the installed tinyobjloader was built with.
    const bool parsed = tinyobj::LoadObj(&attrib, &shapes, &materials, &warnings, &errors, path.c_str(),
                                         directory.c_str(), /*triangulate=*/false);
    PENUMBRA_CHECK(parsed, where, "parse error: ", detail::trimTrailingSpace(errors));

    const size_t vertex_count = attrib.vertices.size() / 3;
    const size_t normal_count = attrib.normals.size() / 3;
    auto filePosition = [&](size_t v) {
        return glm::vec3(static_cast<float>(attrib.vertices[3 * v]), static_cast<float>(attrib.vertices[3 * v + 1]),
                         static_cast<float>(attrib.vertices[3 * v + 2]));
    };

    // Triangles in file vertex indices, plus the normal index each corner named (-1 if none).
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<std::array<int, 3>> triangle_normals;
    std::vector<std::array<uint32_t, 3>> local;
    std::vector<glm::vec3> corners;
    for (const tinyobj::shape_t& shape : shapes) {
        const std::vector<tinyobj::index_t>& indices = shape.mesh.indices;
        size_t offset = 0;
        for (size_t face = 0; face < shape.mesh.num_face_vertices.size(); ++face) {
            const size_t n = shape.mesh.num_face_vertices[face];
            // tinyobjloader stores face sizes as unsigned char: a face of 256+ corners would
            // desynchronise the index stream, which this catches below.
            PENUMBRA_CHECK(offset + n <= indices.size(), where, "malformed face data in shape '",
                           shape.name, "' (a face with more than 255 corners?)");
            corners.clear();
            for (size_t k = 0; k < n; ++k) {
                const int v = indices[offset + k].vertex_index;
                PENUMBRA_CHECK(v >= 0 && static_cast<size_t>(v) < vertex_count, where, "face ", face + 1,
                               " of shape '", shape.name, "' uses vertex ", v + 1, " but the file has ",
                               vertex_count, " vertices");
                corners.push_back(filePosition(static_cast<size_t>(v)));
            }
            local.clear();
            detail::triangulatePolygon(corners, local);
            for (const std::array<uint32_t, 3>& t : local) {
                std::array<uint32_t, 3> triangle{};
                std::array<int, 3> normals{};
                for (size_t k = 0; k < 3; ++k) {
                    const tinyobj::index_t& corner = indices[offset + t[k]];
                    triangle[k] = static_cast<uint32_t>(corner.vertex_index);
                    normals[k] = corner.normal_index;
                }
                // A repeated index is no triangle at all and would poison the edge topology.
                if (triangle[0] == triangle[1] || triangle[1] == triangle[2] || triangle[2] == triangle[0])
                    continue;
                triangles.push_back(triangle);
                triangle_normals.push_back(normals);
            }
            offset += n;
        }
        PENUMBRA_CHECK(offset == indices.size(), where, "malformed face data in shape '", shape.name,
                       "' (a face with more than 255 corners?)");
    }
    PENUMBRA_CHECK(!triangles.empty(), where, "no triangles (", vertex_count, " vertices, ",
                   shapes.size(), " shapes)");
    PENUMBRA_CHECK(triangles.size() * 3 <= detail::kMaxSceneVertices, where, "too many triangles");

    // Keep used vertices only, in file order, so the mesh bounds are the object's.
    constexpr uint32_t kUnused = UINT32_MAX;
    std::vector<uint32_t> remap(vertex_count, kUnused);
    for (const auto& triangle : triangles)
        for (uint32_t v : triangle) remap[v] = 0;
    Mesh mesh;
    mesh.name = detail::fileStem(path);
    for (size_t v = 0; v < vertex_count; ++v) {
        if (remap[v] == kUnused) continue;
        const glm::vec3 p = filePosition(v);
        PENUMBRA_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), where, "vertex ",
                       v + 1, " has a NaN or infinite coordinate (", p.x, ", ", p.y, ", ", p.z, ")");
        remap[v] = static_cast<uint32_t>(mesh.positions.size());
        mesh.positions.push_back(p);
    }
    mesh.indices.reserve(triangles.size() * 3);
    for (const auto& triangle : triangles)
        for (uint32_t v : triangle) mesh.indices.push_back(remap[v]);

    // File normals are usable only as one normal per position: per-corner normals (hard edges)
    // would need split vertices, which would break index-based adjacency.
    bool use_file_normals = normal_count > 0;
    std::vector<int> vertex_normal(mesh.positions.size(), -1);
    for (size_t t = 0; t < triangles.size() && use_file_normals; ++t) {
        for (size_t k = 0; k < 3 && use_file_normals; ++k) {
            const int n = triangle_normals[t][k];
            if (n < 0 || static_cast<size_t>(n) >= normal_count) {
                use_file_normals = false;
                break;
            }
            int& chosen = vertex_normal[mesh.indices[3 * t + k]];
            if (chosen < 0) {
                chosen = n;
            } else if (chosen != n) {
                for (size_t c = 0; c < 3; ++c)  // different index, same vector is still one normal
                    use_file_normals = use_file_normals && attrib.normals[3 * size_t(chosen) + c] ==
                                                               attrib.normals[3 * size_t(n) + c];
            }
        }
    }
    if (use_file_normals) {
        mesh.normals.resize(mesh.positions.size());
        for (size_t v = 0; v < mesh.positions.size() && use_file_normals; ++v) {
            const size_t n = static_cast<size_t>(vertex_normal[v]);
            const glm::vec3 normal(static_cast<float>(attrib.normals[3 * n]), static_cast<float>(attrib.normals[3 * n + 1]),
                                   static_cast<float>(attrib.normals[3 * n + 2]));
            const float length = glm::length(normal);
            use_file_normals = std::isfinite(length) && length > 0.0f;
            if (use_file_normals) mesh.normals[v] = normal / length;
        }
    }

    mesh.closed = isClosed(mesh);
    if (mesh.closed && signedVolume(mesh) < 0.0) {
        for (size_t t = 0; t < mesh.indices.size(); t += 3) std::swap(mesh.indices[t + 1], mesh.indices[t + 2]);
    }
    if (use_file_normals) {
        // Files whose normals oppose their winding (on the whole) get them turned around, so
        // shading agrees with the front faces that culling and shadow casting use.
        double agreement = 0.0;
        for (size_t t = 0; t < mesh.indices.size(); t += 3) {
            const glm::vec3 a = mesh.positions[mesh.indices[t]], b = mesh.positions[mesh.indices[t + 1]],
                            c = mesh.positions[mesh.indices[t + 2]];
            const glm::vec3 sum = mesh.normals[mesh.indices[t]] + mesh.normals[mesh.indices[t + 1]] +
                                  mesh.normals[mesh.indices[t + 2]];
            agreement += static_cast<double>(glm::dot(glm::cross(b - a, c - a), sum));
        }
        if (agreement < 0.0)
            for (glm::vec3& normal : mesh.normals) normal = -normal;
    } else {
        computeSmoothNormals(mesh);
    }

    const Bounds box = mesh.bounds();
    const glm::vec3 size = box.size();
    const float extent = std::max(size.x, std::max(size.y, size.z));
    PENUMBRA_CHECK(std::isfinite(extent), where, "coordinates too large (extent overflows float)");
    PENUMBRA_CHECK(extent > 0.0f, where, "all ", mesh.positions.size(), " used vertices coincide");
    float ground_y = box.min.y;
    if (options.normalize) {
        detail::fitUnitBoxOnGround(mesh);
        ground_y = 0.0f;
    }
    return sceneFromMesh(std::move(mesh), ground_y, options.ground);
}

inline Scene load(const std::string& spec) {
    static const std::string kBuiltinPrefix = "builtin:";
    if (spec.compare(0, kBuiltinPrefix.size(), kBuiltinPrefix) == 0)
        return builtin(spec.substr(kBuiltinPrefix.size()));
    return loadObj(spec);
}

}  // namespace penumbra::scene

#endif
