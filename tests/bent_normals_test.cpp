// bent_normals.hpp: adjacency (CSR, degenerate faces left out, welding), the per-vertex l_bend and
// the per-fragment shade; every light-back-facing triangle gets exactly 0 direct light (torus knot,
// ../shared/scenes/spot.obj); welded split vertices give seam-free l_bend. The GLSL twin is
// compared in bent_normals_gl_test.cpp.
#include "penumbra/bent_normals.hpp"
#include "penumbra/scene/obj.hpp"
#include "penumbra/scene/scene.hpp"
#include "penumbra/scene/weld.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <fstream>
#include <random>

using glm::vec3;
using penumbra::test::contains;
using penumbra::test::errorOf;

namespace {

/// Every light-back-facing triangle (all three vertex dots < 0, the arithmetic bentLight uses) gets
/// 0 direct light at random barycentric points, whatever the engine's diffuse term there; returns
/// (back-facing triangles, fragments checked). `l_f` plays the engine: Phong with smooth normals.
std::pair<size_t, size_t> checkBackFaces(const penumbra::scene::Mesh& mesh, const penumbra::BentNormalMesh& bent,
                                         const vec3& light, float radius, uint32_t seed) {
    std::vector<float> l_bend(mesh.positions.size());
    for (uint32_t v = 0; v < l_bend.size(); ++v) l_bend[v] = penumbra::bentLight(bent, v, mesh.positions[v], light, radius);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    size_t back = 0, fragments = 0;
    for (uint32_t f = 0; f < bent.face_count; ++f) {
        const uint32_t i[3] = {mesh.indices[3 * f], mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]};
        const vec3 n(bent.face_normals[f]);
        if (n == vec3(0.0f)) continue;  // degenerate
        bool facing_away = true;
        for (uint32_t v : i) {
            const vec3 l = glm::normalize(light - mesh.positions[v]);
            facing_away &= penumbra::detail::dotRounded(l, n) < 0.0f;
        }
        if (!facing_away) continue;
        ++back;
        for (int k = 0; k < 8; ++k) {
            float a = unit(rng), b = unit(rng);
            if (a + b > 1.0f) a = 1.0f - a, b = 1.0f - b;
            const float c = 1.0f - a - b;
            const float lb = c * l_bend[i[0]] + a * l_bend[i[1]] + b * l_bend[i[2]];
            const vec3 p = c * mesh.positions[i[0]] + a * mesh.positions[i[1]] + b * mesh.positions[i[2]];
            const vec3 normal = glm::normalize(c * mesh.normals[i[0]] + a * mesh.normals[i[1]] + b * mesh.normals[i[2]]);
            const float l_f = glm::dot(normal, glm::normalize(light - p));  // may be > 0: the leak bent normals remove
            REQUIRE(penumbra::bentDirect(lb, l_f) == 0.0f);
            ++fragments;
        }
    }
    return {back, fragments};
}

}  // namespace

