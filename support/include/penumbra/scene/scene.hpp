// penumbra::scene — procedural test scenes for soft-shadow tests, examples and benchmarks.
// Part of penumbra::support (support/include/; a core install has none of it, see CMakeLists.txt:
// PENUMBRA_BUILD_SUPPORT). CMake target penumbra::support links tinyobjloader and stb.
//
// Integration: header-only, needs GLM and penumbra/error.hpp; no GL, no files, no links.
// Produces plain indexed triangle meshes (positions, per-vertex unit normals, uint32 triangle
// lists with counter-clockwise front faces) gathered in a Scene with a default Camera and a
// spherical Light. Conventions shared by every scene:
//   - y is up, the ground plane lies at y = 0, the object fits about a unit box standing on it;
//   - Scene::meshes is {ground, object} (or {object} without ground), named "ground" and the scene;
//   - the default camera sees the object and its shadow on the ground for any aspect >= 1; the
//     light sits above and to the left-front at ~3 units with radius ~0.15, so penumbrae show;
//   - Mesh::closed promises an edge-manifold, watertight, outward-oriented mesh, which is what
//     shadow-volume style casters need to use light-back-facing culling and silhouette counting;
//   - generation is deterministic: same arguments, same mesh. Randomness comes from a fixed
//     PCG32 (the same sequence with every standard library), never from std distributions.
// Bad arguments throw penumbra::Error naming the function and the value.
#ifndef PENUMBRA_SCENE_SCENE_HPP
#define PENUMBRA_SCENE_SCENE_HPP

#include <penumbra/error.hpp>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace penumbra::scene {

/// Axis-aligned box. The default value is the empty box (min > max), which extend() grows.
struct Bounds {
    glm::vec3 min{std::numeric_limits<float>::max()};
    glm::vec3 max{std::numeric_limits<float>::lowest()};

    bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
    glm::vec3 center() const { return 0.5f * (min + max); }
    glm::vec3 size() const { return max - min; }
    void extend(const glm::vec3& point) {
        min = glm::min(min, point);
        max = glm::max(max, point);
    }
    void extend(const Bounds& other) {
        if (other.empty()) return;
        extend(other.min);
        extend(other.max);
    }
};

/// Indexed triangle mesh. One vertex per position: hard edges are not split, so index-based
/// adjacency (silhouettes, GL_TRIANGLES_ADJACENCY) sees the real topology.
struct Mesh {
    std::string name;
    std::vector<glm::vec3> positions;  // positions.size() vertices
    std::vector<glm::vec3> normals;    // per vertex, unit length, same size as positions
    std::vector<uint32_t> indices;     // triangle list, 3 per triangle, counter-clockwise = front
    bool closed = false;  // every directed edge has exactly one opposite twin and the surface
                          // faces outward (positive signed volume); never true for an empty mesh

    size_t triangleCount() const { return indices.size() / 3; }
    Bounds bounds() const {
        Bounds box;
        for (const glm::vec3& p : positions) box.extend(p);
        return box;
    }
};

/// Right-handed look-at camera; projection() follows GLM's configured clip convention
/// (OpenGL depth [-1, 1] unless the engine defines GLM_FORCE_DEPTH_ZERO_TO_ONE).
struct Camera {
    glm::vec3 eye{0.0f, 1.5f, 3.0f};
    glm::vec3 target{0.0f, 0.5f, 0.0f};
    glm::vec3 up{0.0f, 1.0f, 0.0f};
    float fov_y_degrees = 45.0f;
    float z_near = 0.05f, z_far = 50.0f;

    /// Throws penumbra::Error if eye == target or up is parallel to the view direction.
    glm::mat4 view() const {
        const glm::vec3 forward = target - eye;
        PENUMBRA_CHECK(glm::length(forward) > 0.0f,
                       "penumbra::scene::Camera::view: eye equals target (", eye.x, ", ", eye.y,
                       ", ", eye.z, ")");
        PENUMBRA_CHECK(glm::length(glm::cross(forward, up)) > 0.0f,
                       "penumbra::scene::Camera::view: up (", up.x, ", ", up.y, ", ", up.z,
                       ") is zero or parallel to the view direction");
        return glm::lookAt(eye, target, up);
    }
    /// aspect = width / height. Throws penumbra::Error on a non-positive aspect, a field of view
    /// outside (0, 180) degrees or planes that do not satisfy 0 < z_near < z_far.
    glm::mat4 projection(float aspect) const {
        PENUMBRA_CHECK(std::isfinite(aspect) && aspect > 0.0f,
                       "penumbra::scene::Camera::projection: aspect must be > 0, got ", aspect);
        PENUMBRA_CHECK(fov_y_degrees > 0.0f && fov_y_degrees < 180.0f,
                       "penumbra::scene::Camera::projection: fov_y_degrees must be in (0, 180), got ",
                       fov_y_degrees);
        PENUMBRA_CHECK(z_near > 0.0f && z_far > z_near && std::isfinite(z_far),
                       "penumbra::scene::Camera::projection: need 0 < z_near < z_far, got z_near = ",
                       z_near, ", z_far = ", z_far);
        return glm::perspective(glm::radians(fov_y_degrees), aspect, z_near, z_far);
    }
};

/// Spherical (volumetric) light: soft shadows come from its nonzero radius.
struct Light {
    glm::vec3 position{0.0f, 3.0f, 0.0f};
    float radius = 0.15f;
};

struct Scene {
    std::string name;
    std::vector<Mesh> meshes;  // {ground, object}, or {object} when built without ground
    Camera camera;             // frames the object and its shadow (aspect >= 1)
    Light light;               // above and to the side, shadow lands on the ground in view

