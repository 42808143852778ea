// Tests for penumbra/scene: procedural scenes, OBJ loading and PNG writing.
//
// Link: tinyobjloader (-ltinyobjloader) and stb (-lstb). Optional compile definition
// PENUMBRA_SHARED_SCENES_DIR="<repo>/../shared/scenes" enables the real-mesh test; without it,
// or when the folder is missing, that test skips with a message.
#include <penumbra/scene/image.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace penumbra::scene;

// --- independent checkers (deliberately not the library's own helpers) ---------------------

/// Every directed edge occurs exactly once and its opposite twin exactly once.
bool everyEdgeHasOneOppositeTwin(const Mesh& mesh) {
    std::map<std::pair<uint32_t, uint32_t>, int> directed;
    for (size_t t = 0; t < mesh.indices.size(); t += 3)
        for (size_t k = 0; k < 3; ++k) ++directed[{mesh.indices[t + k], mesh.indices[t + (k + 1) % 3]}];
    if (directed.empty()) return false;
    for (const auto& [edge, count] : directed) {
        if (count != 1) return false;
        const auto twin = directed.find({edge.second, edge.first});
        if (twin == directed.end() || twin->second != 1) return false;
    }
    return true;
}

glm::dvec3 faceNormal(const Mesh& mesh, size_t t) {
    const glm::dvec3 a(mesh.positions[mesh.indices[3 * t]]), b(mesh.positions[mesh.indices[3 * t + 1]]),
        c(mesh.positions[mesh.indices[3 * t + 2]]);
    return glm::cross(b - a, c - a);
}

/// Sizes, index range, finite positions, unit normals, no repeated index, no zero-area triangle
/// (computed in float, as a GPU would see it), and, for generated meshes, vertex normals on the
/// front side of every face (real meshes with sharp folds can legitimately violate that).
void checkWellFormed(const Mesh& mesh, double min_area, bool normals_face_front = true) {
    INFO("mesh " << mesh.name);
    REQUIRE(mesh.normals.size() == mesh.positions.size());
    REQUIRE(mesh.indices.size() % 3 == 0);
    REQUIRE(mesh.triangleCount() == mesh.indices.size() / 3);
    for (uint32_t index : mesh.indices) REQUIRE(index < mesh.positions.size());
    for (size_t v = 0; v < mesh.positions.size(); ++v) {
        const glm::vec3 p = mesh.positions[v];
        REQUIRE((std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)));
        REQUIRE(std::abs(glm::length(mesh.normals[v]) - 1.0f) < 1e-4f);
    }
    size_t facing_away = 0;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
        REQUIRE((a != b && b != c && c != a));
        const glm::vec3 fa = mesh.positions[a], fb = mesh.positions[b], fc = mesh.positions[c];
        const float float_area = 0.5f * glm::length(glm::cross(fb - fa, fc - fa));
        if (!(float_area > min_area)) {
            INFO("triangle " << t << " area " << float_area);
            REQUIRE(float_area > min_area);
        }
        const glm::dvec3 n = faceNormal(mesh, t);
        for (uint32_t v : {a, b, c})
            if (glm::dot(n, glm::dvec3(mesh.normals[v])) <= 0.0) ++facing_away;
    }
    if (normals_face_front) CHECK(facing_away == 0);
    CHECK_NOTHROW(validateMesh(mesh));
}

void checkUnitBoxOnGround(const Mesh& mesh) {
    const Bounds box = mesh.bounds();
    REQUIRE_FALSE(box.empty());
    const glm::vec3 size = box.size();
    CHECK(std::max(size.x, std::max(size.y, size.z)) == doctest::Approx(1.0f).epsilon(1e-5));
    CHECK(box.min.y == doctest::Approx(0.0f).epsilon(1e-6));
    CHECK(std::abs(box.center().x) < 1e-5f);
    CHECK(std::abs(box.center().z) < 1e-5f);
}

const Mesh& objectOf(const Scene& scene) { return scene.meshes.back(); }
// From a temporary scene: by value, so `const Mesh m = objectOf(loadObj(...))` cannot dangle.
Mesh objectOf(Scene&& scene) { return std::move(scene.meshes.back()); }

bool sameMesh(const Mesh& a, const Mesh& b) {
    return a.positions == b.positions && a.normals == b.normals && a.indices == b.indices && a.closed == b.closed;
}

/// The object's box corners and their shadow (projected from the light centre onto y = ground)
/// must all be inside the default camera's view volume.
void checkFraming(const Scene& scene, float ground_y) {
    INFO("scene " << scene.name);
    const Mesh& object = objectOf(scene);
    Bounds box = object.bounds();
    if (box.empty()) box = Bounds{{-0.5f, ground_y, -0.5f}, {0.5f, ground_y + 1.0f, 0.5f}};
    const Light& light = scene.light;
    CHECK(light.radius > 0.0f);
    const float light_distance = glm::length(light.position - box.center());
    CHECK(light.radius <= 0.1f * light_distance);
    CHECK(light.position.y - light.radius > box.max.y);  // the whole sphere is above the object

    std::vector<glm::vec3> must_see;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::vec3 p((corner & 1) ? box.max.x : box.min.x, (corner & 2) ? box.max.y : box.min.y,
                          (corner & 4) ? box.max.z : box.min.z);
        must_see.push_back(p);
        const float t = (light.position.y - ground_y) / (light.position.y - p.y);
        must_see.push_back(light.position + (p - light.position) * t);
    }
    // The shadow is cast to the side, not straight down: its footprint leaves the object's.
    const glm::vec3 top_shadow = must_see[2 * 7 + 1];
    CHECK(glm::length(glm::vec2(top_shadow.x - box.center().x, top_shadow.z - box.center().z)) >
          0.5f * glm::length(glm::vec2(box.size().x, box.size().z)));

    const Camera& camera = scene.camera;
    CHECK(camera.z_near > 0.0f);
    CHECK(camera.eye.y > ground_y);
    for (float aspect : {1.0f, 4.0f / 3.0f, 16.0f / 9.0f}) {
        const glm::mat4 clip_from_world = camera.projection(aspect) * camera.view();
        for (const glm::vec3& p : must_see) {
            const glm::vec4 clip = clip_from_world * glm::vec4(p, 1.0f);
            INFO("point " << p.x << ", " << p.y << ", " << p.z << " aspect " << aspect);
            REQUIRE(clip.w > 0.0f);
            CHECK(std::abs(clip.x / clip.w) <= 1.0f);
            CHECK(std::abs(clip.y / clip.w) <= 1.0f);
            CHECK(std::abs(clip.z / clip.w) <= 1.0f);
        }
    }
    if (scene.meshes.size() == 2) {
        const Mesh& ground = scene.meshes.front();
        CHECK(ground.name == "ground");
        const Bounds plane = ground.bounds();
        CHECK(plane.min.y == ground_y);
        CHECK(plane.max.y == ground_y);
        for (const glm::vec3& p : must_see) {
            CHECK(p.x >= plane.min.x);
            CHECK(p.x <= plane.max.x);
            CHECK(p.z >= plane.min.z);
            CHECK(p.z <= plane.max.z);
        }
    }
}

uint32_t freshSeed() {
    static const uint32_t seed = std::random_device{}();
    return seed;
}

