// GPU light-volume tessellator (penumbra/gl/light_volume.hpp) against its CPU twin: the same lattice
// depths and the same triangles in the same order, bit for bit on drivers whose float and double
// operations are correctly rounded and unfused (llvmpipe); on other drivers the mesh is still
// required to be closed (the watertight checks of light_volume_test on the GPU's mesh).
#include <penumbra/airlight.hpp>
#include <penumbra/gl/light_volume.hpp>
#include <penumbra/gl/state.hpp>
#include <penumbra/light_volume.hpp>
#include <penumbra/reference/light_shafts.hpp>

#include "support/per_frame_contract.hpp"
#include "support/engine_state.hpp"
#include "support/gl_test_support.hpp"
#include "shader_catalog.hpp"
#include "support/light_volume_maps.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <memory>
#include <tuple>
#include <random>
#include <string>
#include <vector>

namespace {

using penumbra::LightVolumeMesh;
using penumbra::LightVolumeOptions;
using penumbra::LightVolumeSetup;
using penumbra::LightVolumeTessellation;
using penumbra::test::volumeSetup;

/// The shadow map as the engine would have it: a 32-bit float depth texture.
struct DepthTexture {
    GLuint id = 0;
    DepthTexture(uint32_t r, const std::vector<float>& depth) : DepthTexture(0, {}, r, r, depth) {}
    DepthTexture(int, const std::vector<float>&, uint32_t w, uint32_t h, const std::vector<float>& depth) {
        glCreateTextures(GL_TEXTURE_2D, 1, &id);
        glTextureStorage2D(id, 1, GL_DEPTH_COMPONENT32F, static_cast<GLsizei>(w), static_cast<GLsizei>(h));
        glTextureSubImage2D(id, 0, 0, 0, static_cast<GLsizei>(w), static_cast<GLsizei>(h), GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
        // A shadow sampler's settings on the texture itself: the tessellator's sampler overrides them.
        glTextureParameteri(id, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
        glTextureParameteri(id, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    }
    ~DepthTexture() { glDeleteTextures(1, &id); }
    DepthTexture(const DepthTexture&) = delete;
    DepthTexture& operator=(const DepthTexture&) = delete;
};

/// The engine's lit image: RGBA32F, cleared to 0; red() reads the airlight back (row-major, bottom-up).
struct LitImage {
    penumbra::gl::Texture texture{GL_TEXTURE_2D};
    uint32_t w, h;
    LitImage(uint32_t width, uint32_t height) : w(width), h(height) {
        glTextureStorage2D(texture.id(), 1, GL_RGBA32F, GLsizei(w), GLsizei(h));
        const float zero[4] = {0, 0, 0, 0};
        glClearTexImage(texture.id(), 0, GL_RGBA, GL_FLOAT, zero);
    }
    std::vector<float> red() const {
        std::vector<glm::vec4> pixels(size_t(w) * h);
        glGetTextureImage(texture.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(16 * pixels.size()), pixels.data());
        std::vector<float> out(pixels.size());
        for (size_t i = 0; i < pixels.size(); ++i) out[i] = pixels[i].r;
        return out;
    }
};

/// The render's view of the shaft scene from `eye` through `camera`.
penumbra::gl::LightVolumeView shaftView(const penumbra::test::ShaftScene& scene, const glm::dmat4& camera, const glm::dvec3& eye) {
    penumbra::gl::LightVolumeView view;
    view.camera_view_projection = camera;
    view.eye = eye;
    view.light_view_projection = scene.view_projection;
    view.light_position = scene.light;
    return view;
}

/// Tessellators by (R, flatness, mode): programs and buffers are load-time objects, reused.
penumbra::gl::LightVolumeTessellator& tessellator(const LightVolumeSetup& setup) {
    static std::map<std::tuple<uint32_t, double, int>, std::unique_ptr<penumbra::gl::LightVolumeTessellator>> cache;
    auto& slot = cache[{setup.resolution, setup.options.flatness, int(setup.options.tessellation)}];
    if (!slot) slot = std::make_unique<penumbra::gl::LightVolumeTessellator>(setup);
    return *slot;
}

uint64_t closedEdgesMismatch(const LightVolumeMesh& mesh) {
    std::map<uint64_t, int> edges;
    for (size_t t = 0; t + 2 < mesh.triangles.size(); t += 3)
        for (int e = 0; e < 3; ++e) ++edges[(uint64_t(mesh.triangles[t + e]) << 32) | mesh.triangles[t + (e + 1) % 3]];
    uint64_t bad = 0;
    for (const auto& [key, count] : edges) {
        const auto twin = edges.find((key << 32) | (key >> 32));
        bad += count != 1 || twin == edges.end() || twin->second != 1;
    }
    return bad;
}

/// GPU vs CPU on one map; returns the GPU's triangle count.
uint64_t compare(const std::string& what, const LightVolumeSetup& setup, const std::vector<float>& depth, bool exact_driver) {
    INFO(what << ", R = " << setup.resolution << ", flatness = " << setup.options.flatness
              << (setup.options.tessellation == LightVolumeTessellation::Static ? ", static" : ", adaptive"));
    const std::vector<float> corners = penumbra::lightVolumeCornerDepths(setup, depth);
    const LightVolumeMesh cpu = penumbra::tessellateLightVolume(setup, corners);
    DepthTexture texture(setup.resolution, depth);
    penumbra::gl::LightVolumeTessellator& gpu = tessellator(setup);
    gpu.tessellate(texture.id);
    const LightVolumeMesh mesh = gpu.readMesh();
    const std::vector<float> gpu_corners = gpu.readCorners();
    CHECK(closedEdgesMismatch(mesh) == 0);
    uint32_t command[4];
    glGetNamedBufferSubData(gpu.indirect().buffer, 0, sizeof(command), command);
    CHECK(command[0] == mesh.triangles.size());
    CHECK(command[1] == 1u);
    if (exact_driver) {
        CHECK(std::memcmp(gpu_corners.data(), corners.data(), 4 * corners.size()) == 0);
        CHECK(mesh.floor_triangles == cpu.floor_triangles);
        REQUIRE(mesh.triangles.size() == cpu.triangles.size());
        size_t first_difference = mesh.triangles.size();
        for (size_t i = 0; i < mesh.triangles.size() && first_difference == mesh.triangles.size(); ++i)
            if (mesh.triangles[i] != cpu.triangles[i]) first_difference = i;
        INFO("first differing vertex word " << first_difference);
        CHECK(first_difference == mesh.triangles.size());
    }
    return mesh.triangleCount();
}

}  // namespace

TEST_CASE("GPU light-volume tessellator == CPU twin: planes, saddles, random maps, static and adaptive") {
    const bool exact = penumbra::test::rendererRoundsCorrectly(penumbra::test::context().renderer());
    const uint32_t seed = penumbra::test::testSeed(21);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    uint64_t maps = 0;
    for (uint32_t r : {2u, 4u, 8u, 32u, 128u}) {
        for (int trial = 0; trial < 8; ++trial) {
            std::vector<float> depth(size_t(r) * r);
            const int kind = trial % 4;
            std::vector<glm::vec3> discs(1 + rng() % 4);
            for (glm::vec3& d : discs) d = glm::vec3(unit(rng) * r, unit(rng) * r, 1.0f + unit(rng) * r / 4.0f);
            for (uint32_t y = 0; y < r; ++y) {
                for (uint32_t x = 0; x < r; ++x) {
                    float value = 0.25f + float(x) * 0x1p-13f + float(y) * 0x1p-14f;  // an exact plane
                    if (kind == 1)
                        for (const glm::vec3& d : discs)
                            if (glm::length(glm::vec2(x + 0.5f, y + 0.5f) - glm::vec2(d)) < d.z) value = 0.2f;
                    if (kind == 2) value = 0.5f + (float(x) - r / 2.0f) * (float(y) - r / 2.0f) * 0x1p-16f;
                    if (kind == 3) value = unit(rng);
                    depth[size_t(y) * r + x] = value;
                }
            }
            const double flatness = trial < 4 ? 0.0 : std::pow(10.0, -2.0 - 4.0 * unit(rng));
            compare("kind " + std::to_string(kind), volumeSetup(r, flatness), depth, exact);
            ++maps;
        }
        std::vector<float> depth(size_t(r) * r, 1.0f);
        compare("static, depth 1", volumeSetup(r, 0.0, LightVolumeTessellation::Static), depth, exact);
    }
    MESSAGE("seed ", seed, ": ", maps, " random maps, GPU == CPU", std::string(exact ? " bit for bit" : " (closed; this driver is not exact)"));
}

TEST_CASE("GPU light-volume tessellator == CPU twin on the built-in scenes' shadow maps (256^2, columns 1024^2)") {
    const bool exact = penumbra::test::rendererRoundsCorrectly(penumbra::test::context().renderer());
    for (const char* name : {"torus_knot", "columns", "hairball", "grass", "window_wall"}) {
        const penumbra::test::SceneMap map = penumbra::test::sceneMap(name, 256);
        const uint64_t adaptive = compare(name, volumeSetup(256, 1e-6), map.depth, exact);
        const uint64_t fixed = compare(name, volumeSetup(256, 0.0, LightVolumeTessellation::Static), map.depth, exact);
        MESSAGE(std::string(name), " 256^2: GPU adaptive (flatness 1e-6) ", adaptive, " triangles, static ", fixed);
    }
    const penumbra::test::SceneMap columns = penumbra::test::sceneMap("columns", 1024);
    compare("columns", volumeSetup(1024, 1e-6), columns.depth, exact);
}

TEST_SUITE("stress") {
    TEST_CASE("GPU light-volume tessellator == CPU twin on every built-in scene at 1024^2 and 2048^2, static and adaptive") {
        const bool exact = penumbra::test::rendererRoundsCorrectly(penumbra::test::context().renderer());
        for (uint32_t r : {1024u, 2048u}) {
            for (const char* name : {"torus_knot", "columns", "hairball", "grass", "window_wall"}) {
                const penumbra::test::SceneMap map = penumbra::test::sceneMap(name, r);
                const uint64_t adaptive = compare(name, volumeSetup(r, 1e-6), map.depth, exact);
                const uint64_t fixed = compare(name, volumeSetup(r, 0.0, LightVolumeTessellation::Static), map.depth, exact);
                MESSAGE(std::string(name), " ", r, "^2: GPU adaptive (flatness 1e-6) ", adaptive, " triangles, static ", fixed, " (",
                        100.0 * double(adaptive) / double(fixed), " %)");
            }
        }
    }
}

TEST_CASE("light-volume tessellator: per-frame contract (no query, read-back, wait or allocation) and load-time errors") {
    penumbra::test::context();
    const LightVolumeSetup setup = volumeSetup(64, 1e-6);
    std::vector<float> depth(64 * 64);
    for (size_t t = 0; t < depth.size(); ++t) depth[t] = (t % 7 == 0) ? 0.3f : 0.8f;
    DepthTexture texture(64, depth);
    penumbra::gl::LightVolumeTessellator gpu(setup);
    gpu.tessellate(texture.id);  // warm-up: lazy driver compiles, first-use state
    glFinish();
    penumbra::test::checkPerFrameContract([&] { gpu.tessellate(texture.id); });
    glBindBuffer(0xDEADu, 0);  // an engine's queued error survives tessellate()
    gpu.tessellate(texture.id);
    CHECK(glGetError() == GL_INVALID_ENUM);
    CHECK(gpu.readMesh().triangles == penumbra::tessellateLightVolume(setup, penumbra::lightVolumeCornerDepths(setup, depth)).triangles);

    // A setup not made by lightVolumeSetup is refused by name.
    LightVolumeSetup bad;
    bad.resolution = 48;
    CHECK_THROWS_WITH_AS(penumbra::gl::LightVolumeTessellator{bad}, doctest::Contains("R = 48"), penumbra::Error);
}

TEST_CASE("GPU airlight.glsl == airlight<double> (table: hardware filter and fetch; quadrature 8 / 16 / 32 nodes, isotropic and HG)") {
    const bool exact = penumbra::test::rendererRoundsCorrectly(penumbra::test::context().renderer());
    const uint32_t seed = penumbra::test::testSeed(23);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const penumbra::ShaderLibrary lib = penumbra::test::catalogLibrary();
    struct Variant {
        penumbra::ShaderDefines defines;
        uint32_t nodes;
        bool table;        // penumbraAirlight runs the table (else the quadrature)
        bool filtered;     // the table through the sampler (hardware bilinear)
        double g;
    };
    const Variant variants[] = {{{{"PENUMBRA_AIRLIGHT_NODES", "16"}}, 16, true, true, 0.0},
                                {{{"PENUMBRA_AIRLIGHT_NODES", "8"}, {"AIRLIGHT_TEST_FETCH", "1"}}, 8, true, false, 0.0},
                                {{{"PENUMBRA_AIRLIGHT_NODES", "32"}, {"AIRLIGHT_TEST_QUADRATURE_ONLY", "1"}}, 32, false, false, 0.6}};
    for (const Variant& v : variants) {
        penumbra::AirlightMedium medium;
        medium.sigma_s = 0.05;
        medium.sigma_t = 0.08;
        medium.hg_g = v.g;
        penumbra::AirlightOptions options;
        options.quadrature_nodes = v.nodes;
        options.method = v.table ? penumbra::AirlightMethod::Table : penumbra::AirlightMethod::Quadrature;
        const penumbra::AirlightSetup setup = penumbra::airlightSetup(medium, 10.0, options);
        penumbra::AirlightOptions quadrature_options = options;
        quadrature_options.method = penumbra::AirlightMethod::Quadrature;
        const penumbra::AirlightSetup quadrature = penumbra::airlightSetup(medium, 10.0, quadrature_options);
        const uint32_t count = 2000;
        std::vector<glm::vec4> queries;
        std::vector<glm::dvec3> eyes, dirs, lights;
        std::vector<double> ts;
        for (uint32_t q = 0; q < count; ++q) {
            // Eye at the origin (the float convention), a light within 20 units, rays in any direction.
            const glm::dvec3 light(40.0 * unit(rng) - 20.0, 20.0 * unit(rng) - 5.0, 40.0 * unit(rng) - 20.0);
            glm::dvec3 dir(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
            dir = glm::normalize(glm::dvec3(glm::vec3(glm::normalize(dir))));  // what the float shader sees
            const double t = 60.0 * unit(rng) * unit(rng) + 1e-3;
            const glm::vec3 fdir(dir), flight(light);
            queries.emplace_back(0.0f, 0.0f, 0.0f, float(t));
            queries.emplace_back(fdir, 0.0f);
            queries.emplace_back(flight, 0.0f);
            eyes.emplace_back(0.0);
            dirs.push_back(glm::dvec3(fdir));
            lights.push_back(glm::dvec3(flight));
            ts.push_back(double(float(t)));
        }
        const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("light_volume/airlight_test.comp.glsl", v.defines, lib);
        penumbra::gl::Buffer query_buffer = penumbra::gl::Buffer::fromVector(queries), results(8ull * count);
        penumbra::gl::Buffer table_buffer = penumbra::gl::Buffer::fromVector(setup.table.empty() ? std::vector<float>(1, 0.0f) : setup.table);
        GLuint texture = 0;
        glCreateTextures(GL_TEXTURE_2D, 1, &texture);
        glTextureStorage2D(texture, 1, GL_R32F, GLsizei(setup.tableWidth()), GLsizei(setup.tableHeight()));
        if (!setup.table.empty())
            glTextureSubImage2D(texture, 0, 0, 0, GLsizei(setup.tableWidth()), GLsizei(setup.tableHeight()), GL_RED, GL_FLOAT,
                                setup.table.data());
        glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTextureParameteri(texture, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTextureParameteri(texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glUseProgram(program.id());
        glBindTextureUnit(0, texture);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, table_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, query_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, results.id());
        const glm::vec4 shader_medium = setup.shaderMedium(), shader_params = setup.shaderParams();
        glUniform4fv(0, 1, &shader_medium.x);
        glUniform4fv(1, 1, &shader_params.x);
        glUniform1ui(2, count);
        glDispatchCompute((count + 63) / 64, 1, 1);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        std::vector<glm::vec2> out(count);
        glGetNamedBufferSubData(results.id(), 0, GLsizeiptr(8ull * count), out.data());
        glDeleteTextures(1, &texture);
        double worst = 0.0, worst_quadrature = 0.0, worst_twin = 0.0;
        for (uint32_t q = 0; q < count; ++q) {
            // Errors relative to the whole ray's airlight (the table's documented scale).
            const double whole = penumbra::airlight<double>(quadrature, eyes[q], dirs[q], lights[q], 1e18);
            const double main = penumbra::airlight<double>(setup, eyes[q], dirs[q], lights[q], ts[q]);
            const double quad = penumbra::airlight<double>(quadrature, eyes[q], dirs[q], lights[q], ts[q]);
            if (!(whole > 0.0)) continue;
            worst = std::max(worst, std::abs(double(out[q].x) - main) / whole);
            worst_quadrature = std::max(worst_quadrature, std::abs(double(out[q].y) - quad) / whole);
            const float twin = penumbra::airlight<float>(setup, glm::vec3(0.0f), glm::vec3(dirs[q]), glm::vec3(lights[q]), float(ts[q]));
            worst_twin = std::max(worst_twin, std::abs(double(out[q].x) - double(twin)) / whole);
        }
        INFO("nodes " << v.nodes << (v.table ? (v.filtered ? ", table (hardware filter)" : ", table (fetch)") : ", quadrature") << ", g "
                      << v.g);
        MESSAGE("seed ", seed, ", nodes ", v.nodes, ", g ", v.g, ": max |GPU - CPU| / A(inf): main vs double ", worst,
                ", vs the float twin ", worst_twin, "; quadrature vs double ", worst_quadrature);
        // The GPU sits ~2e-5 of A(inf) below the CPU (float and double alike) on llvmpipe: its exp and
        // atan are not correctly rounded (GLSL allows atan 4096 ulp), so the bound is llvmpipe's;
        // other drivers get a 10x looser one.
        const double bound = exact ? 1e-4 : 1e-3;
        CHECK(worst <= bound);
        CHECK(worst_quadrature <= bound);
        CHECK(worst_twin <= bound);
    }
}

namespace {

/// The shaft scene rendered by the GPU (tessellator + renderer) into an RGBA32F image, the camera's
/// depth from `scene_depth` (distance along each pixel ray, converted to window depth in float).
std::vector<float> renderShafts(const penumbra::test::ShaftScene& scene, const penumbra::AirlightSetup& airlight, const glm::dvec3& eye,
                                const glm::dvec3& target, uint32_t w, uint32_t h, const std::vector<double>& scene_depth,
                                std::vector<double>* used_depth) {
    penumbra::LightVolumeOptions options;
    options.flatness = 1e-6;
    const LightVolumeSetup setup = penumbra::lightVolumeSetup(scene.r, options);
    DepthTexture shadow_map(scene.r, scene.depth);
    penumbra::gl::LightVolumeTessellator& tessellator_ = tessellator(setup);
    tessellator_.tessellate(shadow_map.id);
    const glm::dmat4 camera = penumbra::test::cameraViewProjection(eye, target, w, h);
    const std::vector<glm::dvec3> dirs = penumbra::test::rays(eye, target, w, h);
    std::vector<float> window(size_t(w) * h, 1.0f);
    const glm::dmat4 inverse = glm::inverse(camera);
    for (size_t i = 0; i < dirs.size(); ++i) {
        if (scene_depth[i] >= 1e6) continue;
        const glm::dvec4 clip = camera * glm::dvec4(eye + scene_depth[i] * dirs[i], 1.0);
        window[i] = float(0.5 * clip.z / clip.w + 0.5);
    }
    if (used_depth) {  // the distance the GPU will reconstruct from the float window depth
        used_depth->assign(dirs.size(), 1e18);
        for (size_t i = 0; i < dirs.size(); ++i) {
            if (window[i] >= 1.0f) continue;
            const glm::dvec4 p = inverse * glm::dvec4(2.0 * (i % w + 0.5) / w - 1.0, 2.0 * (i / w + 0.5) / h - 1.0, 2.0 * window[i] - 1.0, 1.0);
            (*used_depth)[i] = glm::length(glm::dvec3(p) / p.w - eye);
        }
    }
    DepthTexture camera_depth(0, {}, w, h, window);
    LitImage lit(w, h);
    penumbra::gl::LightVolumeRenderer renderer(w, h, airlight);
    renderer.render(tessellator_, shaftView(scene, camera, eye), camera_depth.id, lit.texture.id());
    return lit.red();
}

penumbra::reference::ShadowMapLookup ShadowMapLookupNearest() { return penumbra::reference::ShadowMapLookup::Nearest; }

penumbra::AirlightSetup tableFog() {
    penumbra::AirlightMedium medium;
    medium.sigma_s = 0.08;
    medium.sigma_t = 0.1;
    return penumbra::airlightSetup(medium, 50.0);
}

}  // namespace

TEST_CASE("GPU light-volume render == its CPU twin (crossings of the volume, clamped to the scene), and the wall cancels the shafts") {
    penumbra::test::context();
    const penumbra::test::ShaftScene with = penumbra::test::shaftScene(true), without = penumbra::test::shaftScene(false);
    const penumbra::AirlightSetup airlight = tableFog();
    const uint32_t w = 64, h = 48;
    const glm::dvec3 eye(5.0, 1.5, 6.0), target(0.0, 1.0, 0.0);
    const std::vector<glm::dvec3> dirs = penumbra::test::rays(eye, target, w, h);
    std::vector<double> ground(dirs.size());
    for (size_t i = 0; i < dirs.size(); ++i) ground[i] = penumbra::test::groundDepth(eye, dirs[i], 1e9);
    std::vector<double> used;
    const std::vector<float> gpu = renderShafts(with, airlight, eye, target, w, h, ground, &used);
    // The CPU twin on the same mesh, depths and airlight (double).
    penumbra::LightVolumeOptions options;
    options.flatness = 1e-6;
    const LightVolumeSetup setup = penumbra::lightVolumeSetup(with.r, options);
    const std::vector<float> corners = penumbra::lightVolumeCornerDepths(setup, with.depth);
    const penumbra::reference::LightVolumeRaycaster twin(penumbra::tessellateLightVolume(setup, corners), corners, with.inverse, with.light);
    double peak = 0.0, worst = 0.0;
    std::vector<double> errors;
    for (size_t i = 0; i < dirs.size(); ++i) {
        const auto cumulative = [&](double t) { return penumbra::airlight<double>(airlight, eye, dirs[i], with.light, t); };
        const double cpu = twin.airlight(eye, dirs[i], used[i], 200.0, cumulative);
        peak = std::max(peak, cpu);
        errors.push_back(std::abs(double(gpu[i]) - cpu));
    }
    std::vector<double> sorted = errors;
    std::sort(sorted.begin(), sorted.end());
    worst = sorted.back();
    const double p99 = sorted[sorted.size() * 99 / 100];
    MESSAGE(w, "x", h, " pixels: peak airlight ", peak, ", |GPU - CPU twin| 99th percentile ", p99, ", max ", worst);
    CHECK(peak > 0.0);
    CHECK(p99 <= 2e-3 * peak);   // float positions and airlight against double
    CHECK(worst <= 0.05 * peak);  // a pixel centre on a volume edge: rasterization and the ray cast may disagree

    // A wall at z = 3 in front of the shaft: the images with and without the caster are the same.
    std::vector<double> walled(dirs.size());
    for (size_t i = 0; i < dirs.size(); ++i) walled[i] = std::min(ground[i], dirs[i].z < 0.0 ? (3.0 - eye.z) / dirs[i].z : 1e9);
    const std::vector<float> a = renderShafts(with, airlight, eye, target, w, h, walled, nullptr);
    const std::vector<float> b = renderShafts(without, airlight, eye, target, w, h, walled, nullptr);
    const std::vector<float> open_b = renderShafts(without, airlight, eye, target, w, h, ground, nullptr);
    double wall_difference = 0.0, open_difference = 0.0;
    for (size_t i = 0; i < a.size(); ++i) {
        wall_difference = std::max(wall_difference, double(std::abs(a[i] - b[i])));
        open_difference = std::max(open_difference, double(std::abs(gpu[i] - open_b[i])));
    }
    MESSAGE("behind a wall: max |shafts - none| ", wall_difference, "; without the wall ", open_difference);
    CHECK(open_difference > 1e-3 * peak);
    CHECK(wall_difference <= 1e-6 * peak);  // blending order only (the crossings in front are the same surfaces)
}

TEST_CASE("GPU light-volume render: the engine's raster state (scissor, colour mask, clip control, ...) changes no pixel") {
    // The accumulation clear obeys the scissor test and the colour mask, the volume's draw the
    // polygon mode, clip planes and clip control (whose origin flips gl_FrontFacing, the sign of a
    // crossing): render() sets them (penumbra::gl::setPassRasterState).
    penumbra::test::context();
    const penumbra::test::ShaftScene scene = penumbra::test::shaftScene(true);
    const penumbra::AirlightSetup airlight = tableFog();
    const uint32_t w = 64, h = 48;
    const glm::dvec3 eye(5.0, 1.5, 6.0), target(0.0, 1.0, 0.0);
    const std::vector<glm::dvec3> dirs = penumbra::test::rays(eye, target, w, h);
    std::vector<double> ground(dirs.size());
    for (size_t i = 0; i < dirs.size(); ++i) ground[i] = penumbra::test::groundDepth(eye, dirs[i], 1e9);
    penumbra::test::setDefaultState();
    const std::vector<float> reference = renderShafts(scene, airlight, eye, target, w, h, ground, nullptr);
    penumbra::test::setHostileState();
    glBlendFuncSeparatei(0, GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ZERO);
    glBlendEquationSeparatei(0, GL_FUNC_SUBTRACT, GL_MAX);
    glUseProgram(0);  // the last render's programs died with its renderer: not the engine's to get back
    const std::vector<double> before = penumbra::test::rasterStateSnapshot();
    std::vector<float> hostile;
    {
        penumbra::gl::StateSave saved;  // and the engine gets all of it back
        hostile = renderShafts(scene, airlight, eye, target, w, h, ground, nullptr);
    }
    {
        const std::vector<double> after = penumbra::test::rasterStateSnapshot();
        REQUIRE(after.size() == before.size());
        for (size_t i = 0; i < before.size(); ++i) {
            CAPTURE(i);
            CHECK(after[i] == before[i]);
        }
        const GLenum error = glGetError();
        CHECK(error == GL_NO_ERROR);
    }
    penumbra::test::setDefaultState();
    glBlendFuncSeparatei(0, GL_ONE, GL_ZERO, GL_ONE, GL_ZERO);
    glBlendEquationSeparatei(0, GL_FUNC_ADD, GL_FUNC_ADD);
    REQUIRE(reference.size() == hostile.size());
    size_t differing = 0, lit = 0;
    for (size_t i = 0; i < reference.size(); ++i) {
        differing += std::memcmp(&reference[i], &hostile[i], sizeof(float)) != 0;
        lit += reference[i] > 0.0f;
    }
    MESSAGE(differing, " of ", reference.size(), " pixels differ under the engine's state");
    CHECK(lit > 0);
    CHECK(differing == 0);
}

TEST_CASE("GPU ray-march baseline == its CPU twin (reference::rayMarchExact, nearest texel), and converges to the volume") {
    penumbra::test::context();
    const penumbra::test::ShaftScene scene = penumbra::test::shaftScene(true);
    const penumbra::AirlightSetup airlight = tableFog();
    const uint32_t w = 48, h = 36, steps = 256;
    const glm::dvec3 eye(5.0, 1.5, 6.0), target(0.0, 1.0, 0.0);
    const glm::dmat4 camera = penumbra::test::cameraViewProjection(eye, target, w, h);
    const std::vector<glm::dvec3> dirs = penumbra::test::rays(eye, target, w, h);
    std::vector<float> window(dirs.size(), 1.0f);
    std::vector<double> used(dirs.size(), 1e18);
    const glm::dmat4 inverse = glm::inverse(camera);
    for (size_t i = 0; i < dirs.size(); ++i) {
        const double ground = penumbra::test::groundDepth(eye, dirs[i], 1e9);
        if (ground >= 1e6) continue;
        const glm::dvec4 clip = camera * glm::dvec4(eye + ground * dirs[i], 1.0);
        window[i] = float(0.5 * clip.z / clip.w + 0.5);
        const glm::dvec4 p = inverse * glm::dvec4(2.0 * (i % w + 0.5) / w - 1.0, 2.0 * (i / w + 0.5) / h - 1.0, 2.0 * window[i] - 1.0, 1.0);
        used[i] = glm::length(glm::dvec3(p) / p.w - eye);
    }
    DepthTexture shadow_map(scene.r, scene.depth), camera_depth(0, {}, w, h, window);
    LitImage lit(w, h);
    penumbra::gl::LightVolumeRenderer renderer(w, h, airlight);
    renderer.rayMarch(shadow_map.id, scene.r, steps, shaftView(scene, camera, eye), camera_depth.id, lit.texture.id());
    const std::vector<float> pixels = lit.red();
    penumbra::reference::ShadowMapView map;
    map.view_projection = scene.view_projection;
    map.resolution = scene.r;
    map.depth = &scene.depth;
    std::vector<double> errors;
    double peak = 0.0;
    for (size_t i = 0; i < dirs.size(); ++i) {
        const auto [t_in, t_out] = penumbra::reference::frustumInterval(map, eye, dirs[i], std::min(used[i], 1e6));
        const double cpu = penumbra::reference::rayMarchExact(
            eye, dirs[i], t_in, t_out, steps,
            [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(map, ShadowMapLookupNearest(), x); },
            [&](double t) { return penumbra::airlight<double>(airlight, eye, dirs[i], scene.light, t); });
        peak = std::max(peak, cpu);
        errors.push_back(std::abs(double(pixels[i]) - cpu));
    }
    std::sort(errors.begin(), errors.end());
    const double p99 = errors[errors.size() * 99 / 100], worst = errors.back();
    MESSAGE(w, "x", h, " pixels, ", steps, " steps: peak ", peak, ", |GPU march - CPU twin| 99th percentile ", p99, ", max ", worst);
    CHECK(peak > 0.0);
    CHECK(p99 <= 1e-3 * peak);
    CHECK(worst <= 0.05 * peak);  // a step midpoint within float rounding of the shadow map's depth
}

TEST_CASE("light-volume renderer: per-frame contract of render() and rayMarch() (no query, read-back, wait or allocation) and load-time errors") {
    penumbra::test::context();
    const penumbra::test::ShaftScene scene = penumbra::test::shaftScene(true);
    const penumbra::AirlightSetup airlight = tableFog();
    const uint32_t w = 32, h = 24;
    const glm::dvec3 eye(5.0, 1.5, 6.0), target(0.0, 1.0, 0.0);
    penumbra::LightVolumeOptions options;
    options.flatness = 1e-6;
    penumbra::gl::LightVolumeTessellator& volume = tessellator(penumbra::lightVolumeSetup(scene.r, options));
    DepthTexture shadow_map(scene.r, scene.depth);
    volume.tessellate(shadow_map.id);
    std::vector<float> window(size_t(w) * h, 1.0f);
    DepthTexture camera_depth(0, {}, w, h, window);
    LitImage image(w, h);
    const GLuint lit = image.texture.id();
    penumbra::gl::LightVolumeRenderer renderer(w, h, airlight);
    const penumbra::gl::LightVolumeView view = shaftView(scene, penumbra::test::cameraViewProjection(eye, target, w, h), eye);
    // Warm-up: lazy driver compiles, first-use state.
    renderer.render(volume, view, camera_depth.id, lit);
    renderer.rayMarch(shadow_map.id, scene.r, 16, view, camera_depth.id, lit);
    glFinish();
    for (int which = 0; which < 2; ++which) {
        INFO((which == 0 ? "render()" : "rayMarch()"));
        const auto frame = [&] {
            if (which == 0) renderer.render(volume, view, camera_depth.id, lit);
            else renderer.rayMarch(shadow_map.id, scene.r, 16, view, camera_depth.id, lit);
        };
        penumbra::test::checkPerFrameContract(frame);
        glBindBuffer(0xDEADu, 0);  // an engine's queued error survives the call
        frame();
        CHECK(glGetError() == GL_INVALID_ENUM);
        CHECK(glGetError() == GL_NO_ERROR);
    }

    // Load-time errors, each naming the value.
    CHECK_THROWS_WITH_AS(penumbra::gl::LightVolumeRenderer(0, 4, airlight), doctest::Contains("viewport 0x4"), penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::gl::LightVolumeRenderer(4, 20000, airlight), doctest::Contains("viewport 4x20000"), penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::gl::LightVolumeRenderer(4, 4, airlight, GL_RGBA8), doctest::Contains("0x8058"), penumbra::Error);
    penumbra::AirlightMedium forward;
    forward.sigma_s = 0.08;
    forward.sigma_t = 0.1;
    forward.hg_g = 0.5;
    CHECK_THROWS_WITH_AS(penumbra::gl::LightVolumeRenderer(4, 4, penumbra::airlightSetup(forward, 50.0)), doctest::Contains("got method 2"),
                         penumbra::Error);
}