    /// Union of every mesh's bounds (ground included); empty() when there are no vertices.
    Bounds bounds() const {
        Bounds box;
        for (const Mesh& mesh : meshes) box.extend(mesh.bounds());
        return box;
    }
    size_t triangleCount() const {
        size_t count = 0;
        for (const Mesh& mesh : meshes) count += mesh.triangleCount();
        return count;
    }
    /// All meshes in one, named after the scene. closed is true only when every mesh is closed
    /// (disjoint closed pieces stay closed: indices are offset, so no edge gains a false twin);
    /// with a ground plane it is therefore false. Throws penumbra::Error past 2^32 vertices.
    Mesh merged() const;
    /// merged() without the ground (the mesh named "ground"): the casters of a scene whose ground
    /// only receives (it lies below everything it could shadow). Triangle i is the i-th non-ground
    /// triangle in scene order.
    Mesh casters() const;

private:
    Mesh mergedMeshes(bool with_ground) const;
};

// ---------------------------------------------------------------------------------------------
// Mesh utilities

/// Recomputes normals as the angle-weighted average of adjacent face normals (Thürmer and
/// Wüthrich 1998): unlike area weighting, a vertex's normal does not depend on how the faces
/// around it happen to be split. Vertices without a non-degenerate face get (0, 1, 0).
inline void computeSmoothNormals(Mesh& mesh);

/// True when the mesh is nonempty and every directed edge (a, b) occurs exactly once and its
/// twin (b, a) exactly once: watertight, edge-manifold, consistently oriented. Says nothing about
/// inside/outside; see signedVolume().
inline bool isClosed(const Mesh& mesh);

/// Signed volume by the divergence theorem; positive for a closed mesh facing outward.
inline double signedVolume(const Mesh& mesh);

/// Throws penumbra::Error naming the first problem: normals/positions size mismatch, index
/// count not a multiple of 3, index out of range, a triangle repeating a vertex, a non-finite
/// position, or a normal that is not unit length (tolerance 1e-3).
inline void validateMesh(const Mesh& mesh);

// ---------------------------------------------------------------------------------------------
// Generators

/// Square plane of side 2 * half_size centred on the y axis at height y, normal +y, split into
/// subdivisions^2 quads (2 triangles each). Open (closed = false), named "ground".
/// Throws penumbra::Error unless half_size > 0, y finite, 1 <= subdivisions <= 65534.
inline Mesh groundPlane(float half_size, float y = 0.0f, uint32_t subdivisions = 1);

/// Frames a scene around `object`: the Scene takes the object's name, gets a ground plane at
/// ground_y (if `ground`) large enough for the shadow, and the default camera and light.
/// An empty object is framed as if it were the unit box standing at ground_y.
/// Throws penumbra::Error for non-finite bounds or an object of zero extent.
inline Scene sceneFromMesh(Mesh object, float ground_y = 0.0f, bool ground = true);

/// (p, q) = (2, 3) torus knot tube, closed, standing upright (knot plane = xy) on the ground.
/// 4 * tessellation segments along the knot, max(3, tessellation / 4) sides around the tube,
/// so 2 * segments * sides triangles (8192 for the default). Normals are the exact tube normals.
/// Throws penumbra::Error if tessellation < 3 or the mesh would exceed 2^32 vertices.
inline Scene torusKnot(uint32_t tessellation = 64, bool ground = true);

/// `count` columns in a near-square grid inside the unit footprint, alternating rounded boxes
/// and cylinders (checkerboard), plus a lintel resting on the back row (most negative z) when
/// that row has two or more columns (columns 0.85 high, 0.95 with the lintel). Every piece is
/// closed (the lintel slightly sinks into the column tops, so no light leaks through the
/// joints), so the object mesh is closed.
/// Edges are bevelled so that smooth normals stay flat on the faces. count = 0 gives an empty
/// object mesh (closed = false) framed like the unit box.
/// Throws penumbra::Error if the mesh would exceed 2^32 vertices.
inline Scene columns(uint32_t count = 9, bool ground = true);

/// `triangles` thin random sliver triangles (hair strands 0.08-0.25 long, 0.002-0.008 wide,
/// random orientation, 3 unshared vertices each, face normals) inside a ball of radius 0.45
/// centred at (0, 0.55, 0), floating 0.1 above the ground. Open. triangles = 0 gives an empty
/// object mesh. Same (triangles, seed) -> same mesh, and the first n strands do not depend on
/// `triangles`. Throws penumbra::Error past 2^32 vertices.
inline Scene hairball(uint32_t triangles = 20000, uint32_t seed = 1, bool ground = true);

/// `blades` thin curved grass blades (7 triangles, 9 vertices each; height 0.3-0.8, base width
/// 0.012-0.025, tapering to a tip, bent along a parabola) rooted on the ground in the ring
/// 0.2 <= r <= 0.5. Open. blades = 0 gives an empty object mesh. Same (blades, seed) -> same
/// mesh, and the first n blades do not depend on `blades`. Throws penumbra::Error past 2^32
/// vertices.
inline Scene grass(uint32_t blades = 2000, uint32_t seed = 1, bool ground = true);

/// The columns scene (columns(9)) beside a wall with three tall windows on the light's side: the
/// wall's shadow falls across the floor behind the columns, the light reaching it through the
/// windows, so a spot light in fog has openings to shine through (soft_shadows --mode volumetric).
/// The wall (x from -0.75 to -0.69, z from -0.6 to 0.6, 1.3 high; windows 0.22 wide from y = 0.45
/// to 1.05) is closed pieces: a sill band, a head band and four piers sunk 0.05 into both bands so
/// no light leaks at the joints; the object mesh is closed. Framing and light as
/// sceneFromMesh. Not in builtinNames(): see there.
inline Scene windowWall(bool ground = true);

/// {"torus_knot", "columns", "hairball", "grass"}: the object scenes every block is tested and
/// benchmarked on. builtin() also knows extraBuiltinNames().
inline std::vector<std::string> builtinNames();

