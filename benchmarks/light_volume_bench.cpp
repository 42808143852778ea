// Light-volume tessellator (penumbra/gl/light_volume.hpp, billeter2010): adaptive against static
// tessellation of the built-in scenes' shadow maps at 512^2, 1024^2 and 2048^2.
//
// Input: the scene rendered into a 32-bit float depth texture from a spot light framing the casters
// and the ground around them (1.5x their box), as an engine's shadow pass would.
//
// Entries BM_LightVolume/<scene>/<R>/<mode>, mode = static | adaptive_1e-6 | adaptive_1e-4 (the
// flatness: the adaptive floor stays within 2 * flatness of the static one in post-projective depth).
// Counters:
//   edge_map_ms, tessellate_ms, total_ms  GPU stages (median of 3): lattice depths + the flags of
//                                         every level with closure and restriction (the seed's
//                                         Laplacian, edge map and its mip hierarchy), counts + scan +
//                                         emission + command (timeGpu's method: GL_TIME_ELAPSED
//                                         where it measures, else glFinish + wall clock, e.g. llvmpipe)
//   cpu_ms                                the CPU twin (lattice depths + tessellateLightVolume), once
//   triangles, floor_triangles            the mesh the GPU emitted (== the CPU twin's)
//   triangles_vs_static                   triangles / the static tessellation's (2 R^2 + 4 R)
//   err_floor_max                         lightVolumeFloorError: the floor's largest deviation from the
//                                         static surface, post-projective depth
//   gpu_equals_cpu                        1 when the GPU mesh equals the CPU twin's, word for word
//   render_ms                             the volume drawn over the camera's depth and composited
//                                         (LightVolumeRenderer::render), 256 x 192, median of 3
//   volume_ms                             total_ms + render_ms: what a frame pays for its shafts
//   err_rmse                              the rendered airlight against the converged ray march of
//                                         the same shadow map (CPU, 1024 steps, each lit step exact)
// Entries BM_LightVolumeRayMarch/<scene>/<R>/<steps>, steps = 64 | 256 | 1024: the baseline an
// engine would run instead (LightVolumeRenderer::rayMarch, GPU), march_ms and err_rmse against the
// same converged march. The fog: sigma_s 0.05, sigma_t 0.08, isotropic (the table).
// Entries BM_AirlightTable/<method>: airlight() on the CPU, the same 2000 random rays for every
// method (eye at the origin, light in [-3, 3]^3, sigma_t log-uniform in [0.01, 5], sigma_s in
// [0.2, 1] sigma_t, t log-uniform in [0.01, 30] or infinite one time in five), against
// airlightReference (adaptive Gauss-Kronrod in double, 1e-10): method = table_WxH (isotropic, the
// table's size: the GPU's R32F texture) or quadrature_N[_hgG] (N Gauss-Legendre nodes per panel;
// hg 0.6: forward scattering, which the table cannot hold). Counters: ns_double, ns_float (per
// evaluation, median of 5 passes), err_rel_max / err_rel_rms (|A - ref| / ref, double),
// err_ainf_max (|A - ref| / A(inf), the size of the terms a render adds: double; err_float_ainf_max
// in float), table_bytes.
// PENUMBRA_BENCH_SMOKE=1: one scene at 64^2, 100 airlight rays.
#include "bench_common.hpp"

#include <penumbra/airlight.hpp>
#include <penumbra/gl/light_volume.hpp>
#include <penumbra/light_volume.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/light_shafts.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace {

using penumbra::bench::glContext;

/// The scene's shadow map at R^2 (depth texture and its floats), cached per (scene, R).
struct ShadowMap {
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    std::vector<float> depth;
    glm::dmat4 light_view_projection{1.0};
    glm::dvec3 light_position{0.0};
};

