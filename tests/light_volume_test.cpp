// Tests of the light-volume tessellator (penumbra/light_volume.hpp, billeter2010): the closed
// volume is watertight (every directed edge once, its twin once), has no T-junction, faces
// outward, covers the whole shadow map once, and its adaptive floor stays within 2 * flatness of
// the static one at every lattice point; planes become single cells; bad input is rejected by
// name. Shadow maps: synthetic ones and the built-in scenes' depth maps ray cast with the oracle.
#include <penumbra/light_volume.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/scene.hpp>

#include "support/light_volume_maps.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <random>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

namespace {

using penumbra::LightVolumeMesh;
using penumbra::LightVolumeOptions;
using penumbra::LightVolumeSetup;
using penumbra::LightVolumeTessellation;
using penumbra::test::volumeSetup;
using penumbra::test::SceneMap;
using penumbra::test::TestLight;
using penumbra::test::sceneMap;
using penumbra::test::testLight;

struct MeshReport {
    uint64_t bad_edges = 0;       // directed edges occurring more than once or without one twin
    uint64_t t_junctions = 0;     // used lattice vertices strictly inside a floor edge
    uint64_t degenerate = 0;      // triangles repeating a vertex
    int64_t doubled_area = 0;     // sum of the floor's doubled signed areas in lattice units
    double signed_volume = 0.0;   // world space, divergence theorem
    double max_floor_error = 0.0; // max |floor - lattice depth| over every lattice point
    uint64_t uncovered = 0;       // lattice points inside no floor triangle
};

/// Every property of the header comment, checked independently of the tessellator's own logic.
MeshReport inspect(const LightVolumeMesh& mesh, const std::vector<float>& corners, const glm::dmat4& inverse_vp,
                   const glm::dvec3& apex) {
    const uint32_t r = mesh.resolution, n = r + 1;
    MeshReport report;
    std::unordered_map<uint64_t, uint32_t> edges;
    std::vector<uint8_t> used(static_cast<size_t>(n) * n, 0);
    const size_t triangles = mesh.triangles.size() / 3;
    edges.reserve(3 * triangles);
    for (size_t t = 0; t < triangles; ++t) {
        const uint32_t* v = mesh.triangles.data() + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) ++report.degenerate;
        for (int e = 0; e < 3; ++e) ++edges[(uint64_t(v[e]) << 32) | v[(e + 1) % 3]];
        for (int e = 0; e < 3; ++e)
            if (v[e] != penumbra::kLightVolumeApex) used[size_t(penumbra::lightVolumeJ(v[e])) * n + penumbra::lightVolumeI(v[e])] = 1;
    }
    for (const auto& [key, count] : edges) {
        const uint64_t twin = (key << 32) | (key >> 32);
        const auto it = edges.find(twin);
        if (count != 1 || it == edges.end() || it->second != 1) ++report.bad_edges;
    }
    std::vector<uint8_t> covered(static_cast<size_t>(n) * n, 0);
    for (size_t t = 0; t < mesh.floor_triangles; ++t) {
        const uint32_t* v = mesh.triangles.data() + 3 * t;
        int64_t x[3], y[3];
        for (int k = 0; k < 3; ++k) {
            x[k] = penumbra::lightVolumeI(v[k]);
            y[k] = penumbra::lightVolumeJ(v[k]);
        }
        const int64_t area2 = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        report.doubled_area += area2;
        // T-junctions: lattice points strictly inside each edge.
        for (int e = 0; e < 3; ++e) {
            const int64_t dx = x[(e + 1) % 3] - x[e], dy = y[(e + 1) % 3] - y[e];
            const int64_t g = std::gcd(std::abs(dx), std::abs(dy));
            for (int64_t s = 1; s < g; ++s)
                report.t_junctions += used[size_t(y[e] + s * dy / g) * n + size_t(x[e] + s * dx / g)];
        }
        // Every lattice point in the (closed) triangle: interpolated depth vs its own depth.
        if (area2 == 0) continue;
        const int64_t x_lo = std::min({x[0], x[1], x[2]}), x_hi = std::max({x[0], x[1], x[2]});
        const int64_t y_lo = std::min({y[0], y[1], y[2]}), y_hi = std::max({y[0], y[1], y[2]});
        double d[3];
        for (int k = 0; k < 3; ++k) d[k] = corners[size_t(y[k]) * n + size_t(x[k])];
        for (int64_t py = y_lo; py <= y_hi; ++py) {
            for (int64_t px = x_lo; px <= x_hi; ++px) {
                int64_t w[3];
                for (int k = 0; k < 3; ++k) {
                    const int a = (k + 1) % 3, b = (k + 2) % 3;
                    w[k] = (x[b] - x[a]) * (py - y[a]) - (px - x[a]) * (y[b] - y[a]);
                }
                const bool inside = area2 > 0 ? (w[0] >= 0 && w[1] >= 0 && w[2] >= 0) : (w[0] <= 0 && w[1] <= 0 && w[2] <= 0);
                if (!inside) continue;
                covered[size_t(py) * n + size_t(px)] = 1;
                const double value = (double(w[0]) * d[0] + double(w[1]) * d[1] + double(w[2]) * d[2]) / double(area2);
                report.max_floor_error = std::max(report.max_floor_error, std::abs(value - double(corners[size_t(py) * n + size_t(px)])));
            }
        }
    }
    for (uint8_t c : covered) report.uncovered += c == 0;
    for (size_t t = 0; t < triangles; ++t) {
        const uint32_t* v = mesh.triangles.data() + 3 * t;
        const glm::dvec3 a = penumbra::lightVolumePosition(v[0], r, corners, inverse_vp, apex);
        const glm::dvec3 b = penumbra::lightVolumePosition(v[1], r, corners, inverse_vp, apex);
        const glm::dvec3 c = penumbra::lightVolumePosition(v[2], r, corners, inverse_vp, apex);
        report.signed_volume += glm::dot(a - apex, glm::cross(b - apex, c - apex)) / 6.0;
    }
    return report;
}