/// {"window_wall"}: scenes made for one mode's demo (window_wall: light shafts through openings),
/// known to builtin() and load("builtin:...") but left out of builtinNames()'s test sweeps.
inline std::vector<std::string> extraBuiltinNames();

/// The builtin scene `name` with default arguments; throws penumbra::Error listing the valid
/// names when `name` is unknown.
inline Scene builtin(const std::string& name);

// =============================================================================================
// Implementation

namespace detail {

inline constexpr uint64_t kMaxSceneVertices = std::numeric_limits<uint32_t>::max();
inline constexpr double kPi = 3.14159265358979323846;

/// PCG32 (O'Neill 2014, pcg32_srandom_r / pcg32_random_r): tiny, fast and, unlike the std
/// distributions, gives the same sequence with every standard library.
class Pcg32 {
public:
    Pcg32(uint64_t seed, uint64_t stream) : inc_((stream << 1u) | 1u) {
        next();
        state_ += seed;
        next();
    }
    uint32_t next() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ULL + inc_;
        const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((32u - rot) & 31u));
    }
    /// Uniform in [0, 1): the top 24 bits are exactly representable as float.
    float uniform() { return static_cast<float>(next() >> 8) * (1.0f / 16777216.0f); }
    float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
    /// Uniform in the unit ball, by rejection (deterministic, no transcendental functions).
    glm::vec3 inUnitBall() {
        for (;;) {
            const glm::vec3 v(uniform(-1.0f, 1.0f), uniform(-1.0f, 1.0f), uniform(-1.0f, 1.0f));
            if (glm::dot(v, v) <= 1.0f) return v;
        }
    }
    glm::vec3 unitVector() {
        for (;;) {
            const glm::vec3 v = inUnitBall();
            const float length_squared = glm::dot(v, v);
            if (length_squared > 1e-4f) return v / std::sqrt(length_squared);
        }
    }

private:
    uint64_t state_ = 0;
    uint64_t inc_;
};

// Distinct PCG streams so that scenes built from the same seed are uncorrelated.
inline constexpr uint64_t kHairballStream = 0x6861697262616c6cULL;  // "hairball"
inline constexpr uint64_t kGrassStream = 0x6772617373ULL;            // "grass"

inline void checkVertexBudget(const char* function, uint64_t vertices) {
    PENUMBRA_CHECK(vertices <= kMaxSceneVertices, "penumbra::scene::", function, ": ", vertices,
                   " vertices exceed the 32-bit index range");
}

/// Uniformly scales and moves the mesh so its largest extent is 1, centred on the y axis and
/// standing on y = 0. Normals are unaffected by a uniform scale.
inline void fitUnitBoxOnGround(Mesh& mesh) {
    const Bounds box = mesh.bounds();
    if (box.empty()) return;
    const glm::vec3 size = box.size();
    const float extent = std::max(size.x, std::max(size.y, size.z));
    PENUMBRA_CHECK(extent > 0.0f && std::isfinite(extent), "penumbra::scene: mesh '", mesh.name,
                   "' has zero or non-finite extent ", extent);
    const glm::vec3 anchor(box.center().x, box.min.y, box.center().z);
    for (glm::vec3& p : mesh.positions) p = (p - anchor) / extent;
}

enum class PrismSection { roundedBox, cylinder };

/// Appends a closed prism standing at base_center: a cross-section swept from y = 0 to height
/// with bevelled rims. Rings (inset, y) run from the bottom pole out, up and back in to the top
/// pole. The two rings per cap and per side edge keep angle-weighted normals exact on the flat
/// faces and confine the rounding to the bevel, which flat-shaded boxes would need split
/// vertices for (and split vertices would break index-based closedness).
inline void appendRoundedPrism(Mesh& mesh, const glm::vec3& base_center, float half_x,
                               float half_z, float height, PrismSection shape) {
    const float bevel = 0.08f * std::min(std::min(half_x, half_z), 0.5f * height);
    const std::array<glm::vec2, 8> rings = {{{2 * bevel, 0.0f},
                                             {bevel, 0.0f},
                                             {0.0f, bevel},
                                             {0.0f, 2 * bevel},
                                             {0.0f, height - 2 * bevel},
                                             {0.0f, height - bevel},
                                             {bevel, height},
                                             {2 * bevel, height}}};

    // Section points run counter-clockwise seen from above: (x, z) = (cos t, -sin t).
    std::vector<glm::vec2> section;
    auto buildSection = [&](float inset) {
        section.clear();
        if (shape == PrismSection::cylinder) {
            constexpr uint32_t kSides = 32;
            for (uint32_t j = 0; j < kSides; ++j) {
                const double t = 2.0 * kPi * j / kSides;
                section.emplace_back(static_cast<float>(std::cos(t)) * (half_x - inset),
                                     -static_cast<float>(std::sin(t)) * (half_z - inset));
            }
            return;
        }
        // Rounded rectangle: insetting by d keeps the corner centres and shrinks the radius,
        // so every ring is an exact offset of the outer one.
        constexpr uint32_t kArcSegments = 3;
        constexpr float kGuard = 0.15f;  // extra points near each flat side's ends keep it flat
        const float corner_radius = 0.3f * std::min(half_x, half_z);
        const float radius = corner_radius - inset;
        auto arcPoint = [&](uint32_t corner, uint32_t i) {
            const double mid = kPi / 2 * corner + kPi / 4;
            const float sx = std::cos(mid) > 0 ? 1.0f : -1.0f;
            const float sz = -std::sin(mid) > 0 ? 1.0f : -1.0f;
            const glm::vec2 centre(sx * (half_x - corner_radius), sz * (half_z - corner_radius));
            const double t = kPi / 2 * corner + kPi / 2 * i / kArcSegments;
            return centre + radius * glm::vec2(static_cast<float>(std::cos(t)),
                                               -static_cast<float>(std::sin(t)));
        };
        for (uint32_t corner = 0; corner < 4; ++corner) {
            for (uint32_t i = 0; i <= kArcSegments; ++i) section.push_back(arcPoint(corner, i));
            const glm::vec2 side_start = arcPoint(corner, kArcSegments);
            const glm::vec2 side_end = arcPoint((corner + 1) % 4, 0);
            section.push_back(side_start + kGuard * (side_end - side_start));
            section.push_back(side_end - kGuard * (side_end - side_start));
        }
    };
    buildSection(0.0f);
    const uint32_t n = static_cast<uint32_t>(section.size());
    const uint64_t added = 2u + uint64_t(rings.size()) * n;
    checkVertexBudget("columns", mesh.positions.size() + added);

    const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
    const uint32_t ring_count = static_cast<uint32_t>(rings.size());
    const uint32_t top_pole = base + 1 + ring_count * n;
    mesh.positions.push_back(base_center + glm::vec3(0.0f, rings.front().y, 0.0f));
    for (const glm::vec2& ring : rings) {
        buildSection(ring.x);
        for (const glm::vec2& p : section)
            mesh.positions.push_back(base_center + glm::vec3(p.x, ring.y, p.y));
    }
    mesh.positions.push_back(base_center + glm::vec3(0.0f, rings.back().y, 0.0f));

    auto at = [&](uint32_t ring, uint32_t j) { return base + 1 + ring * n + j % n; };
    for (uint32_t j = 0; j < n; ++j) {
        // Bottom cap faces down: reversed relative to the counter-clockwise-from-above section.
        mesh.indices.insert(mesh.indices.end(), {base, at(0, j + 1), at(0, j)});
        for (uint32_t r = 0; r + 1 < ring_count; ++r) {
            const uint32_t a = at(r, j), b = at(r, j + 1), c = at(r + 1, j + 1), d = at(r + 1, j);
            mesh.indices.insert(mesh.indices.end(), {a, b, c, a, c, d});
        }
        mesh.indices.insert(mesh.indices.end(), {top_pole, at(ring_count - 1, j),
                                                 at(ring_count - 1, j + 1)});
    }
}

}  // namespace detail