const ShadowMap& shadowMap(const std::string& name, uint32_t r) {
    static std::map<std::pair<std::string, uint32_t>, ShadowMap> cache;
    ShadowMap& map = cache[{name, r}];
    if (map.gbuffer) return map;
    glContext();
    const penumbra::scene::Scene scene = penumbra::scene::builtin(name);
    penumbra::scene::Bounds box;
    for (size_t m = scene.meshes.size() > 1 ? 1 : 0; m < scene.meshes.size(); ++m) box.extend(scene.meshes[m].bounds());
    const glm::vec3 centre = box.center(), half = 0.75f * (box.max - box.min);
    const glm::mat4 light = penumbra::lightViewProjectionForBounds(glm::vec4(scene.light.position, 1.0f), centre - half, centre + half);
    const penumbra::scene::GpuScene gpu_scene(scene);
    map.light_view_projection = glm::dmat4(light);
    map.light_position = glm::dvec3(scene.light.position);
    map.gbuffer = std::make_unique<penumbra::scene::GBuffer>(r, r);
    map.gbuffer->render(gpu_scene, light);
    map.depth.resize(size_t(r) * r);
    glGetTextureImage(map.gbuffer->depthTexture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(4 * map.depth.size()),
                      map.depth.data());
    return map;
}

constexpr uint32_t kViewWidth = 256, kViewHeight = 192;

penumbra::AirlightSetup benchFog() {
    penumbra::AirlightMedium medium;
    medium.sigma_s = 0.05;
    medium.sigma_t = 0.08;
    return penumbra::airlightSetup(medium, 10.0);
}

/// The camera's depth (a G-buffer pass) and, per pixel (bottom-up), its ray and scene distance.
struct CameraView {
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    glm::dmat4 view_projection{1.0};
    glm::dvec3 eye{0.0};
    std::vector<glm::dvec3> dirs;
    std::vector<double> distance;
};

const CameraView& cameraView(const std::string& name) {
    static std::map<std::string, CameraView> cache;
    CameraView& v = cache[name];
    if (v.gbuffer) return v;
    const uint32_t w = penumbra::bench::smokeRun() ? 32 : kViewWidth, h = penumbra::bench::smokeRun() ? 24 : kViewHeight;
    const penumbra::scene::Scene scene = penumbra::scene::builtin(name);
    v.eye = glm::dvec3(scene.camera.eye);
    v.view_projection = glm::dmat4(scene.camera.projection(float(w) / float(h))) * glm::dmat4(scene.camera.view());
    const penumbra::scene::GpuScene gpu_scene(scene);
    v.gbuffer = std::make_unique<penumbra::scene::GBuffer>(w, h);
    v.gbuffer->render(gpu_scene, glm::mat4(v.view_projection));
    std::vector<float> depth(size_t(w) * h);
    glGetTextureImage(v.gbuffer->depthTexture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(4 * depth.size()), depth.data());
    const glm::dmat4 inverse = glm::inverse(v.view_projection);
    for (size_t i = 0; i < depth.size(); ++i) {
        const double x = 2.0 * (i % w + 0.5) / w - 1.0, y = 2.0 * (i / w + 0.5) / h - 1.0;
        const glm::dvec4 far_point = inverse * glm::dvec4(x, y, 1.0, 1.0);
        v.dirs.push_back(glm::normalize(glm::dvec3(far_point) / far_point.w - v.eye));
        const glm::dvec4 p = inverse * glm::dvec4(x, y, 2.0 * depth[i] - 1.0, 1.0);
        v.distance.push_back(depth[i] >= 1.0f ? 1e6 : glm::length(glm::dvec3(p) / p.w - v.eye));
    }
    return v;
}

/// The converged ray march of the shadow map (CPU, 1024 steps, nearest texel, each lit step exact).
const std::vector<double>& convergedMarch(const std::string& name, uint32_t r) {
    static std::map<std::pair<std::string, uint32_t>, std::vector<double>> cache;
    std::vector<double>& out = cache[{name, r}];
    if (!out.empty()) return out;
    const ShadowMap& map = shadowMap(name, r);
    const CameraView& v = cameraView(name);
    const penumbra::AirlightSetup fog = benchFog();
    penumbra::reference::ShadowMapView view;
    view.view_projection = map.light_view_projection;
    view.resolution = r;
    view.depth = &map.depth;
    out.assign(v.dirs.size(), 0.0);
    const unsigned threads = std::max(1u, std::thread::hardware_concurrency());
    std::vector<std::thread> pool;
    for (unsigned t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            for (size_t i = t; i < v.dirs.size(); i += threads) {
                const auto [t_in, t_out] = penumbra::reference::frustumInterval(view, v.eye, v.dirs[i], v.distance[i]);
                out[i] = penumbra::reference::rayMarchExact(
                    v.eye, v.dirs[i], t_in, t_out, 1024,
                    [&](const glm::dvec3& x) { return penumbra::reference::shadowMapLit(view, penumbra::reference::ShadowMapLookup::Nearest, x); },
                    [&](double t) { return penumbra::airlight<double>(fog, v.eye, v.dirs[i], map.light_position, t); });
            }
        });
    for (std::thread& thread : pool) thread.join();
    return out;
}