/// A unique folder under the system temp dir, removed with everything in it at scope exit.
struct TempDir {
    fs::path path;
    TempDir() {
        std::mt19937_64 bits(std::random_device{}());
        path = fs::temp_directory_path() / ("penumbra_scene_test_" + std::to_string(bits()));
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ignored;
        fs::remove_all(path, ignored);
    }
    std::string write(const std::string& name, const std::string& text) const {
        const fs::path file = path / name;
        std::ofstream(file, std::ios::binary) << text;
        return file.string();
    }
};

std::string errorMessage(const std::function<void()>& action) {
    try {
        action();
    } catch (const penumbra::Error& error) {
        return error.what();
    }
    return "<no penumbra::Error thrown>";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Unit cube from quads with one normal per face: corners then name 3 different normals, so the
// loader must discard them and compute smooth normals.
const char* const kQuadCubeObj = R"(# unit cube, quads, per-face normals
o cube
v -1 -1 -1
v  1 -1 -1
v  1  1 -1
v -1  1 -1
v -1 -1  1
v  1 -1  1
v  1  1  1
v -1  1  1
vn 0 0 -1
vn 0 0 1
vn 0 -1 0
vn 0 1 0
vn -1 0 0
vn 1 0 0
f 1//1 4//1 3//1 2//1
f 5//2 6//2 7//2 8//2
f 1//3 2//3 6//3 5//3
f 4//4 8//4 7//4 3//4
f 1//5 5//5 8//5 4//5
f 2//6 3//6 7//6 6//6
)";