inline Mesh Scene::merged() const { return mergedMeshes(true); }
inline Mesh Scene::casters() const { return mergedMeshes(false); }

inline Mesh Scene::mergedMeshes(bool with_ground) const {
    Mesh out;
    out.name = name;
    uint64_t vertex_total = 0;
    size_t index_total = 0;
    const auto kept = [with_ground](const Mesh& mesh) { return with_ground || mesh.name != "ground"; };
    for (const Mesh& mesh : meshes) {
        if (!kept(mesh)) continue;
        vertex_total += mesh.positions.size();
        index_total += mesh.indices.size();
    }
    detail::checkVertexBudget("Scene::merged", vertex_total);
    out.positions.reserve(static_cast<size_t>(vertex_total));
    out.normals.reserve(static_cast<size_t>(vertex_total));
    out.indices.reserve(index_total);
    bool all_closed = true, any = false;
    for (const Mesh& mesh : meshes) {
        if (!kept(mesh)) continue;
        any = true;
        const uint32_t offset = static_cast<uint32_t>(out.positions.size());
        out.positions.insert(out.positions.end(), mesh.positions.begin(), mesh.positions.end());
        out.normals.insert(out.normals.end(), mesh.normals.begin(), mesh.normals.end());
        for (uint32_t index : mesh.indices) out.indices.push_back(index + offset);
        all_closed = all_closed && mesh.closed;
    }
    out.closed = any && all_closed;
    return out;
}

inline void computeSmoothNormals(Mesh& mesh) {
    std::vector<glm::dvec3> sums(mesh.positions.size(), glm::dvec3(0.0));
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const uint32_t v[3] = {mesh.indices[t], mesh.indices[t + 1], mesh.indices[t + 2]};
        PENUMBRA_CHECK(v[0] < sums.size() && v[1] < sums.size() && v[2] < sums.size(),
                       "penumbra::scene::computeSmoothNormals: mesh '", mesh.name, "' triangle ",
                       t / 3, " indexes past its ", sums.size(), " vertices");
        const glm::dvec3 p[3] = {glm::dvec3(mesh.positions[v[0]]), glm::dvec3(mesh.positions[v[1]]),
                                 glm::dvec3(mesh.positions[v[2]])};
        const glm::dvec3 face = glm::cross(p[1] - p[0], p[2] - p[0]);
        const double face_length = glm::length(face);
        if (!(face_length > 0.0) || !std::isfinite(face_length)) continue;
        const glm::dvec3 unit_face = face / face_length;
        for (int k = 0; k < 3; ++k) {
            const glm::dvec3 e0 = p[(k + 1) % 3] - p[k];
            const glm::dvec3 e1 = p[(k + 2) % 3] - p[k];
            // atan2 of |cross| and dot stays accurate for the tiny and near-180-degree corner
            // angles that slivers have, where acos of a normalised dot would not.
            const double angle = std::atan2(glm::length(glm::cross(e0, e1)), glm::dot(e0, e1));
            sums[v[k]] += unit_face * angle;
        }
    }
    mesh.normals.resize(mesh.positions.size());
    for (size_t i = 0; i < sums.size(); ++i) {
        const double length = glm::length(sums[i]);
        mesh.normals[i] = length > 1e-30 && std::isfinite(length)
                              ? glm::vec3(sums[i] / length)
                              : glm::vec3(0.0f, 1.0f, 0.0f);
    }
}

inline bool isClosed(const Mesh& mesh) {
    if (mesh.indices.empty() || mesh.indices.size() % 3 != 0) return false;
    std::vector<uint64_t> edges;
    edges.reserve(mesh.indices.size());
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
        for (size_t k = 0; k < 3; ++k) {
            const uint64_t a = mesh.indices[t + k];
            const uint64_t b = mesh.indices[t + (k + 1) % 3];
            if (a == b) return false;
            edges.push_back((a << 32) | b);
        }
    }
    std::sort(edges.begin(), edges.end());
    if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;
    for (uint64_t edge : edges) {
        const uint64_t twin = (edge << 32) | (edge >> 32);
        if (!std::binary_search(edges.begin(), edges.end(), twin)) return false;
    }
    return true;
}