void checkVolume(const std::string& what, const LightVolumeSetup& setup, const std::vector<float>& depth, const TestLight& light,
                 LightVolumeMesh* out = nullptr) {
    INFO(what << ", R = " << setup.resolution << ", flatness = " << setup.options.flatness
              << (setup.options.tessellation == LightVolumeTessellation::Static ? ", static" : ", adaptive"));
    const std::vector<float> corners = penumbra::lightVolumeCornerDepths(setup, depth);
    LightVolumeMesh mesh = penumbra::tessellateLightVolume(setup, corners);
    const MeshReport report = inspect(mesh, corners, light.inverse, light.position);
    const int64_t r = setup.resolution;
    CHECK(report.bad_edges == 0);
    CHECK(report.t_junctions == 0);
    CHECK(report.degenerate == 0);
    CHECK(report.doubled_area == -2 * r * r);  // clockwise in NDC, the whole map once
    CHECK(report.uncovered == 0);
    CHECK(report.signed_volume > 0.0);
    CHECK(report.max_floor_error <= 2.0 * setup.options.flatness + 1e-12);
    CHECK(mesh.triangleCount() <= setup.maxTriangles());
    CHECK(mesh.floor_triangles <= setup.max_floor_triangles);
    if (setup.options.tessellation == LightVolumeTessellation::Static) {
        CHECK(mesh.floor_triangles == uint64_t(2 * r * r));
        CHECK(mesh.triangleCount() == uint64_t(2 * r * r + 4 * r));
    }
    if (out) *out = std::move(mesh);
}

}  // namespace