std::string cubeObjWithFaces(bool inward, double scale, double offset) {
    static const int faces[6][4] = {{1, 4, 3, 2}, {5, 6, 7, 8}, {1, 2, 6, 5}, {4, 8, 7, 3}, {1, 5, 8, 4}, {2, 3, 7, 6}};
    std::ostringstream obj;
    const int corners[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                               {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
    for (const auto& c : corners)
        obj << "v " << offset + scale * c[0] << ' ' << offset + scale * c[1] << ' ' << offset + scale * c[2] << '\n';
    for (const auto& f : faces) {
        obj << 'f';
        if (inward)
            for (int k = 3; k >= 0; --k) obj << ' ' << f[k];
        else
            for (int k = 0; k < 4; ++k) obj << ' ' << f[k];
        obj << '\n';
    }
    return obj.str();
}

/// Prism over a polygon (counter-clockwise seen from +y) given as (x, z) points, with n-gon caps.
std::string prismObj(const std::vector<glm::vec2>& polygon, float height) {
    std::ostringstream obj;
    const size_t n = polygon.size();
    for (float y : {0.0f, height})
        for (const glm::vec2& p : polygon) obj << "v " << p.x << ' ' << y << ' ' << p.y << '\n';
    obj << 'f';  // bottom faces down: reverse order
    for (size_t k = n; k-- > 0;) obj << ' ' << k + 1;
    obj << "\nf";
    for (size_t k = 0; k < n; ++k) obj << ' ' << n + k + 1;
    obj << '\n';
    for (size_t k = 0; k < n; ++k) {
        const size_t a = k + 1, b = (k + 1) % n + 1;
        obj << "f " << a << ' ' << b << ' ' << b + n << ' ' << a + n << '\n';
    }
    return obj.str();
}

/// A generated closed solid: flagged closed, every directed edge with one opposite twin, closed by
/// the library's own test, outward (positive volume) and well formed.
void checkClosedSolid(const Mesh& mesh, double min_area) {
    CHECK(mesh.closed);
    CHECK(everyEdgeHasOneOppositeTwin(mesh));
    CHECK(isClosed(mesh));
    CHECK(signedVolume(mesh) > 0.0);
    checkWellFormed(mesh, min_area);
}

}  // namespace

// =============================================================================================

TEST_CASE("scene: PCG32 matches the reference sequence") {
    // pcg32-demo: pcg32_srandom_r(&rng, 42u, 54u) then pcg32_random_r.
    penumbra::scene::detail::Pcg32 rng(42u, 54u);
    const uint32_t expected[] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    for (uint32_t value : expected) CHECK(rng.next() == value);
    for (int i = 0; i < 1000; ++i) {
        const float u = rng.uniform();
        REQUIRE(u >= 0.0f);
        REQUIRE(u < 1.0f);
    }
}

TEST_CASE("scene: builtin names and lookup") {
    CHECK(builtinNames() == std::vector<std::string>{"torus_knot", "columns", "hairball", "grass"});
    CHECK(extraBuiltinNames() == std::vector<std::string>{"window_wall"});
    std::vector<std::string> every = builtinNames();
    const std::vector<std::string> extras = extraBuiltinNames();
    every.insert(every.end(), extras.begin(), extras.end());
    for (const std::string& name : every) {
        const Scene scene = builtin(name);
        CHECK(scene.name == name);
        REQUIRE(scene.meshes.size() == 2);
        CHECK(scene.meshes[0].name == "ground");
        CHECK(scene.meshes[1].name == name);
        CHECK(scene.triangleCount() == scene.meshes[0].triangleCount() + scene.meshes[1].triangleCount());
        CHECK(sameMesh(load("builtin:" + name).meshes[1], scene.meshes[1]));
        MESSAGE(name << ": " << scene.meshes[1].triangleCount() << " object triangles, "
                     << scene.meshes[1].positions.size() << " vertices, closed = " << scene.meshes[1].closed);
    }
    const std::string message = errorMessage([] { builtin("teapot"); });
    CHECK(contains(message, "'teapot'"));
    for (const std::string& name : every) CHECK(contains(message, name));
    CHECK(contains(errorMessage([] { load("builtin:nope"); }), "'nope'"));
    CHECK(contains(errorMessage([] { load("builtin:"); }), "valid names"));
}

TEST_CASE("scene: ground plane") {
    for (uint32_t subdivisions : {1u, 2u, 3u, 16u}) {
        const Mesh ground = groundPlane(2.5f, -0.25f, subdivisions);
        CHECK(ground.name == "ground");
        CHECK_FALSE(ground.closed);
        CHECK(ground.positions.size() == size_t(subdivisions + 1) * (subdivisions + 1));
        CHECK(ground.triangleCount() == size_t(2) * subdivisions * subdivisions);
        checkWellFormed(ground, 1e-6);
        for (size_t t = 0; t < ground.triangleCount(); ++t) {
            const glm::dvec3 n = faceNormal(ground, t);  // counter-clockwise seen from above
            REQUIRE(n.y > 0.0);
        }
        const Bounds box = ground.bounds();
        CHECK(box.min == glm::vec3(-2.5f, -0.25f, -2.5f));
        CHECK(box.max == glm::vec3(2.5f, -0.25f, 2.5f));
        double area = 0;
        for (size_t t = 0; t < ground.triangleCount(); ++t) area += 0.5 * glm::length(faceNormal(ground, t));
        CHECK(area == doctest::Approx(25.0));
        CHECK_FALSE(isClosed(ground));
        CHECK_FALSE(everyEdgeHasOneOppositeTwin(ground));
    }
    CHECK_THROWS_AS(groundPlane(0.0f), penumbra::Error);
    CHECK_THROWS_AS(groundPlane(-1.0f), penumbra::Error);
    CHECK_THROWS_AS(groundPlane(std::nanf("")), penumbra::Error);
    CHECK_THROWS_AS(groundPlane(1.0f, INFINITY), penumbra::Error);
    CHECK(contains(errorMessage([] { groundPlane(1.0f, 0.0f, 0); }), "subdivisions"));
}

TEST_CASE("scene: torus knot is closed, outward, non-degenerate, unit sized") {
    for (uint32_t tessellation : {3u, 4u, 5u, 7u, 8u, 16u, 63u, 64u, 65u, 128u}) {
        INFO("tessellation " << tessellation);
        const Scene scene = torusKnot(tessellation);
        const Mesh& knot = objectOf(scene);
        const size_t segments = 4u * tessellation, sides = std::max(3u, tessellation / 4);
        CHECK(knot.positions.size() == segments * sides);
        CHECK(knot.triangleCount() == 2 * segments * sides);
        checkClosedSolid(knot, 1e-7);
        checkUnitBoxOnGround(knot);
    }
    CHECK(torusKnot().meshes[1].triangleCount() == 8192);
    CHECK(torusKnot(64, false).meshes.size() == 1);
    for (uint32_t bad : {0u, 1u, 2u}) CHECK(contains(errorMessage([bad] { torusKnot(bad); }), "tessellation"));
}

TEST_CASE("scene: columns are closed, outward, non-degenerate, unit sized") {
    for (uint32_t count : {1u, 2u, 3u, 4u, 5u, 9u, 10u, 16u, 17u, 100u}) {
        INFO("count " << count);
        const Scene scene = columns(count);
        const Mesh& object = objectOf(scene);
        checkClosedSolid(object, 1e-9);
        const Bounds box = object.bounds();
        CHECK(box.min.y == 0.0f);
        CHECK(box.max.y <= 1.0f);
        CHECK(box.min.x >= -0.5f);
        CHECK(box.max.x <= 0.5f);
        CHECK(box.min.z >= -0.5f);
        CHECK(box.max.z <= 0.5f);
        // Flat faces keep flat normals: most vertices point along an axis (bevels are thin).
        size_t axis_aligned = 0;
        for (const glm::vec3& n : object.normals)
            axis_aligned += std::max(std::abs(n.x), std::max(std::abs(n.y), std::abs(n.z))) > 0.9999f;
        CHECK(axis_aligned > 0);
    }
    const Scene empty = columns(0);
    REQUIRE(empty.meshes.size() == 2);
    CHECK(objectOf(empty).triangleCount() == 0);
    CHECK_FALSE(objectOf(empty).closed);
    checkFraming(empty, 0.0f);
}

TEST_CASE("scene: window_wall is columns(9) plus a closed wall whose three windows are open") {
    const Scene scene = windowWall();
    CHECK(scene.name == "window_wall");
    const Mesh& object = objectOf(scene);
    checkClosedSolid(object, 1e-9);
    // The columns come first, unchanged.
    const Mesh& pillars = objectOf(columns(9));
    REQUIRE(object.positions.size() > pillars.positions.size());
    CHECK(std::equal(pillars.positions.begin(), pillars.positions.end(), object.positions.begin()));
    CHECK(std::equal(pillars.indices.begin(), pillars.indices.end(), object.indices.begin()));
    // The wall: every vertex past the columns' lies in its slab, none inside a window opening, and
    // the wall spans its full length and height.
    const Bounds box = object.bounds();
    CHECK(box.min.x == doctest::Approx(-0.75f));
    CHECK(box.max.y == doctest::Approx(1.3f));
    CHECK(box.min.z == doctest::Approx(-0.6f));
    CHECK(box.max.z == doctest::Approx(0.6f));
    const float pier = (1.2f - 3 * 0.22f) / 4;
    size_t inside_window = 0;
    for (size_t v = pillars.positions.size(); v < object.positions.size(); ++v) {
        const glm::vec3 p = object.positions[v];
        CHECK(p.x >= -0.7501f);
        CHECK(p.x <= -0.6899f);
        for (int w = 0; w < 3; ++w) {
            const float z0 = -0.6f + pier + float(w) * (pier + 0.22f);
            inside_window += p.z > z0 + 1e-4f && p.z < z0 + 0.22f - 1e-4f && p.y > 0.45f + 1e-4f && p.y < 1.05f - 1e-4f;
        }
    }
    CHECK(inside_window == 0);
    checkFraming(scene, 0.0f);
    CHECK(sameMesh(load("builtin:window_wall").meshes[1], object));
    CHECK(objectOf(windowWall(false)).triangleCount() == object.triangleCount());
    CHECK(windowWall(false).meshes.size() == 1);
}

TEST_CASE("scene: hairball and grass are open, seeded and deterministic") {
    const uint32_t seed = freshSeed();
    MESSAGE("fresh seed " << seed);
    INFO("seed " << seed);
    for (uint32_t count : {0u, 1u, 2u, 255u, 256u, 257u, 1000u}) {
        INFO("count " << count);
        const Scene hair = hairball(count, seed);
        const Mesh& strands = objectOf(hair);
        CHECK(strands.triangleCount() == count);
        CHECK(strands.positions.size() == 3 * size_t(count));
        CHECK_FALSE(strands.closed);
        CHECK_FALSE(isClosed(strands));
        checkWellFormed(strands, 1e-6);
        for (const glm::vec3& p : strands.positions) REQUIRE(glm::length(p - glm::vec3(0, 0.55f, 0)) <= 0.4501f);
        CHECK(sameMesh(strands, objectOf(hairball(count, seed))));

        const Scene field = grass(count, seed);
        const Mesh& blades = objectOf(field);
        CHECK(blades.triangleCount() == 7 * size_t(count));
        CHECK(blades.positions.size() == 9 * size_t(count));
        CHECK_FALSE(blades.closed);
        CHECK_FALSE(isClosed(blades));
        checkWellFormed(blades, 1e-8);
        for (size_t b = 0; b < count; ++b) {
            const glm::vec3 root = 0.5f * (blades.positions[9 * b] + blades.positions[9 * b + 1]);
            REQUIRE(root.y == 0.0f);
            const float radius = glm::length(glm::vec2(root.x, root.z));
            REQUIRE(radius >= 0.2f - 1e-5f);
            REQUIRE(radius <= 0.5f + 1e-5f);
        }
        for (const glm::vec3& p : blades.positions) REQUIRE(p.y >= 0.0f);
        CHECK(sameMesh(blades, objectOf(grass(count, seed))));
        if (count > 0) {
            CHECK_FALSE(sameMesh(strands, objectOf(hairball(count, seed + 1))));
            CHECK_FALSE(sameMesh(blades, objectOf(grass(count, seed + 1))));
        }
    }
    // Prefix stability: asking for more strands/blades only appends.
    const Mesh small = objectOf(hairball(100, seed)), large = objectOf(hairball(300, seed));
    CHECK(std::equal(small.positions.begin(), small.positions.end(), large.positions.begin()));
    const Mesh few = objectOf(grass(50, seed)), many = objectOf(grass(60, seed));
    CHECK(std::equal(few.positions.begin(), few.positions.end(), many.positions.begin()));
    // Default arguments are part of the contract (seed 1).
    CHECK(sameMesh(objectOf(hairball()), objectOf(hairball(20000, 1))));
    CHECK(objectOf(grass()).triangleCount() == 14000);
}

TEST_CASE("scene: default camera and light frame the object and its shadow") {
    for (const std::string& name : builtinNames()) {
        checkFraming(builtin(name), 0.0f);
    }
    checkFraming(windowWall(), 0.0f);
    checkFraming(torusKnot(16, false), 0.0f);
    checkFraming(columns(1), 0.0f);
    checkFraming(hairball(0), 0.0f);
    // A mesh far from the origin and not unit sized.
    Mesh box;
    box.name = "offset_box";
    detail::appendRoundedPrism(box, glm::vec3(40.0f, 3.0f, -25.0f), 6.0f, 2.0f, 10.0f, detail::PrismSection::roundedBox);
    computeSmoothNormals(box);
    box.closed = true;
    const Scene scene = sceneFromMesh(box, 3.0f);
    CHECK(scene.name == "offset_box");
    checkFraming(scene, 3.0f);
    // Camera validation.
    Camera camera = scene.camera;
    CHECK_NOTHROW(camera.view());
    CHECK_THROWS_AS(camera.projection(0.0f), penumbra::Error);
    CHECK_THROWS_AS(camera.projection(std::nanf("")), penumbra::Error);
    camera.z_near = camera.z_far;
    CHECK(contains(errorMessage([&] { camera.projection(1.0f); }), "z_near"));
    camera = scene.camera;
    camera.target = camera.eye;
    CHECK(contains(errorMessage([&] { camera.view(); }), "eye equals target"));
    camera = scene.camera;
    camera.up = camera.target - camera.eye;
    CHECK(contains(errorMessage([&] { camera.view(); }), "parallel"));
    CHECK_THROWS_AS(sceneFromMesh(Mesh{"point", {glm::vec3(1.0f)}, {glm::vec3(0, 1, 0)}, {}, false}), penumbra::Error);
}

TEST_CASE("scene: bounds, triangle count and merged") {
    const Scene scene = columns(4);
    const Mesh all = scene.merged();
    CHECK(all.name == "columns");
    CHECK(all.positions.size() == scene.meshes[0].positions.size() + scene.meshes[1].positions.size());
    CHECK(all.triangleCount() == scene.triangleCount());
    CHECK_FALSE(all.closed);  // the ground is open
    checkWellFormed(all, 1e-9);
    const Bounds box = scene.bounds();
    CHECK(box.min == all.bounds().min);
    CHECK(box.max == all.bounds().max);
    CHECK(box.min == scene.meshes[0].bounds().min);  // the ground is the widest piece

    const Scene lone = columns(4, false);
    CHECK(lone.merged().closed);
    CHECK(sameMesh(lone.merged(), lone.meshes[0]));
    Scene two_closed = torusKnot(8, false);
    two_closed.meshes.push_back(columns(2, false).meshes[0]);
    const Mesh pair = two_closed.merged();
    CHECK(pair.closed);  // disjoint closed pieces stay closed...
    CHECK(everyEdgeHasOneOppositeTwin(pair));  // ...because indices are offset per piece
    CHECK(Scene{}.bounds().empty());
    CHECK(Scene{}.triangleCount() == 0);
    CHECK_FALSE(Scene{}.merged().closed);

    // casters(): every mesh but the ground, as merged() builds it.
    REQUIRE(scene.meshes[0].name == "ground");
    const Mesh casters = scene.casters();
    CHECK(casters.name == "columns");
    CHECK(casters.closed);  // the columns alone are closed
    CHECK(sameMesh(casters, scene.meshes[1]));
    CHECK(sameMesh(casters, lone.merged()));
    CHECK(sameMesh(lone.casters(), lone.merged()));  // no ground: the same as merged()
    CHECK(casters.triangleCount() + scene.meshes[0].triangleCount() == scene.triangleCount());
    Scene ground_only;
    ground_only.meshes.push_back(scene.meshes[0]);
    CHECK(ground_only.casters().positions.empty());
    CHECK_FALSE(ground_only.casters().closed);
}

TEST_CASE("scene: mesh utilities") {
    Mesh tetra;
    tetra.name = "tetra";
    tetra.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    tetra.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    computeSmoothNormals(tetra);
    CHECK(isClosed(tetra));
    CHECK(everyEdgeHasOneOppositeTwin(tetra));
    CHECK(signedVolume(tetra) == doctest::Approx(1.0 / 6.0));
    CHECK_NOTHROW(validateMesh(tetra));
    // The corner at the origin meets three faces at right angles: equal weights.
    CHECK(glm::length(tetra.normals[0] + glm::normalize(glm::vec3(1, 1, 1))) < 1e-5f);

    Mesh open = tetra;
    open.indices.resize(9);
    CHECK_FALSE(isClosed(open));
    Mesh flipped = tetra;
    std::swap(flipped.indices[1], flipped.indices[2]);
    CHECK_FALSE(isClosed(flipped));
    Mesh doubled = tetra;
    doubled.indices.insert(doubled.indices.end(), tetra.indices.begin(), tetra.indices.end());
    CHECK_FALSE(isClosed(doubled));
    Mesh inside_out = tetra;
    for (size_t t = 0; t < inside_out.indices.size(); t += 3) std::swap(inside_out.indices[t + 1], inside_out.indices[t + 2]);
    CHECK(isClosed(inside_out));  // topology only...
    CHECK(signedVolume(inside_out) < 0.0);  // ...orientation comes from the volume
    CHECK_FALSE(isClosed(Mesh{}));

    Mesh bad = tetra;
    bad.indices[4] = 9;
    CHECK(contains(errorMessage([&] { validateMesh(bad); }), "indexes past"));
    bad = tetra;
    bad.positions[1].x = std::nanf("");
    CHECK(contains(errorMessage([&] { validateMesh(bad); }), "non-finite"));
    bad = tetra;
    bad.normals[2] *= 2.0f;
    CHECK(contains(errorMessage([&] { validateMesh(bad); }), "normal of length"));
    bad = tetra;
    bad.normals.pop_back();
    CHECK(contains(errorMessage([&] { validateMesh(bad); }), "3 normals"));
    bad = tetra;
    bad.indices[1] = bad.indices[0];
    CHECK(contains(errorMessage([&] { validateMesh(bad); }), "repeats a vertex"));
    bad = tetra;
    bad.indices.pop_back();
    CHECK(contains(errorMessage([&] { validateMesh(bad); }), "multiple of 3"));

    // Isolated and degenerate-only vertices still get a unit normal.
    Mesh sparse;
    sparse.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {5, 5, 5}};
    sparse.indices = {0, 1, 2};
    computeSmoothNormals(sparse);
    for (const glm::vec3& n : sparse.normals) CHECK(glm::length(n) == doctest::Approx(1.0f));
}