/// An RGBA32F image the render or the march adds its airlight to, cleared, and its read-back.
struct Canvas {
    penumbra::gl::Texture texture{GL_TEXTURE_2D};
    uint32_t w, h;
    Canvas(uint32_t width, uint32_t height) : w(width), h(height) {
        glTextureStorage2D(texture.id(), 1, GL_RGBA32F, GLsizei(w), GLsizei(h));
    }
    void clear() {
        const float zero[4] = {0, 0, 0, 0};
        glClearTexImage(texture.id(), 0, GL_RGBA, GL_FLOAT, zero);
    }
    double rmse(const std::vector<double>& reference) const {
        std::vector<glm::vec4> pixels(size_t(w) * h);
        glGetTextureImage(texture.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(16 * pixels.size()), pixels.data());
        double sum = 0.0;
        for (size_t i = 0; i < pixels.size(); ++i) sum += (double(pixels[i].r) - reference[i]) * (double(pixels[i].r) - reference[i]);
        return std::sqrt(sum / double(pixels.size()));
    }
};

penumbra::gl::LightVolumeView lightVolumeView(const std::string& name, uint32_t r) {
    const ShadowMap& map = shadowMap(name, r);
    const CameraView& v = cameraView(name);
    penumbra::gl::LightVolumeView view;
    view.camera_view_projection = v.view_projection;
    view.eye = v.eye;
    view.light_view_projection = map.light_view_projection;
    view.light_position = map.light_position;
    return view;
}

void rayMarchEntry(benchmark::State& state, const std::string& name, uint32_t r, uint32_t steps) {
    const ShadowMap& map = shadowMap(name, r);
    const CameraView& v = cameraView(name);
    const std::vector<double>& reference = convergedMarch(name, r);
    const uint32_t w = penumbra::bench::smokeRun() ? 32 : kViewWidth, h = penumbra::bench::smokeRun() ? 24 : kViewHeight;
    Canvas image(w, h);
    penumbra::gl::LightVolumeRenderer renderer(w, h, benchFog());
    const penumbra::gl::LightVolumeView view = lightVolumeView(name, r);
    std::vector<double> times;
    for (auto _ : state) {
        for (int run = 0; run < 3; ++run) {
            image.clear();
            times.push_back(1e3 * penumbra::bench::timeGpu(
                                      [&] { renderer.rayMarch(map.gbuffer->depthTexture(), r, steps, view, v.gbuffer->depthTexture(), image.texture.id()); }));
        }
        state.SetIterationTime(penumbra::bench::median(times) * 1e-3);
    }
    state.counters["march_ms"] = penumbra::bench::median(times);
    state.counters["steps"] = steps;
    state.counters["err_rmse"] = image.rmse(reference);
    penumbra::bench::reportTimer(state);
    state.SetLabel(name + " " + std::to_string(r) + "^2 ray march " + std::to_string(steps) + " steps");
}