TEST_CASE("light volume setup and corner depths: bad input named") {
    for (uint32_t bad : {0u, 1u, 3u, 100u, 1023u, 32768u}) {
        INFO("R = " << bad);
        const std::string expected = "got " + std::to_string(bad) + ")";
        CHECK_THROWS_WITH_AS(penumbra::lightVolumeSetup(bad), doctest::Contains(expected.c_str()), penumbra::Error);
    }
    LightVolumeOptions options;
    options.flatness = -1e-3;
    CHECK_THROWS_WITH_AS(penumbra::lightVolumeSetup(64, options), doctest::Contains("flatness"), penumbra::Error);
    options.flatness = std::nan("");
    CHECK_THROWS_WITH_AS(penumbra::lightVolumeSetup(64, options), doctest::Contains("flatness"), penumbra::Error);
    const LightVolumeSetup setup = penumbra::lightVolumeSetup(4);
    CHECK(setup.levels == 2);
    CHECK_THROWS_WITH_AS(penumbra::lightVolumeCornerDepths(setup, std::vector<float>(15, 0.5f)), doctest::Contains("got 15"),
                         penumbra::Error);
    for (float bad : {std::nanf(""), INFINITY, -0.25f, 1.5f}) {
        std::vector<float> depth(16, 0.5f);
        depth[6] = bad;  // texel (2, 1)
        INFO("depth " << bad);
        CHECK_THROWS_WITH_AS(penumbra::lightVolumeCornerDepths(setup, depth), doctest::Contains("texel (2, 1)"), penumbra::Error);
    }
    CHECK_THROWS_AS(penumbra::tessellateLightVolume(setup, std::vector<float>(24, 0.5f)), penumbra::Error);
}

TEST_CASE("light volume: planes become one cell, exactly; corners extrapolate planes to the border") {
    const TestLight light = testLight();
    for (uint32_t r : {2u, 4u, 64u, 1024u}) {
        // Dyadic plane: every texel, interpolated corner and extrapolated border corner is exact.
        std::vector<float> depth(size_t(r) * r);
        for (uint32_t y = 0; y < r; ++y)
            for (uint32_t x = 0; x < r; ++x) depth[size_t(y) * r + x] = 0.25f + float(x) * 0x1p-13f + float(y) * 0x1p-14f;
        const LightVolumeSetup setup = volumeSetup(r, 0.0);
        const std::vector<float> corners = penumbra::lightVolumeCornerDepths(setup, depth);
        for (uint32_t j = 0; j <= r; ++j)
            for (uint32_t i = 0; i <= r; ++i)
                REQUIRE(corners[size_t(j) * (r + 1) + i] == 0.25f + (float(i) - 0.5f) * 0x1p-13f + (float(j) - 0.5f) * 0x1p-14f);
        LightVolumeMesh mesh;
        checkVolume("plane", setup, depth, light, &mesh);
        CHECK(mesh.leaves == 1);
        CHECK(mesh.floor_triangles == 2);
        CHECK(mesh.triangleCount() == 6);
    }
    // Two planes meeting at a crease along x = 40 (of 64): cells away from the crease stay large.
    const uint32_t r = 64;
    std::vector<float> depth(size_t(r) * r);
    for (uint32_t y = 0; y < r; ++y)
        for (uint32_t x = 0; x < r; ++x) depth[size_t(y) * r + x] = 0.5f + float(std::min(x, 40u)) * 0x1p-10f + float(y) * 0x1p-12f;
    LightVolumeMesh mesh;
    checkVolume("crease", volumeSetup(r, 0.0), depth, light, &mesh);
    CHECK(mesh.floor_triangles < 2 * r * r / 5);  // a column of unit cells along the crease, graded away
    MESSAGE("crease at 64^2: ", mesh.floor_triangles, " floor triangles (static ", 2 * r * r, "), ", mesh.leaves, " leaves, ",
            mesh.stitched_leaves, " stitched");
}

TEST_CASE("light volume: a saddle (zero Laplacian) is subdivided; the flatness bound holds") {
    const TestLight light = testLight();
    const uint32_t r = 32;
    std::vector<float> depth(size_t(r) * r);
    for (uint32_t y = 0; y < r; ++y)
        for (uint32_t x = 0; x < r; ++x)
            depth[size_t(y) * r + x] = 0.5f + (float(x) - 16.0f) * (float(y) - 16.0f) * 0x1p-12f;  // z = xy: Laplacian 0
    for (double flatness : {0.0, 1e-3, 1e-2, 0.3}) {
        LightVolumeMesh mesh;
        checkVolume("saddle", volumeSetup(r, flatness), depth, light, &mesh);
        if (flatness == 0.0) CHECK(mesh.leaves > 1);
        if (flatness == 0.3) CHECK(mesh.leaves == 1);  // the root's fourth corner is 4 * 16.5^2 * 2^-12 = 0.266 off its plane
        MESSAGE("saddle 32^2, flatness ", flatness, ": ", mesh.floor_triangles, " floor triangles");
    }
}