TEST_CASE("bent normals: adjacency lists, degenerate faces, face normals") {
    // Two triangles sharing an edge + one degenerate (repeated vertex) + an unused vertex.
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {5, 5, 5}};
    const std::vector<uint32_t> idx = {0, 1, 2, 1, 3, 2, 0, 0, 1};
    const penumbra::BentNormalMesh m = penumbra::bentNormalMesh(p.data(), p.size(), idx.data(), idx.size());
    CHECK(m.vertex_count == 5);
    CHECK(m.face_count == 3);
    CHECK(m.degenerate_faces == 1);
    REQUIRE(m.offsets.size() == 6);
    auto faces = [&](uint32_t v) { return std::vector<uint32_t>(m.faces.begin() + m.offsets[v], m.faces.begin() + m.offsets[v + 1]); };
    CHECK(faces(0) == std::vector<uint32_t>{0});
    CHECK(faces(1) == std::vector<uint32_t>{0, 1});
    CHECK(faces(2) == std::vector<uint32_t>{0, 1});
    CHECK(faces(3) == std::vector<uint32_t>{1});
    CHECK(faces(4).empty());
    CHECK(vec3(m.face_normals[0]) == vec3(0, 0, 1));
    CHECK(m.face_normals[2] == glm::vec4(0.0f));
    CHECK(m.bytes() == (6 + 6) * 4 + 3 * 16);
    // l_bend: toward a light above, both faces face it; no face -> 1; inside the sphere -> -1.
    CHECK(penumbra::bentLight(m, 1, p[1], vec3(0.5f, 0.5f, 3.0f)) > 0.9f);
    CHECK(penumbra::bentLight(m, 1, p[1], vec3(0.5f, 0.5f, -3.0f)) < -0.9f);
    CHECK(penumbra::bentLight(m, 4, p[4], vec3(0, 0, 3)) == 1.0f);
    CHECK(penumbra::bentLight(m, 1, p[1], vec3(1, 0, 0.1f), 0.5f) == -1.0f);
    // A light grazing the plane: toward the centre slightly positive, over the sphere negative.
    const vec3 grazing(10.0f, 0.0f, 0.5f);
    CHECK(penumbra::bentLight(m, 1, p[1], grazing) > 0.0f);
    CHECK(penumbra::bentLight(m, 1, p[1], grazing, 1.0f) < 0.0f);
    // Shade: alpha = clamp(3 l_bend, 0, 1).
    CHECK(penumbra::bentShade(0.5f, 0.7f) == 0.7f);                                  // alpha 1: Phong
    CHECK(penumbra::bentShade(0.1f, 0.7f) == doctest::Approx(0.3f * 0.7f + 0.7f * 0.1f));
    CHECK(penumbra::bentShade(-0.2f, 0.7f) == -0.2f);                                // alpha 0: l_bend
    CHECK(penumbra::bentDirect(-0.2f, 0.7f) == 0.0f);
}

TEST_CASE("bent normals: welding joins split vertices' lists") {
    // A quad split along its diagonal with the diagonal's vertices duplicated (a seam).
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0.5f}, {0, 1, 0}};
    const std::vector<uint32_t> idx = {0, 1, 2, 3, 4, 5};
    const std::vector<uint32_t> weld = penumbra::scene::weldByPosition(p);
    CHECK(weld[1] == weld[3]);
    CHECK(weld[2] == weld[5]);
    CHECK(weld[0] != weld[4]);
    const penumbra::BentNormalMesh split = penumbra::bentNormalMesh(p.data(), p.size(), idx.data(), idx.size());
    const penumbra::BentNormalMesh welded = penumbra::bentNormalMesh(p.data(), p.size(), idx.data(), idx.size(), weld.data());
    CHECK(split.offsets[2] - split.offsets[1] == 1);
    CHECK(welded.offsets[2] - welded.offsets[1] == 2);
    const vec3 light(-2.0f, -2.0f, 1.0f);
    CHECK(penumbra::bentLight(split, 1, p[1], light) != penumbra::bentLight(split, 3, p[3], light));
    CHECK(penumbra::bentLight(welded, 1, p[1], light) == penumbra::bentLight(welded, 3, p[3], light));
}