inline double signedVolume(const Mesh& mesh) {
    double volume = 0.0;
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const glm::dvec3 a(mesh.positions.at(mesh.indices[t]));
        const glm::dvec3 b(mesh.positions.at(mesh.indices[t + 1]));
        const glm::dvec3 c(mesh.positions.at(mesh.indices[t + 2]));
        volume += glm::dot(a, glm::cross(b, c));
    }
    return volume / 6.0;
}

inline void validateMesh(const Mesh& mesh) {
    const char* const where = "penumbra::scene::validateMesh: mesh '";
    PENUMBRA_CHECK(mesh.normals.size() == mesh.positions.size(), where, mesh.name, "' has ",
                   mesh.positions.size(), " positions but ", mesh.normals.size(), " normals");
    PENUMBRA_CHECK(mesh.positions.size() <= detail::kMaxSceneVertices, where, mesh.name,
                   "' has more vertices than 32-bit indices can address");
    PENUMBRA_CHECK(mesh.indices.size() % 3 == 0, where, mesh.name, "' has ", mesh.indices.size(),
                   " indices, not a multiple of 3");
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        const glm::vec3& p = mesh.positions[i];
        PENUMBRA_CHECK(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z), where,
                       mesh.name, "' vertex ", i, " has a non-finite position");
        const float length = glm::length(mesh.normals[i]);
        PENUMBRA_CHECK(std::abs(length - 1.0f) <= 1e-3f, where, mesh.name, "' vertex ", i,
                       " has a normal of length ", length);
    }
    for (size_t t = 0; t < mesh.indices.size(); t += 3) {
        const uint32_t a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        PENUMBRA_CHECK(a < mesh.positions.size() && b < mesh.positions.size() &&
                           c < mesh.positions.size(),
                       where, mesh.name, "' triangle ", t / 3, " indexes past its ",
                       mesh.positions.size(), " vertices");
        PENUMBRA_CHECK(a != b && b != c && c != a, where, mesh.name, "' triangle ", t / 3,
                       " repeats a vertex (", a, ", ", b, ", ", c, ")");
    }
}

inline Mesh groundPlane(float half_size, float y, uint32_t subdivisions) {
    PENUMBRA_CHECK(std::isfinite(half_size) && half_size > 0.0f,
                   "penumbra::scene::groundPlane: half_size must be > 0, got ", half_size);
    PENUMBRA_CHECK(std::isfinite(y), "penumbra::scene::groundPlane: y must be finite, got ", y);
    PENUMBRA_CHECK(subdivisions >= 1 && subdivisions <= 65534u,
                   "penumbra::scene::groundPlane: subdivisions must be in [1, 65534], got ",
                   subdivisions);
    Mesh mesh;
    mesh.name = "ground";
    const uint32_t row = subdivisions + 1;
    mesh.positions.reserve(size_t(row) * row);
    for (uint32_t iz = 0; iz < row; ++iz) {
        for (uint32_t ix = 0; ix < row; ++ix) {
            // Exact endpoints: the last row/column is +half_size, not an accumulated sum.
            const float x = -half_size + 2.0f * half_size * static_cast<float>(ix) / static_cast<float>(subdivisions);
            const float z = -half_size + 2.0f * half_size * static_cast<float>(iz) / static_cast<float>(subdivisions);
            mesh.positions.emplace_back(x, y, z);
        }
    }
    mesh.normals.assign(mesh.positions.size(), glm::vec3(0.0f, 1.0f, 0.0f));
    mesh.indices.reserve(size_t(subdivisions) * subdivisions * 6);
    for (uint32_t iz = 0; iz < subdivisions; ++iz) {
        for (uint32_t ix = 0; ix < subdivisions; ++ix) {
            const uint32_t a = iz * row + ix;  // (x, z)
            const uint32_t b = a + row;        // (x, z + dz)
            const uint32_t c = a + 1;          // (x + dx, z)
            const uint32_t d = b + 1;          // (x + dx, z + dz)
            // (b - a) x (c - a) = +z x +x = +y: counter-clockwise seen from above.
            mesh.indices.insert(mesh.indices.end(), {a, b, c, c, b, d});
        }
    }
    mesh.closed = false;
    return mesh;
}