void lightVolumeEntry(benchmark::State& state, const std::string& name, uint32_t r, double flatness, bool fixed) {
    const ShadowMap& map = shadowMap(name, r);
    penumbra::LightVolumeOptions options;
    options.flatness = flatness;
    options.tessellation = fixed ? penumbra::LightVolumeTessellation::Static : penumbra::LightVolumeTessellation::Adaptive;
    const penumbra::LightVolumeSetup setup = penumbra::lightVolumeSetup(r, options);
    penumbra::gl::LightVolumeTessellator tessellator(setup);
    const GLuint texture = map.gbuffer->depthTexture();
    tessellator.tessellate(texture);  // warm-up
    penumbra::bench::timeGpu([&] { tessellator.tessellate(texture); });
    tessellator.enableStageTimers(!penumbra::bench::timeElapsedMeasuresNow());
    std::vector<double> edge, tess, total;
    for (auto _ : state) {
        for (int run = 0; run < 3; ++run) {
            const double seconds = penumbra::bench::timeGpu([&] { tessellator.tessellate(texture); });
            const penumbra::gl::LightVolumeStageTimes t = tessellator.stageTimes();
            edge.push_back(t.edge_map);
            tess.push_back(t.tessellate);
            total.push_back(1e3 * seconds);
        }
        state.SetIterationTime(penumbra::bench::median(total) * 1e-3);
    }
    const penumbra::LightVolumeMesh mesh = tessellator.readMesh();
    const CameraView& v = cameraView(name);
    const uint32_t w = penumbra::bench::smokeRun() ? 32 : kViewWidth, h = penumbra::bench::smokeRun() ? 24 : kViewHeight;
    Canvas image(w, h);
    penumbra::gl::LightVolumeRenderer renderer(w, h, benchFog());
    const penumbra::gl::LightVolumeView view = lightVolumeView(name, r);
    std::vector<double> render;
    for (int run = 0; run < 4; ++run) {
        image.clear();
        const double seconds = penumbra::bench::timeGpu([&] { renderer.render(tessellator, view, v.gbuffer->depthTexture(), image.texture.id()); });
        if (run > 0) render.push_back(1e3 * seconds);  // the first: warm-up
    }
    state.counters["render_ms"] = penumbra::bench::median(render);
    state.counters["volume_ms"] = penumbra::bench::median(total) + penumbra::bench::median(render);
    state.counters["err_rmse"] = image.rmse(convergedMarch(name, r));
    const auto start = std::chrono::steady_clock::now();
    const std::vector<float> corners = penumbra::lightVolumeCornerDepths(setup, map.depth);
    const penumbra::LightVolumeMesh cpu = penumbra::tessellateLightVolume(setup, corners);
    const double cpu_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    state.counters["edge_map_ms"] = penumbra::bench::median(edge);
    state.counters["tessellate_ms"] = penumbra::bench::median(tess);
    state.counters["total_ms"] = penumbra::bench::median(total);
    state.counters["cpu_ms"] = cpu_ms;
    state.counters["triangles"] = double(mesh.triangleCount());
    state.counters["floor_triangles"] = double(mesh.floor_triangles);
    state.counters["triangles_vs_static"] = double(mesh.triangleCount()) / double(2.0 * r * r + 4.0 * r);
    state.counters["err_floor_max"] = penumbra::lightVolumeFloorError(mesh, corners);
    state.counters["gpu_equals_cpu"] = mesh.triangles == cpu.triangles ? 1.0 : 0.0;
    penumbra::bench::reportTimer(state);
    state.SetLabel(name + " " + std::to_string(r) + "^2 " + (fixed ? std::string("static") : "flatness " + std::to_string(flatness)));
}

/// One airlight case: a ray from the origin, a light, a medium and a distance.
struct AirlightCase {
    glm::dvec3 dir, light;
    double sigma_s, sigma_t, t;
};

const std::vector<AirlightCase>& airlightCases() {
    static const std::vector<AirlightCase> cases = [] {
        std::mt19937_64 rng(12);
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        std::normal_distribution<double> normal;
        std::vector<AirlightCase> out(penumbra::bench::smokeRun() ? 100 : 2000);
        for (AirlightCase& c : out) {
            c.dir = glm::normalize(glm::dvec3(normal(rng), normal(rng), normal(rng)));
            c.light = glm::dvec3(6 * unit(rng) - 3, 6 * unit(rng) - 3, 6 * unit(rng) - 3);
            c.sigma_t = 0.01 * std::pow(500.0, unit(rng));
            c.sigma_s = (0.2 + 0.8 * unit(rng)) * c.sigma_t;
            c.t = unit(rng) < 0.2 ? std::numeric_limits<double>::infinity() : 0.01 * std::pow(3000.0, unit(rng));
        }
        return out;
    }();
    return cases;
}