// ---------------------------------------------------------------------------------------------
// OBJ

TEST_CASE("obj: quad cube loads closed, smooth and normalised") {
    TempDir dir;
    const std::string path = dir.write("quad_cube.obj", kQuadCubeObj);
    const Scene scene = loadObj(path);
    CHECK(scene.name == "quad_cube");
    REQUIRE(scene.meshes.size() == 2);
    const Mesh& cube = objectOf(scene);
    CHECK(cube.name == "quad_cube");
    CHECK(cube.triangleCount() == 12);
    CHECK(cube.positions.size() == 8);
    CHECK(cube.closed);
    CHECK(everyEdgeHasOneOppositeTwin(cube));
    CHECK(signedVolume(cube) == doctest::Approx(1.0));
    checkWellFormed(cube, 1e-3);
    checkUnitBoxOnGround(cube);
    // Per-face file normals cannot be one per vertex: smooth corner normals replace them.
    for (size_t v = 0; v < 8; ++v) {
        const glm::vec3 outward = glm::normalize(cube.positions[v] - glm::vec3(0, 0.5f, 0));
        CHECK(glm::dot(cube.normals[v], outward) == doctest::Approx(1.0f));
    }
    checkFraming(scene, 0.0f);
    CHECK(sameMesh(objectOf(load(path)), cube));

    ObjOptions no_ground;
    no_ground.ground = false;
    CHECK(loadObj(path, no_ground).meshes.size() == 1);
}