inline Scene sceneFromMesh(Mesh object, float ground_y, bool ground) {
    PENUMBRA_CHECK(std::isfinite(ground_y), "penumbra::scene::sceneFromMesh: ground_y must be finite, got ",
                   ground_y);
    Bounds box = object.bounds();
    if (box.empty()) box = Bounds{{-0.5f, ground_y, -0.5f}, {0.5f, ground_y + 1.0f, 0.5f}};
    const glm::vec3 size = box.size();
    const float radius = 0.5f * glm::length(size);
    PENUMBRA_CHECK(std::isfinite(radius) && std::isfinite(box.min.x + box.min.y + box.min.z),
                   "penumbra::scene::sceneFromMesh: mesh '", object.name, "' has non-finite bounds");
    PENUMBRA_CHECK(radius > 0.0f, "penumbra::scene::sceneFromMesh: mesh '", object.name,
                   "' has zero extent");
    const glm::vec3 centre = box.center();

    Scene scene;
    scene.name = object.name;

    // Light: up and to the left-front, ~3.5 bounding radii away (about 3 units for the unit
    // box), radius 5% of that distance: a visible but not washed-out penumbra.
    const glm::vec3 light_direction = glm::normalize(glm::vec3(-0.6f, 1.0f, 0.45f));
    const float light_distance = 3.5f * radius;
    scene.light.position = centre + light_direction * light_distance;
    scene.light.radius = 0.05f * light_distance;

    // What the camera must see: the object's box corners plus their shadows, projected from
    // the light centre onto the ground plane and widened by the penumbra (light radius times
    // the occluder-to-receiver / light-to-occluder distance ratio).
    std::vector<glm::vec3> must_see;
    Bounds view_region;
    const glm::vec3 light = scene.light.position;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 p((corner & 1) ? box.max.x : box.min.x, (corner & 2) ? box.max.y : box.min.y,
                          (corner & 4) ? box.max.z : box.min.z);
        must_see.push_back(p);
        if (p.y >= light.y || light.y <= ground_y) continue;
        const float t = (light.y - ground_y) / (light.y - p.y);
        const glm::vec3 shadow = light + (p - light) * t;
        const float penumbra = scene.light.radius * (t - 1.0f);
        for (float dx : {-penumbra, penumbra})
            for (float dz : {-penumbra, penumbra}) must_see.push_back(shadow + glm::vec3(dx, 0.0f, dz));
    }
    for (const glm::vec3& p : must_see) view_region.extend(p);

    Camera& camera = scene.camera;
    camera.up = glm::vec3(0.0f, 1.0f, 0.0f);
    camera.fov_y_degrees = 45.0f;
    // Looking from the front (+z) and ~29 degrees down, away from the light's side so the shadow
    // is not hidden behind the object. The distance is the smallest that keeps every point
    // inside a square (aspect 1) view, plus 8%: wider aspects only add room. Perspective puts the
    // box centre off the image centre, so a few passes slide the target to centre the points.
    const glm::vec3 back = glm::normalize(glm::vec3(0.0f, 0.55f, 1.0f));  // target -> eye
    const glm::vec3 right = glm::normalize(glm::cross(camera.up, back));
    const glm::vec3 view_up = glm::cross(back, right);
    const float tan_half_fov = std::tan(glm::radians(0.5f * camera.fov_y_degrees));
    auto fitDistance = [&](const glm::vec3& target) {
        float fit = 0.0f;
        for (const glm::vec3& p : must_see) {
            const glm::vec3 offset = p - target;
            const float nearer = glm::dot(offset, back);  // how much closer to the eye than target
            const float needed = std::max(std::abs(glm::dot(offset, right)),
                                          std::abs(glm::dot(offset, view_up))) / tan_half_fov + nearer;
            fit = std::max(fit, needed);
        }
        return fit;
    };
    camera.target = view_region.center();
    for (int pass = 0; pass < 4; ++pass) {
        const float fit = fitDistance(camera.target);
        glm::vec2 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
        for (const glm::vec3& p : must_see) {
            const glm::vec3 offset = p - camera.target;
            const float depth = std::max(fit - glm::dot(offset, back), 1e-6f * fit);
            const glm::vec2 slope(glm::dot(offset, right) / depth, glm::dot(offset, view_up) / depth);
            lo = glm::min(lo, slope);
            hi = glm::max(hi, slope);
        }
        const glm::vec2 middle = 0.5f * (lo + hi);
        camera.target += (right * middle.x + view_up * middle.y) * fit;
    }
    const float distance = 1.08f * fitDistance(camera.target);
    camera.eye = camera.target + back * distance;

    // Ground: centred under the object, wide enough that the whole shadow lies on it.
    float reach = radius;
    for (const glm::vec3& p : {view_region.min, view_region.max})
        reach = std::max(reach, std::max(std::abs(p.x - centre.x), std::abs(p.z - centre.z)));
    const float ground_half_size = 2.5f * reach;

    camera.z_near = 0.01f * distance;
    camera.z_far = 1.1f * (distance + glm::length(camera.target - centre) + 1.5f * ground_half_size +
                           std::abs(camera.eye.y - ground_y));

    if (ground) {
        Mesh plane = groundPlane(ground_half_size, ground_y, 1);
        for (glm::vec3& p : plane.positions) p += glm::vec3(centre.x, 0.0f, centre.z);
        scene.meshes.push_back(std::move(plane));
    }
    scene.meshes.push_back(std::move(object));
    return scene;
}

inline Scene torusKnot(uint32_t tessellation, bool ground) {
    PENUMBRA_CHECK(tessellation >= 3, "penumbra::scene::torusKnot: tessellation must be >= 3, got ",
                   tessellation);
    const uint64_t segments = 4ull * tessellation;
    const uint64_t sides = std::max<uint64_t>(3, tessellation / 4);
    detail::checkVertexBudget("torusKnot", segments * sides);
    // Curve C(t) = ((2 + cos 3t) cos 2t, (2 + cos 3t) sin 2t, -sin 3t): strands stay >= 1.66
    // apart and the radius of curvature >= 1.43, so a 0.5 tube neither touches itself nor folds.
    constexpr double kTubeRadius = 0.5;

    Mesh mesh;
    mesh.name = "torus_knot";
    mesh.positions.reserve(static_cast<size_t>(segments * sides));
    mesh.normals.reserve(static_cast<size_t>(segments * sides));
    for (uint64_t i = 0; i < segments; ++i) {
        const double t = 2.0 * detail::kPi * static_cast<double>(i) / static_cast<double>(segments);
        const double r = 2.0 + std::cos(3 * t);
        const double dr = -3.0 * std::sin(3 * t);
        const glm::dvec3 curve(r * std::cos(2 * t), r * std::sin(2 * t), -std::sin(3 * t));
        const glm::dvec3 tangent = glm::normalize(
            glm::dvec3(dr * std::cos(2 * t) - 2 * r * std::sin(2 * t),
                       dr * std::sin(2 * t) + 2 * r * std::cos(2 * t), -3 * std::cos(3 * t)));
        // Frame from the tangent and the position (which is never parallel to it): periodic in
        // t by construction, so the tube closes without the twist seam Frenet or parallel
        // transport frames would need to fix.
        const glm::dvec3 binormal = glm::normalize(glm::cross(tangent, curve));
        const glm::dvec3 normal = glm::cross(binormal, tangent);
        for (uint64_t j = 0; j < sides; ++j) {
            const double phi = 2.0 * detail::kPi * static_cast<double>(j) / static_cast<double>(sides);
            const glm::dvec3 n = std::cos(phi) * normal + std::sin(phi) * binormal;
            mesh.positions.emplace_back(curve + kTubeRadius * n);
            mesh.normals.emplace_back(n);
        }
    }
    mesh.indices.reserve(static_cast<size_t>(segments * sides * 6));
    auto at = [&](uint64_t i, uint64_t j) {
        return static_cast<uint32_t>((i % segments) * sides + (j % sides));
    };
    for (uint64_t i = 0; i < segments; ++i) {
        for (uint64_t j = 0; j < sides; ++j) {
            const uint32_t a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
            // Along the knot x around the tube = outward, so a-c-b and a-d-c face out.
            mesh.indices.insert(mesh.indices.end(), {a, c, b, a, d, c});
        }
    }
    for (glm::vec3& n : mesh.normals) n = glm::normalize(n);
    detail::fitUnitBoxOnGround(mesh);
    mesh.closed = true;
    return sceneFromMesh(std::move(mesh), 0.0f, ground);
}