/// airlightReference of every case for phase g: A(t) and A(inf), cached per g.
const std::vector<std::pair<double, double>>& airlightReferences(double g) {
    static std::map<double, std::vector<std::pair<double, double>>> cache;
    std::vector<std::pair<double, double>>& out = cache[g];
    if (!out.empty()) return out;
    penumbra::AirlightOptions options;
    options.method = penumbra::AirlightMethod::Quadrature;
    for (const AirlightCase& c : airlightCases()) {
        penumbra::AirlightMedium medium;
        medium.sigma_s = c.sigma_s;
        medium.sigma_t = c.sigma_t;
        medium.hg_g = g;
        const penumbra::AirlightSetup setup = penumbra::airlightSetup(medium, 1.0, options);
        out.emplace_back(penumbra::airlightReference(setup, glm::dvec3(0.0), c.dir, c.light, 0.0, c.t),
                         penumbra::airlightReference(setup, glm::dvec3(0.0), c.dir, c.light, 0.0, penumbra::kAirlightMaxDistance));
    }
    return out;
}

void airlightEntry(benchmark::State& state, const penumbra::AirlightOptions& options, double g) {
    const std::vector<AirlightCase>& cases = airlightCases();
    const auto& reference = airlightReferences(g);
    // One setup per case (the media differ); the table is built once and shared by copy.
    std::vector<penumbra::AirlightSetup> setups;
    penumbra::AirlightMedium first;
    first.sigma_s = first.sigma_t = 1.0;
    first.hg_g = g;
    const penumbra::AirlightSetup base = penumbra::airlightSetup(first, 1.0, options);
    for (const AirlightCase& c : cases) {
        penumbra::AirlightSetup setup = base;
        penumbra::AirlightMedium medium;
        medium.sigma_s = c.sigma_s;
        medium.sigma_t = c.sigma_t;
        medium.hg_g = g;
        penumbra::airlightSetMedium(setup, medium, 1.0);
        setups.push_back(std::move(setup));
    }
    double rel_max = 0, rel_sum2 = 0, ainf_max = 0, float_ainf_max = 0;
    size_t rel_count = 0;
    for (size_t i = 0; i < cases.size(); ++i) {
        const AirlightCase& c = cases[i];
        const double a = penumbra::airlight<double>(setups[i], glm::dvec3(0.0), c.dir, c.light, c.t);
        const float f = penumbra::airlight<float>(setups[i], glm::vec3(0.0f), glm::vec3(c.dir), glm::vec3(c.light), float(c.t));
        const auto [ref, ref_inf] = reference[i];
        if (ref > 0) {
            const double rel = std::abs(a - ref) / ref;
            rel_max = std::max(rel_max, rel);
            rel_sum2 += rel * rel;
            ++rel_count;
        }
        if (ref_inf > 0) {
            ainf_max = std::max(ainf_max, std::abs(a - ref) / ref_inf);
            float_ainf_max = std::max(float_ainf_max, std::abs(double(f) - ref) / ref_inf);
        }
    }
    auto timePass = [&](auto precision) {
        using T = decltype(precision);
        std::vector<double> ns;
        for (int pass = 0; pass < 5; ++pass) {
            T sum = 0;
            const auto start = std::chrono::steady_clock::now();
            for (size_t i = 0; i < cases.size(); ++i)
                sum += penumbra::airlight<T>(setups[i], glm::vec<3, T>(0), glm::vec<3, T>(cases[i].dir), glm::vec<3, T>(cases[i].light),
                                             T(cases[i].t));
            ns.push_back(std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() / double(cases.size()));
            benchmark::DoNotOptimize(sum);
        }
        return penumbra::bench::median(ns);
    };
    double ns_double = 0, ns_float = 0;
    for (auto _ : state) {
        ns_double = timePass(0.0);
        ns_float = timePass(0.0f);
        state.SetIterationTime(ns_double * 1e-9 * double(cases.size()));
    }
    state.counters["ns_double"] = ns_double;
    state.counters["ns_float"] = ns_float;
    state.counters["err_rel_max"] = rel_max;
    state.counters["err_rel_rms"] = rel_count ? std::sqrt(rel_sum2 / double(rel_count)) : 0.0;
    state.counters["err_ainf_max"] = ainf_max;
    state.counters["err_float_ainf_max"] = float_ainf_max;
    state.counters["table_bytes"] = double(base.tableBytes());
    state.counters["rays"] = double(cases.size());
}