TEST_CASE("light volume: random maps (steps, ramps, noise, constant 0 and 1) are closed at every flatness") {
    const uint32_t seed = penumbra::test::testSeed(11);
    std::mt19937 rng(seed);
    const TestLight light = testLight();
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    uint64_t cases = 0, leaves = 0, stitched = 0;
    for (uint32_t r : {2u, 4u, 8u, 16u, 32u, 64u}) {
        for (int trial = 0; trial < 40; ++trial) {
            std::vector<float> depth(size_t(r) * r);
            const int kind = trial % 5;
            // A few discs of a nearer depth over a tilted plane (casters over a ground), noise, or constants.
            const float a = unit(rng) * 0x1p-6f, b = unit(rng) * 0x1p-6f;
            std::vector<glm::vec3> discs(1 + rng() % 4);
            for (glm::vec3& d : discs) d = glm::vec3(unit(rng) * r, unit(rng) * r, 1.0f + unit(rng) * r / 4.0f);
            for (uint32_t y = 0; y < r; ++y) {
                for (uint32_t x = 0; x < r; ++x) {
                    float value = 0.6f + a * float(x) / float(r) + b * float(y) / float(r);
                    if (kind == 1 || kind == 2)
                        for (const glm::vec3& d : discs)
                            if (glm::length(glm::vec2(x + 0.5f, y + 0.5f) - glm::vec2(d)) < d.z) value = 0.3f - 0.01f * d.z / float(r);
                    if (kind == 2) value += unit(rng) * 1e-4f;
                    if (kind == 3) value = 1.0f;
                    if (kind == 4) value = trial % 2 ? 0.0f : unit(rng);
                    depth[size_t(y) * r + x] = value;
                }
            }
            const double flatness = (rng() % 3 == 0) ? 0.0 : std::pow(10.0, -1.0 - 5.0 * unit(rng));
            LightVolumeMesh mesh;
            checkVolume("random kind " + std::to_string(kind), volumeSetup(r, flatness), depth, light, &mesh);
            if (kind == 3) CHECK(mesh.leaves == 1);
            ++cases;
            leaves += mesh.leaves;
            stitched += mesh.stitched_leaves;
        }
    }
    MESSAGE("seed ", seed, ": ", cases, " random maps closed, ", leaves, " leaves, ", stitched, " stitched");
}

namespace {

void builtinScenes(uint32_t r, const std::vector<std::string>& names) {
    for (const std::string& name : names) {
        const SceneMap map = sceneMap(name, r);
        LightVolumeMesh adaptive, exact, coarse, fixed;
        checkVolume(name + " static", volumeSetup(r, 0.0, LightVolumeTessellation::Static), map.depth, map.light, &fixed);
        checkVolume(name + " adaptive 0", volumeSetup(r, 0.0), map.depth, map.light, &exact);
        checkVolume(name + " adaptive 1e-6", volumeSetup(r, 1e-6), map.depth, map.light, &adaptive);
        checkVolume(name + " adaptive 1e-4", volumeSetup(r, 1e-4), map.depth, map.light, &coarse);
        MESSAGE(name, " ", r, "^2 floor triangles: static ", fixed.floor_triangles, ", adaptive flatness 0: ", exact.floor_triangles,
                " (", 100.0 * exact.floor_triangles / fixed.floor_triangles, " %), 1e-6: ", adaptive.floor_triangles, " (",
                100.0 * adaptive.floor_triangles / fixed.floor_triangles, " %), 1e-4: ", coarse.floor_triangles, " (",
                100.0 * coarse.floor_triangles / fixed.floor_triangles, " %)");
    }
}

}  // namespace

TEST_CASE("light volume: built-in scenes' shadow maps at 256^2, closed, static and adaptive") {
    builtinScenes(256, {"torus_knot", "columns", "hairball", "grass", "window_wall"});
}

TEST_CASE("light volume: columns at 1024^2") { builtinScenes(1024, {"columns"}); }

TEST_SUITE("stress") {
    TEST_CASE("light volume: every built-in scene at 1024^2 and 2048^2") {
        builtinScenes(1024, {"torus_knot", "hairball", "grass", "window_wall"});
        builtinScenes(2048, {"torus_knot", "columns", "hairball", "grass", "window_wall"});
    }
}