namespace detail {
/// Appends columns(count)'s pieces (without normals) to mesh.
inline void appendColumns(Mesh& mesh, uint32_t count) {
    if (count > 0) {
        const uint32_t grid_columns =
            std::max(1u, static_cast<uint32_t>(std::ceil(std::sqrt(static_cast<double>(count)))));
        const uint32_t grid_rows = (count + grid_columns - 1) / grid_columns;
        const float spacing = 1.0f / static_cast<float>(std::max(grid_columns, grid_rows));
        const float half_width = 0.28f * spacing;
        constexpr float kHeight = 0.85f;
        auto cellCentre = [&](uint32_t row, uint32_t column) {
            return glm::vec3((static_cast<float>(column) - 0.5f * static_cast<float>(grid_columns - 1)) * spacing,
                             0.0f,
                             (static_cast<float>(row) - 0.5f * static_cast<float>(grid_rows - 1)) * spacing);
        };
        for (uint32_t k = 0; k < count; ++k) {
            const uint32_t row = k / grid_columns, column = k % grid_columns;
            const auto shape = (row + column) % 2 == 0 ? detail::PrismSection::roundedBox
                                                       : detail::PrismSection::cylinder;
            detail::appendRoundedPrism(mesh, cellCentre(row, column), half_width, half_width,
                                       kHeight, shape);
        }
        const uint32_t back_row_columns = std::min(count, grid_columns);
        if (back_row_columns >= 2) {
            const glm::vec3 first = cellCentre(0, 0), last = cellCentre(0, back_row_columns - 1);
            const float overhang = 1.15f * half_width;
            // Sink the lintel below the columns' top bevel so no sliver of light leaks through
            // at the joints; the pieces interpenetrate but each stays closed on its own.
            const float column_bevel = 0.08f * half_width;
            const float bottom = kHeight - 2.5f * column_bevel;
            const float thickness = 0.35f * spacing;
            detail::appendRoundedPrism(mesh, glm::vec3(0.5f * (first.x + last.x), bottom, first.z),
                                       0.5f * (last.x - first.x) + overhang, overhang, thickness,
                                       detail::PrismSection::roundedBox);
        }
    }
}
}  // namespace detail

inline Scene columns(uint32_t count, bool ground) {
    Mesh mesh;
    mesh.name = "columns";
    detail::appendColumns(mesh, count);
    if (count > 0) {
        computeSmoothNormals(mesh);
        mesh.closed = true;
    }
    return sceneFromMesh(std::move(mesh), 0.0f, ground);
}

inline Scene windowWall(bool ground) {
    Mesh mesh;
    mesh.name = "window_wall";
    detail::appendColumns(mesh, 9);
    constexpr float kX = -0.72f, kHalfThickness = 0.03f, kHalfLength = 0.6f, kHeight = 1.3f;
    constexpr float kSill = 0.45f, kHead = 1.05f, kWindow = 0.22f, kSink = 0.05f;
    constexpr int kWindows = 3;
    constexpr float kPier = (2.0f * kHalfLength - kWindows * kWindow) / (kWindows + 1);
    const auto box = [&](float y0, float y1, float z0, float z1) {
        detail::appendRoundedPrism(mesh, glm::vec3(kX, y0, 0.5f * (z0 + z1)), kHalfThickness, 0.5f * (z1 - z0), y1 - y0,
                                   detail::PrismSection::roundedBox);
    };
    box(0.0f, kSill, -kHalfLength, kHalfLength);     // sill band
    box(kHead, kHeight, -kHalfLength, kHalfLength);  // head band
    for (int p = 0; p <= kWindows; ++p) {            // piers, sunk into both bands
        const float z0 = -kHalfLength + float(p) * (kPier + kWindow);
        box(kSill - kSink, kHead + kSink, z0, z0 + kPier);
    }
    computeSmoothNormals(mesh);
    mesh.closed = true;
    return sceneFromMesh(std::move(mesh), 0.0f, ground);
}