TEST_CASE("bent normals: light-back-facing triangles get exactly 0 direct light (torus knot, spot)") {
    const penumbra::scene::Scene knot = penumbra::scene::torusKnot(64, false);
    const penumbra::scene::Mesh& mesh = knot.meshes[0];
    const penumbra::BentNormalMesh bent =
        penumbra::bentNormalMesh(mesh.positions.data(), mesh.positions.size(), mesh.indices.data(), mesh.indices.size());
    for (const float radius : {0.0f, knot.light.radius}) {
        const auto [back, fragments] = checkBackFaces(mesh, bent, knot.light.position, radius, 7);
        MESSAGE("torus knot, radius " << radius << ": " << back << " back-facing triangles, " << fragments
                                      << " fragments, all 0");
        CHECK(back > mesh.triangleCount() / 4);
    }
    const std::string spot = std::string(PENUMBRA_SHARED_SCENES_DIR) + "/spot.obj";
    if (!std::ifstream(spot)) {
        MESSAGE("skipped spot.obj: " << spot << " not found (../shared absent)");
        return;
    }
    const penumbra::scene::Scene scene = penumbra::scene::loadObj(spot);
    const penumbra::scene::Mesh merged = scene.merged();
    const std::vector<uint32_t> weld = penumbra::scene::weldByPosition(merged.positions);
    const penumbra::BentNormalMesh spot_bent = penumbra::bentNormalMesh(merged.positions.data(), merged.positions.size(),
                                                                        merged.indices.data(), merged.indices.size(),
                                                                        weld.data());
    const auto [back, fragments] = checkBackFaces(merged, spot_bent, scene.light.position, scene.light.radius, 9);
    MESSAGE("spot.obj: " << back << " back-facing triangles, " << fragments << " fragments, all 0");
    CHECK(back > 0);
    // Seams: loadObj already shares a vertex per position, so split every vertex per triangle (what
    // per-face UVs or normals do to an OBJ) and weld the copies back by position. Unwelded, copies
    // see only their own face (a visible seam); welded, copies of one position have identical l_bend.
    penumbra::scene::Mesh split;
    for (uint32_t i : merged.indices) {
        split.indices.push_back(static_cast<uint32_t>(split.positions.size()));
        split.positions.push_back(merged.positions[i]);
    }
    const std::vector<uint32_t> split_weld = penumbra::scene::weldByPosition(split.positions);
    const penumbra::BentNormalMesh unwelded = penumbra::bentNormalMesh(split.positions.data(), split.positions.size(),
                                                                       split.indices.data(), split.indices.size());
    const penumbra::BentNormalMesh rewelded = penumbra::bentNormalMesh(split.positions.data(), split.positions.size(),
                                                                       split.indices.data(), split.indices.size(),
                                                                       split_weld.data());
    float worst_unwelded = 0.0f, worst_welded = 0.0f;
    const glm::vec3 light = scene.light.position;
    std::vector<uint32_t> first_copy(split.positions.size(), UINT32_MAX);  // weld id -> its first vertex
    for (uint32_t v = 0; v < split.positions.size(); ++v)
        if (first_copy[split_weld[v]] == UINT32_MAX) first_copy[split_weld[v]] = v;
    for (uint32_t v = 0; v < split.positions.size(); ++v) {
        const uint32_t w = first_copy[split_weld[v]];  // another copy of v's position
        const glm::vec3 p = split.positions[v];
        worst_unwelded = std::max(worst_unwelded, std::abs(penumbra::bentLight(unwelded, v, p, light) -
                                                           penumbra::bentLight(unwelded, w, p, light)));
        worst_welded = std::max(worst_welded, std::abs(penumbra::bentLight(rewelded, v, p, light) -
                                                       penumbra::bentLight(rewelded, w, p, light)));
        REQUIRE(penumbra::bentLight(rewelded, v, p, light) == penumbra::bentLight(spot_bent, merged.indices[v], p, light));
    }
    MESSAGE("spot.obj split per triangle (" << split.positions.size() << " vertices): largest l_bend step across copies "
                                            << worst_unwelded << " unwelded, " << worst_welded << " welded");
    CHECK(worst_unwelded > 1.0f / 255.0f);
    CHECK(worst_welded == 0.0f);
}

TEST_CASE("bent normals: bad input") {
    const std::vector<vec3> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    const std::vector<uint32_t> idx = {0, 1, 2}, bad = {0, 1, 3};
    CHECK(contains(errorOf([&] { penumbra::bentNormalMesh(p.data(), 3, idx.data(), 2); }), "not a multiple of 3"));
    CHECK(contains(errorOf([&] { penumbra::bentNormalMesh(p.data(), 3, bad.data(), 3); }), "index 2 is 3"));
    const std::vector<vec3> nan = {{0, 0, 0}, {1, std::nanf(""), 0}, {0, 1, 0}};
    CHECK(contains(errorOf([&] { penumbra::bentNormalMesh(nan.data(), 3, idx.data(), 3); }), "vertex 1 is not finite"));
    const std::vector<uint32_t> weld = {0, 7, 2};
    CHECK(contains(errorOf([&] { penumbra::bentNormalMesh(p.data(), 3, idx.data(), 3, weld.data()); }), "weld id 7"));
    // Empty meshes are fine: no faces, every vertex plain Phong.
    const penumbra::BentNormalMesh empty = penumbra::bentNormalMesh(p.data(), 3, nullptr, 0);
    CHECK(empty.faces.empty());
    CHECK(penumbra::bentLight(empty, 0, p[0], vec3(0, 0, 5)) == 1.0f);
}