const bool kRegistered = [] {
    const bool smoke = penumbra::bench::smokeRun();
    const std::vector<std::string> scenes = smoke ? std::vector<std::string>{"columns"}
                                                  : std::vector<std::string>{"torus_knot", "columns", "hairball", "grass", "window_wall"};
    const std::vector<uint32_t> sizes = smoke ? std::vector<uint32_t>{64} : std::vector<uint32_t>{512, 1024, 2048};
    const std::pair<const char*, double> modes[] = {{"static", 0.0}, {"adaptive_1e-6", 1e-6}, {"adaptive_1e-4", 1e-4}};
    for (const std::string& name : scenes) {
        for (uint32_t r : sizes) {
            for (const auto& [mode, flatness] : modes) {
                const bool fixed = std::string(mode) == "static";
                const std::string entry = "BM_LightVolume/" + name + "/" + std::to_string(r) + "/" + mode;
                benchmark::RegisterBenchmark(entry.c_str(),
                                             [name, r, flatness = flatness, fixed](benchmark::State& st) {
                                                 lightVolumeEntry(st, name, r, flatness, fixed);
                                             })
                    ->UseManualTime()
                    ->Iterations(1)
                    ->Unit(benchmark::kMillisecond);
            }
            for (uint32_t steps : {64u, 256u, 1024u}) {
                const std::string entry = "BM_LightVolumeRayMarch/" + name + "/" + std::to_string(r) + "/" + std::to_string(steps);
                benchmark::RegisterBenchmark(entry.c_str(), [name, r, steps](benchmark::State& st) { rayMarchEntry(st, name, r, steps); })
                    ->UseManualTime()
                    ->Iterations(1)
                    ->Unit(benchmark::kMillisecond);
            }
        }
    }
    struct AirlightMethodEntry {
        std::string name;
        penumbra::AirlightMethod method;
        uint32_t width, height, nodes;
        double g;
    };
    const std::vector<AirlightMethodEntry> methods = {
        {"table_32x32", penumbra::AirlightMethod::Table, 32, 32, 16, 0.0},
        {"table_64x64", penumbra::AirlightMethod::Table, 64, 64, 16, 0.0},
        {"table_128x64", penumbra::AirlightMethod::Table, 128, 64, 16, 0.0},
        {"table_256x128", penumbra::AirlightMethod::Table, 256, 128, 16, 0.0},
        {"quadrature_8", penumbra::AirlightMethod::Quadrature, 128, 64, 8, 0.0},
        {"quadrature_16", penumbra::AirlightMethod::Quadrature, 128, 64, 16, 0.0},
        {"quadrature_32", penumbra::AirlightMethod::Quadrature, 128, 64, 32, 0.0},
        {"quadrature_16_hg0.6", penumbra::AirlightMethod::Quadrature, 128, 64, 16, 0.6},
        {"quadrature_32_hg0.6", penumbra::AirlightMethod::Quadrature, 128, 64, 32, 0.6},
    };
    for (const AirlightMethodEntry& m : methods) {
        if (smoke && m.name != "table_128x64" && m.name != "quadrature_16") continue;
        penumbra::AirlightOptions options;
        options.method = m.method;
        options.table_width = m.width;
        options.table_height = m.height;
        options.quadrature_nodes = m.nodes;
        const double g = m.g;
        benchmark::RegisterBenchmark(("BM_AirlightTable/" + m.name).c_str(),
                                     [options, g](benchmark::State& st) { airlightEntry(st, options, g); })
            ->UseManualTime()
            ->Iterations(1)
            ->Unit(benchmark::kMicrosecond);
    }
    return true;
}();

}  // namespace