inline Scene hairball(uint32_t triangles, uint32_t seed, bool ground) {
    detail::checkVertexBudget("hairball", 3ull * triangles);
    constexpr float kBallRadius = 0.45f;
    const glm::vec3 ball_centre(0.0f, 0.55f, 0.0f);
    detail::Pcg32 rng(seed, detail::kHairballStream);
    Mesh mesh;
    mesh.name = "hairball";
    mesh.positions.reserve(size_t(3) * triangles);
    mesh.normals.reserve(size_t(3) * triangles);
    mesh.indices.reserve(size_t(3) * triangles);
    for (uint32_t i = 0; i < triangles; ++i) {
        const float length = rng.uniform(0.08f, 0.25f);
        const float width = rng.uniform(0.002f, 0.008f);
        // The root stays length + width from the surface, so the whole strand is in the ball.
        const glm::vec3 root = ball_centre + rng.inUnitBall() * (kBallRadius - length - width);
        const glm::vec3 direction = rng.unitVector();
        const glm::vec3 helper = std::abs(direction.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        const glm::vec3 side0 = glm::normalize(glm::cross(direction, helper));
        const glm::vec3 side1 = glm::cross(direction, side0);
        const float spin = rng.uniform(0.0f, 2.0f * static_cast<float>(detail::kPi));
        const glm::vec3 across = std::cos(spin) * side0 + std::sin(spin) * side1;
        const glm::vec3 a = root - 0.5f * width * across;
        const glm::vec3 b = root + 0.5f * width * across;
        const glm::vec3 c = root + length * direction;
        const glm::vec3 face = glm::cross(b - a, c - a);
        const float face_length = glm::length(face);
        const glm::vec3 normal =
            face_length > 0.0f ? face / face_length : glm::normalize(glm::cross(across, direction));
        const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), {a, b, c});
        mesh.normals.insert(mesh.normals.end(), {normal, normal, normal});
        mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
    }
    mesh.closed = false;
    return sceneFromMesh(std::move(mesh), 0.0f, ground);
}

inline Scene grass(uint32_t blades, uint32_t seed, bool ground) {
    constexpr uint32_t kLevels = 4;  // vertex pairs per blade below the tip
    constexpr uint32_t kVerticesPerBlade = 2 * kLevels + 1;
    detail::checkVertexBudget("grass", uint64_t(kVerticesPerBlade) * blades);
    detail::Pcg32 rng(seed, detail::kGrassStream);
    Mesh mesh;
    mesh.name = "grass";
    mesh.positions.reserve(size_t(kVerticesPerBlade) * blades);
    mesh.normals.reserve(size_t(kVerticesPerBlade) * blades);
    mesh.indices.reserve(size_t(3) * (2 * kLevels - 1) * blades);
    const float two_pi = 2.0f * static_cast<float>(detail::kPi);
    for (uint32_t i = 0; i < blades; ++i) {
        // Uniform over the ring's area: radius = sqrt of a uniform in [r0^2, r1^2].
        const float ring_radius = std::sqrt(rng.uniform(0.2f * 0.2f, 0.5f * 0.5f));
        const float ring_angle = rng.uniform(0.0f, two_pi);
        const glm::vec3 root(ring_radius * std::cos(ring_angle), 0.0f, ring_radius * std::sin(ring_angle));
        const float height = rng.uniform(0.3f, 0.8f);
        const float width = rng.uniform(0.012f, 0.025f);
        const float facing = rng.uniform(0.0f, two_pi);
        const float bend = rng.uniform(0.1f, 0.6f) * (rng.uniform() < 0.5f ? -1.0f : 1.0f);
        const glm::vec3 across(std::cos(facing), 0.0f, std::sin(facing));
        const glm::vec3 lean(-std::sin(facing), 0.0f, std::cos(facing));
        // Centreline P(s) = root + height * (s up + bend s^2 lean): a parabola bending away
        // from the blade's flat side, as real blades do.
        auto centre = [&](float s) {
            return root + height * (glm::vec3(0.0f, s, 0.0f) + bend * s * s * lean);
        };
        auto normalAt = [&](float s) {
            const glm::vec3 tangent = glm::vec3(0.0f, 1.0f, 0.0f) + 2.0f * bend * s * lean;
            return glm::normalize(glm::cross(across, tangent));
        };
        const uint32_t base = static_cast<uint32_t>(mesh.positions.size());
        for (uint32_t level = 0; level < kLevels; ++level) {
            const float s = static_cast<float>(level) / kLevels;
            const float half = 0.5f * width * (1.0f - s);
            const glm::vec3 n = normalAt(s);
            mesh.positions.insert(mesh.positions.end(), {centre(s) - half * across, centre(s) + half * across});
            mesh.normals.insert(mesh.normals.end(), {n, n});
        }
        mesh.positions.push_back(centre(1.0f));
        mesh.normals.push_back(normalAt(1.0f));
        for (uint32_t level = 0; level + 1 < kLevels; ++level) {
            const uint32_t left = base + 2 * level, right = left + 1;
            const uint32_t next_left = left + 2, next_right = left + 3;
            // Counter-clockwise seen from the side the normal (across x tangent) points to.
            mesh.indices.insert(mesh.indices.end(),
                                {left, right, next_right, left, next_right, next_left});
        }
        const uint32_t last_left = base + 2 * (kLevels - 1);
        mesh.indices.insert(mesh.indices.end(), {last_left, last_left + 1, base + 2 * kLevels});
    }
    mesh.closed = false;
    return sceneFromMesh(std::move(mesh), 0.0f, ground);
}

inline std::vector<std::string> builtinNames() { return {"torus_knot", "columns", "hairball", "grass"}; }
inline std::vector<std::string> extraBuiltinNames() { return {"window_wall"}; }

inline Scene builtin(const std::string& name) {
    if (name == "torus_knot") return torusKnot();
    if (name == "columns") return columns();
    if (name == "hairball") return hairball();
    if (name == "grass") return grass();
    if (name == "window_wall") return windowWall();
    std::string valid;
    for (const std::string& known : builtinNames()) valid += (valid.empty() ? "" : ", ") + known;
    for (const std::string& known : extraBuiltinNames()) valid += ", " + known;
    ::penumbra::detail::fail("penumbra::scene::builtin: unknown scene '", name, "'; valid names: ", valid);
}

}  // namespace penumbra::scene

#endif