TEST_CASE("obj: winding, normals, polygons and raw coordinates") {
    TempDir dir;
    SUBCASE("inside-out closed mesh is turned outward") {
        const Scene scene = loadObj(dir.write("inward.obj", cubeObjWithFaces(true, 1.0, 0.0)));
        CHECK(objectOf(scene).closed);
        CHECK(signedVolume(objectOf(scene)) > 0.0);
        checkWellFormed(objectOf(scene), 1e-3);
    }
    SUBCASE("normalize = false keeps file coordinates, ground under the object") {
        ObjOptions raw;
        raw.normalize = false;
        const Scene scene = loadObj(dir.write("raw.obj", cubeObjWithFaces(false, 2.0, 10.0)), raw);
        const Bounds box = objectOf(scene).bounds();
        CHECK(box.min == glm::vec3(8.0f));
        CHECK(box.max == glm::vec3(12.0f));
        CHECK(scene.meshes.front().bounds().min.y == 8.0f);
        checkFraming(scene, 8.0f);
    }
    SUBCASE("one normal per vertex in the file is kept (normalised)") {
        const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nvn 0 3 0\nvn 0 0.5 0\nvn 0 2 0\nf 1//1 2//2 3//3\n";
        const Mesh mesh = objectOf(loadObj(dir.write("normals.obj", obj)));
        CHECK_FALSE(mesh.closed);
        for (const glm::vec3& n : mesh.normals) CHECK(n == glm::vec3(0, 1, 0));
        // Normals opposing the winding are turned around with it.
        const std::string flipped = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nvn 0 -1 0\nf 1//1 2//1 3//1\n";
        for (const glm::vec3& n : objectOf(loadObj(dir.write("against.obj", flipped))).normals)
            CHECK(n == glm::vec3(0, 1, 0));
    }
    SUBCASE("n-gons: convex hexagon and concave L prisms stay closed with upright caps") {
        std::vector<glm::vec2> hexagon, ell = {{0, 0}, {2, 0}, {2, -1}, {1, -1}, {1, -3}, {0, -3}};
        for (int k = 0; k < 6; ++k)
            hexagon.emplace_back(std::cos(static_cast<float>(k) * 3.14159265f / 3), -std::sin(static_cast<float>(k) * 3.14159265f / 3));
        for (const auto& polygon : {hexagon, ell}) {
            ObjOptions raw;
            raw.normalize = false;
            const Mesh prism = objectOf(loadObj(dir.write("prism.obj", prismObj(polygon, 1.0f)), raw));
            CHECK(prism.triangleCount() == 2 * 6 + 2 * 4);
            CHECK(prism.closed);
            CHECK(everyEdgeHasOneOppositeTwin(prism));
            checkWellFormed(prism, 1e-4);
            // Ear clipping never emits a cap triangle facing the wrong way (a fan would, for L).
            for (size_t t = 0; t < prism.triangleCount(); ++t) {
                const glm::dvec3 n = faceNormal(prism, t);
                const float y = prism.positions[prism.indices[3 * t]].y;
                const bool cap = y == prism.positions[prism.indices[3 * t + 1]].y &&
                                 y == prism.positions[prism.indices[3 * t + 2]].y;
                if (cap) CHECK((y > 0.5f ? n.y > 0.0 : n.y < 0.0));
            }
        }
        const Mesh ell_prism = objectOf(loadObj(dir.write("ell.obj", prismObj(ell, 2.0f)), ObjOptions{true, false}));
        CHECK(signedVolume(ell_prism) == doctest::Approx(4.0 * 2.0));
    }
    SUBCASE("unused vertices and index-degenerate faces are dropped") {
        const std::string obj = "v 5 5 5\nv 0 0 0\nv 1 0 0\nv 0 0 -1\nv 9 9 9\nf 2 3 4\nf 2 2 3\n";
        const Mesh mesh = objectOf(loadObj(dir.write("sparse.obj", obj), ObjOptions{false, false}));
        CHECK(mesh.positions.size() == 3);
        CHECK(mesh.triangleCount() == 1);
        CHECK(mesh.bounds().max == glm::vec3(1, 0, 0));
    }
}

TEST_CASE("obj: failures name the path and the reason") {
    TempDir dir;
    const std::string missing = (dir.path / "missing.obj").string();
    std::string message = errorMessage([&] { loadObj(missing); });
    CHECK(contains(message, missing));
    CHECK(contains(message, "cannot open"));
    CHECK(contains(errorMessage([&] { load(missing); }), missing));

    const std::string garbage = dir.write("garbage.obj", "this is not\n an OBJ file \x01\x02\xff\n{}[]\n");
    message = errorMessage([&] { loadObj(garbage); });
    CHECK(contains(message, garbage));
    CHECK(contains(message, "no triangles"));

    const std::string empty = dir.write("empty.obj", "");
    CHECK(contains(errorMessage([&] { loadObj(empty); }), "no triangles"));

    const std::string degenerate = dir.write("degenerate.obj", "v 0 0 0\nv 1 0 0\nf 1 1 2\nf 1 2\n");
    CHECK(contains(errorMessage([&] { loadObj(degenerate); }), "no triangles"));

    // 1e39 is a fine double but overflows float: the validating pass names line and text.
    const std::string infinite = dir.write("infinite.obj", "v 0 0 0\nv 1e39 0 0\nv 0 1 0\nf 1 2 3\n");
    message = errorMessage([&] { loadObj(infinite); });
    CHECK(contains(message, infinite));
    CHECK(contains(message, "vertex 2: '1e39' is beyond float range"));  // not "NaN or infinite": it is neither
    CHECK(contains(message, "line 2"));
    CHECK(contains(message, "'1e39'"));

    const std::string out_of_range = dir.write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    message = errorMessage([&] { loadObj(out_of_range); });
    CHECK(contains(message, out_of_range));
    CHECK(contains(message, "vertex 9"));

    const std::string coincident = dir.write("point.obj", "v 1 1 1\nv 1 1 1\nv 1 1 1\nf 1 2 3\n");
    CHECK(contains(errorMessage([&] { loadObj(coincident); }), "coincide"));

    CHECK(contains(errorMessage([&] { loadObj(dir.path.string()); }), dir.path.string()));
}

TEST_CASE("obj: the validating pass names the line and the value") {
    // Each case: OBJ text, then the parts its message must contain. Without the pass,
    // tinyobjloader reads nan/inf/garbage as 0 and a missing coordinate as 0.
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    const std::vector<std::pair<std::string, std::vector<std::string>>> cases = {
        {"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "vertex 2 has a NaN or infinite coordinate", "'nan'"}},
        {"v 0 0 0\nv 1 0 0\nv 0 -NaN 0\nf 1 2 3\n", {"line 3", "vertex 3", "NaN or infinite", "'-NaN'"}},
        {"v 0 0 0\nv 1 inf 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "vertex 2", "NaN or infinite", "'inf'"}},
        {"v 0 0 0\nv 1 0 0\nv 0 1 -Infinity\nf 1 2 3\n", {"line 3", "'-Infinity'"}},
        {"v 0 0 0\nv 1 0 1e400\nv 0 1 0\nf 1 2 3\n", {"line 2", "'1e400'", "beyond float range"}},
        {"# c\nv 0 0 0\nv 1 0\nv 0 1 0\nf 1 2 3\n", {"line 3", "vertex 2", "needs 3 coordinates, found 2"}},
        {"v\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"line 1", "found 0"}},
        {"v 0 0 0\nv 1 0 0\nv 0 1.2.3 0\nf 1 2 3\n", {"line 3", "'1.2.3' is not a number"}},
        {"v 0 0 0\nv 1 0 0\nv 0 0x10 0\nf 1 2 3\n", {"line 3", "'0x10' is not a number"}},
        {"v 0 0 0\nv 1 0 0\nv 0 1 0 extra\nf 1 2 3\n", {"line 3", "'extra' is not a number"}},
        {tri + "vn 0 1\nf 1 2 3\n", {"line 4", "normal 1", "needs 3 coordinates"}},
        {tri + "vn 0 nan 0\nf 1 2 3\n", {"line 4", "normal 1", "'nan'"}},
        {tri + "vt 0.5 e\nf 1 2 3\n", {"line 4", "texture coordinate 1", "'e' is not a number"}},
        {tri + "f 1 2 0\n", {"line 4", "vertex index 0", "start at 1"}},
        {tri + "f 1 2 9\n", {"line 4", "vertex 9", "the file has 3 vertices"}},
        {tri + "f 1 2 -4\n", {"line 4", "relative vertex index -4", "3 defined so far"}},
        {tri + "f 1 2 2147483648\n", {"line 4", "'2147483648' overflows int"}},
        {tri + "f 1 2 -99999999999999999999999\n", {"line 4", "overflows int"}},
        {tri + "f 1 2 3x\n", {"line 4", "'3x' is not a vertex index"}},
        {tri + "f 1 2 /3\n", {"line 4", "'/3'", "not a vertex index"}},
        {tri + "vn 0 1 0\nf 1//1 2//1 3//2\n", {"line 5", "normal 2", "the file has 1 normals"}},
        {tri + "f 1/0 2 3\n", {"line 4", "texture coordinate index 0"}},
        {tri + "f 1/1/1/1 2 3\n", {"line 4", "more than 3 indices"}},
        {"v 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\nv 1 1 nan\r\n", {"line 5", "'nan'"}},  // CRLF counts once
        {"v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n", {"every one of the 1 triangles has zero area"}},  // collinear: nothing to render
        {"v 0 0 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nf 1 2 3\nf 2 3 4\n", {"every one of the 2 triangles has zero area"}},
    };
    for (const auto& [text, parts] : cases) {
        INFO(text);
        const std::string message = errorMessage([&] { parseObj(text, "case.obj"); });
        CHECK(contains(message, "parseObj('case.obj')"));
        for (const std::string& part : parts) CHECK(contains(message, part));
    }
    // The same reaches loadObj's message with the path.
    TempDir dir;
    const std::string path = dir.write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string message = errorMessage([&] { loadObj(path); });
    CHECK(contains(message, path));
    CHECK(contains(message, "line 2"));
    CHECK(contains(message, "'nan'"));

    // What stays valid: signs, leading dots, exponents, relative indices, v//vn, colours,
    // ignored statements (materials, smoothing, lines, tinyobjloader's tags) and unused vt.
    const std::string good = "mtllib missing.mtl\no thing\ns 1\nv +0 -0. .0\nv 1e0 0 0 1 0.5 0.25\n"
                             "v 0 1E+0 0\nvt 0.5\nvn 0 0 1\nusemtl none\nl 1 2\nt crease 2/1/0 1 2 0.5\n"
                             "f -3//1 -2//1 -1//1\n";
    const Scene scene = parseObj(good, "good.obj", ObjOptions{false, false});
    REQUIRE(scene.meshes.size() == 1);
    CHECK(scene.meshes[0].name == "good");
    CHECK(scene.meshes[0].triangleCount() == 1);
    CHECK(scene.meshes[0].bounds().max == glm::vec3(1, 1, 0));
    // Exponents tinyobjloader's own parser would overflow int on (found by obj_fuzz): the
    // values reach it re-printed, so a zero with a huge exponent is zero and 12e-1 is 1.2.
    const Scene exponents = parseObj("v 0e-2147483648 0 0\nv 10e-1 0e2147483647 0\nv 0 12e-1 0\nf 1 2 3\n",
                                     "exponents.obj", ObjOptions{false, false});
    REQUIRE(exponents.meshes.size() == 1);
    CHECK(exponents.meshes[0].bounds().max == glm::vec3(1, 1.2f, 0));
    // parseObj and loadObj agree.
    CHECK(sameMesh(objectOf(parseObj(kQuadCubeObj, "quad_cube.obj")),
                   objectOf(loadObj(dir.write("quad_cube.obj", kQuadCubeObj)))));
}

/// UV sphere of radius `radius` around `centre` (slices x stacks, single-vertex poles, quads in
/// between, outward winding), printed with 17 digits so the file holds the doubles exactly.
/// `offsets` receives each vertex's position relative to the centre, in file order.
std::string uvSphereObj(const glm::dvec3& centre, double radius, std::vector<glm::dvec3>& offsets) {
    const int slices = 8, stacks = 6;
    const double pi = 3.14159265358979323846;
    offsets.clear();
    offsets.emplace_back(0.0, radius, 0.0);
    for (int i = 1; i < stacks; ++i) {
        const double theta = pi * i / stacks;
        for (int j = 0; j < slices; ++j) {
            const double phi = 2.0 * pi * j / slices;
            offsets.emplace_back(radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta),
                                 radius * std::sin(theta) * std::sin(phi));
        }
    }
    offsets.emplace_back(0.0, -radius, 0.0);
    std::ostringstream obj;
    obj.precision(17);
    for (const glm::dvec3& q : offsets) obj << "v " << centre.x + q.x << ' ' << centre.y + q.y << ' ' << centre.z + q.z << '\n';
    const int bottom = 1 + slices * (stacks - 1) + 1;
    auto ring = [&](int i, int j) { return 2 + (i - 1) * slices + (j % slices); };  // 1-based
    for (int j = 0; j < slices; ++j) {
        obj << "f 1 " << ring(1, j + 1) << ' ' << ring(1, j) << '\n';
        for (int i = 1; i + 1 < stacks; ++i)
            obj << "f " << ring(i, j) << ' ' << ring(i, j + 1) << ' ' << ring(i + 1, j + 1) << ' ' << ring(i + 1, j) << '\n';
        obj << "f " << bottom << ' ' << ring(stacks - 1, j) << ' ' << ring(stacks - 1, j + 1) << '\n';
    }
    return obj.str();
}

TEST_CASE("obj: far from the origin, coordinates are normalised in double") {
    TempDir dir;
    SUBCASE("a sphere centred at 1e6 + 0.3 loads with the shape it has at the origin") {
        std::vector<glm::dvec3> offsets;
        const Mesh near = objectOf(loadObj(dir.write("near.obj", uvSphereObj(glm::dvec3(0.0), 1.0, offsets))));
        const double c = 1e6 + 0.3;
        const Mesh far = objectOf(loadObj(dir.write("far.obj", uvSphereObj(glm::dvec3(c, c, c), 1.0, offsets))));
        // Expected, in double from the generated offsets: centred on the y axis, on y = 0, size 1.
        glm::dvec3 lo(1e300), hi(-1e300);
        for (const glm::dvec3& q : offsets) lo = glm::min(lo, q), hi = glm::max(hi, q);
        const double extent = std::max(hi.x - lo.x, std::max(hi.y - lo.y, hi.z - lo.z));
        const glm::dvec3 anchor(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
        REQUIRE(near.positions.size() == offsets.size());
        REQUIRE(far.positions.size() == offsets.size());
        // (Quad splits may differ: a UV sphere's quads are isosceles trapezoids, diagonals tie.)
        CHECK(far.triangleCount() == near.triangleCount());
        CHECK(far.closed);
        double worst = 0.0, worst_normal = 0.0;
        for (size_t v = 0; v < offsets.size(); ++v) {
            const glm::dvec3 expected = (offsets[v] - anchor) / extent;
            for (const Mesh* mesh : {&near, &far}) {
                const glm::dvec3 error = glm::abs(glm::dvec3(mesh->positions[v]) - expected);
                worst = std::max(worst, std::max(error.x, std::max(error.y, error.z)));
            }
            worst_normal = std::max(worst_normal, glm::length(glm::dvec3(far.normals[v] - near.normals[v])));
        }
        INFO("largest position error " << worst << ", normal difference " << worst_normal << " (size 1)");
        CHECK(worst <= 1e-6);
        CHECK(worst_normal <= 1e-5);
    }
    SUBCASE("a unit cube centred at 1e8 loads as the unit box on the ground") {
        std::ostringstream obj;
        obj.precision(17);
        for (int corner = 0; corner < 8; ++corner)
            obj << "v " << 1e8 + ((corner & 1) ? 0.5 : -0.5) << ' ' << 1e8 + ((corner & 2) ? 0.5 : -0.5) << ' '
                << 1e8 + ((corner & 4) ? 0.5 : -0.5) << '\n';
        // Outward quads over the corner numbering above (bit 0 = x, bit 1 = y, bit 2 = z), 1-based.
        obj << "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
        const std::string path = dir.write("far_cube.obj", obj.str());
        const Mesh cube = objectOf(loadObj(path));
        REQUIRE(cube.positions.size() == 8);
        CHECK(cube.triangleCount() == 12);
        CHECK(cube.closed);
        CHECK(signedVolume(cube) == doctest::Approx(1.0));
        for (int corner = 0; corner < 8; ++corner) {
            const glm::vec3 expected((corner & 1) ? 0.5f : -0.5f, (corner & 2) ? 1.0f : 0.0f, (corner & 4) ? 0.5f : -0.5f);
            CHECK(cube.positions[static_cast<size_t>(corner)] == expected);
        }
        checkWellFormed(cube, 0.1);
        // Raw coordinates must be floats: at 1e8 (float spacing 8) the cube is one point, refused
        // with a message that says so and points at normalisation.
        ObjOptions raw;
        raw.normalize = false;
        const std::string message = errorMessage([&] { loadObj(path, raw); });
        CHECK(contains(message, path));
        CHECK(contains(message, "coincide in float"));
        CHECK(contains(message, "normalize"));
    }
}

TEST_CASE("obj: exact duplicate triangles are removed and counted") {
    TempDir dir;
    std::string copies = "v 0 0 0\nv 1 0 0\nv 0 0 -1\n";
    for (int k = 0; k < 10000; ++k) copies += "f 1 2 3\n";
    const std::string path = dir.write("copies.obj", copies);
    SUBCASE("10^4 copies of one triangle load as one, reported") {
        ObjReport report;
        const Mesh mesh = objectOf(loadObj(path, ObjOptions{}, report));
        CHECK(mesh.triangleCount() == 1);
        CHECK(mesh.positions.size() == 3);
        CHECK(report.duplicate_triangles == 9999);
        REQUIRE(report.warnings.size() == 1);
        CHECK(contains(report.warnings[0], "9999 duplicate triangles removed"));
        // The plain overloads give the same scene.
        CHECK(sameMesh(objectOf(loadObj(path)), mesh));
        CHECK(sameMesh(objectOf(parseObj(copies, "copies.obj")), mesh));
    }
    SUBCASE("kept on request, still counted") {
        ObjOptions keep;
        keep.remove_duplicate_triangles = false;
        ObjReport report;
        CHECK(objectOf(loadObj(path, keep, report)).triangleCount() == 10000);
        CHECK(report.duplicate_triangles == 9999);
        REQUIRE(report.warnings.size() == 1);
        CHECK(contains(report.warnings[0], "9999 duplicate triangles kept"));
    }
    SUBCASE("same positions in any rotation are duplicates; the reversed winding is not") {
        // Vertices 4-6 repeat 1-3's positions under other indices; f 1 3 2 is the back face.
        const std::string obj = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 1 0 0\nv 0 0 -1\nv 0 0 0\n"
                                "f 1 2 3\nf 2 3 1\nf 3 1 2\nf 6 4 5\nf 1 3 2\nf 4 5 6\n";
        ObjReport report;
        const Mesh mesh = objectOf(parseObj(obj, "rotations.obj", ObjOptions{false, false}, report));
        CHECK(report.duplicate_triangles == 4);
        REQUIRE(mesh.triangleCount() == 2);
        CHECK(mesh.positions.size() == 3);  // vertices 4-6 are no longer used
        // The first occurrence is kept, in file order: the front face, then the back face.
        CHECK(mesh.indices == std::vector<uint32_t>{0, 1, 2, 0, 2, 1});
    }
    SUBCASE("a clean file reports nothing; index-degenerate faces are counted") {
        ObjReport report;
        parseObj(kQuadCubeObj, "quad_cube.obj", ObjOptions{}, report);
        CHECK(report.duplicate_triangles == 0);
        CHECK(report.repeated_index_triangles == 0);
        CHECK(report.warnings.empty());
        parseObj("v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\nf 2 2 3\nf 1 1 1\n", "degenerate.obj", ObjOptions{}, report);
        CHECK(report.duplicate_triangles == 0);  // a report is reset, not accumulated
        CHECK(report.repeated_index_triangles == 2);
        REQUIRE(report.warnings.size() == 1);
        CHECK(contains(report.warnings[0], "2 triangles repeating a vertex index dropped"));
    }
}

TEST_CASE("obj: progress is reported while loading and can cancel") {
    // 2^17 face lines: enough for calls inside the line and face loops, not only at their ends.
    std::string text = "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 0 1 0\n";
    for (int k = 0; k < (1 << 17); ++k) text += k % 2 ? "f 1 2 3\n" : "f 1 3 4\n";
    std::vector<double> fractions;
    ObjOptions options;
    options.progress = [&](double fraction) {
        fractions.push_back(fraction);
        return true;
    };
    const Mesh mesh = objectOf(parseObj(text, "progress.obj", options));
    CHECK(mesh.triangleCount() == 2);
    REQUIRE(fractions.size() >= 6);
    CHECK(fractions.back() == 1.0);
    CHECK(std::is_sorted(fractions.begin(), fractions.end()));
    CHECK(fractions.front() >= 0.0);
    size_t inside = 0;
    for (double f : fractions) inside += f > 0.0 && f < 1.0;
    CHECK(inside >= 4);

    // Cancelling at any call throws, naming the file and the fraction reached.
    for (size_t stop : {size_t(0), fractions.size() / 2, fractions.size() - 1}) {
        INFO("cancel at call " << stop);
        size_t calls = 0;
        options.progress = [&](double) { return calls++ < stop; };
        const std::string message = errorMessage([&] { parseObj(text, "progress.obj", options); });
        CHECK(contains(message, "parseObj('progress.obj')"));
        CHECK(contains(message, "cancelled"));
        CHECK(calls == stop + 1);
    }
}

TEST_CASE("obj: shared real meshes (spot closed, teapot)") {
#ifndef PENUMBRA_SHARED_SCENES_DIR
    MESSAGE("skipped: PENUMBRA_SHARED_SCENES_DIR is not defined");
#else
    const fs::path folder = PENUMBRA_SHARED_SCENES_DIR;
    if (!fs::is_directory(folder)) {
        MESSAGE("skipped: shared scenes folder " << folder.string() << " is missing");
        return;
    }
    for (const char* file : {"spot.obj", "teapot.obj", "cow.obj", "fandisk.obj"}) {
        const fs::path path = folder / file;
        if (!fs::exists(path)) {
            MESSAGE("skipped " << path.string() << ": missing");
            continue;
        }
        INFO(path.string());
        ObjReport report;
        const Scene scene = loadObj(path.string(), ObjOptions{}, report);
        const Mesh& mesh = objectOf(scene);
        MESSAGE(std::string(file) << ": " << mesh.triangleCount() << " triangles, " << mesh.positions.size()
                     << " vertices, closed = " << mesh.closed << ", " << report.duplicate_triangles
                     << " duplicates removed, " << report.warnings.size() << " warnings");
        CHECK(report.warnings.size() == size_t(report.short_faces > 0) + size_t(report.repeated_index_triangles > 0) +
                                            size_t(report.duplicate_triangles > 0));
        CHECK(mesh.triangleCount() > 1000);
        checkWellFormed(mesh, 0.0, /*normals_face_front=*/false);
        checkUnitBoxOnGround(mesh);
        checkFraming(scene, 0.0f);
        CHECK(mesh.closed == everyEdgeHasOneOppositeTwin(mesh));
        if (std::string(file) == "spot.obj") {
            CHECK(mesh.closed);
            CHECK(signedVolume(mesh) > 0.0);
        }
    }
#endif
}

// ---------------------------------------------------------------------------------------------
// Images

TEST_CASE("image: linear to sRGB8") {
    CHECK(linearToSrgb8(0.0f) == 0);
    CHECK(linearToSrgb8(-3.0f) == 0);
    CHECK(linearToSrgb8(std::nanf("")) == 0);
    CHECK(linearToSrgb8(1.0f) == 255);
    CHECK(linearToSrgb8(7.0f) == 255);
    CHECK(linearToSrgb8(INFINITY) == 255);
    CHECK(linearToSrgb8(0.5f) == 188);      // 0.7354 * 255 = 187.5
    CHECK(linearToSrgb8(0.0031308f) == 10);  // end of the linear segment: 0.04045 * 255
    CHECK(linearToSrgb8(0.2158605f) == 128);  // ((128 / 255 + 0.055) / 1.055)^2.4
    uint8_t previous = 0;
    for (int i = 0; i <= 10000; ++i) {
        const uint8_t code = linearToSrgb8(static_cast<float>(i) / 10000.0f);
        REQUIRE(code >= previous);
        previous = code;
    }
    for (int code = 0; code < 256; ++code) {
        INFO("code " << code);
        REQUIRE(linearToSrgb8(srgb8ToLinear(static_cast<uint8_t>(code))) == code);
    }
}

TEST_CASE("image: helpers and PNG writing") {
    const uint32_t width = 37, height = 19;  // odd sizes: no accidental alignment
    std::vector<float> linear(size_t(width) * height * 3);
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x) {
            float* rgb = &linear[(size_t(y) * width + x) * 3];
            rgb[0] = static_cast<float>(x) / (width - 1);
            rgb[1] = static_cast<float>(y) / (height - 1);
            rgb[2] = 0.25f;
        }
    const ImageRgb8 image = imageFromLinear(width, height, linear.data(), 3);
    REQUIRE(image.pixels.size() == size_t(width) * height * 3);
    CHECK(image.pixels[0] == 0);
    CHECK(image.pixels[3 * (width - 1)] == 255);
    CHECK(image.pixels[(size_t(height - 1) * width) * 3 + 1] == 255);
    CHECK(image.pixels[2] == linearToSrgb8(0.25f));

    ImageRgb8 flipped = imageFromLinear(width, height, linear.data(), 3, /*bottom_up=*/true);
    CHECK(flipped.pixels != image.pixels);
    flipRows(flipped);
    CHECK(flipped.pixels == image.pixels);

    const std::vector<float> grey = {0.0f, 1.0f};
    const ImageRgb8 two = imageFromLinear(2, 1, grey.data(), 1);
    CHECK(two.pixels == std::vector<uint8_t>{0, 0, 0, 255, 255, 255});
    CHECK(makeImageRgb8(2, 2, 1, 2, 3).pixels == std::vector<uint8_t>{1, 2, 3, 1, 2, 3, 1, 2, 3, 1, 2, 3});
    CHECK_THROWS_AS(imageFromLinear(2, 1, grey.data(), 2), penumbra::Error);
    CHECK_THROWS_AS(imageFromLinear(2, 1, nullptr, 1), penumbra::Error);

    TempDir dir;
    const std::string path = (dir.path / "gradient.png").string();
    writePng(path, image);
    std::ifstream file(path, std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    REQUIRE(bytes.size() > 33);
    const uint8_t signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    CHECK(std::equal(std::begin(signature), std::end(signature), bytes.begin()));
    CHECK(std::string(bytes.begin() + 12, bytes.begin() + 16) == "IHDR");
    auto bigEndian = [&](size_t at) {
        return uint32_t(bytes[at]) << 24 | uint32_t(bytes[at + 1]) << 16 | uint32_t(bytes[at + 2]) << 8 | bytes[at + 3];
    };
    CHECK(bigEndian(16) == width);
    CHECK(bigEndian(20) == height);
    CHECK(bytes[24] == 8);  // bit depth
    CHECK(bytes[25] == 2);  // colour type RGB
    CHECK(bytes == encodePng(image));

    const std::string unwritable = (dir.path / "no_such_folder" / "x.png").string();
    std::string message = errorMessage([&] { writePng(unwritable, image); });
    CHECK(contains(message, unwritable));
    CHECK(contains(message, "cannot create"));
    CHECK(contains(errorMessage([&] { writePng(dir.path.string(), image); }), dir.path.string()));

    ImageRgb8 wrong = image;
    wrong.pixels.pop_back();
    message = errorMessage([&] { writePng((dir.path / "wrong.png").string(), wrong); });
    CHECK(contains(message, "wrong.png"));
    CHECK(contains(message, "37x19"));
    CHECK_FALSE(fs::exists(dir.path / "wrong.png"));
    CHECK(contains(errorMessage([&] { encodePng(ImageRgb8{}); }), "empty"));
    CHECK_THROWS_AS(flipRows(wrong), penumbra::Error);
}
