// Light-volume tessellator (penumbra/gl/light_volume.hpp, billeter2010): adaptive against static
// tessellation of the built-in scenes' shadow maps at 512^2, 1024^2 and 2048^2.
//
// Input: the scene rendered into a 32-bit float depth texture from a spot light framing the casters
// and the ground around them (1.5x their box), as an engine's shadow pass would.
//
// Entries BM_LightVolume/<scene>/<R>/<mode>, mode = static | adaptive_1e-6 | adaptive_1e-4 (the
// flatness: the adaptive floor stays within 2 * flatness of the static one in post-projective depth).
// Counters:
//   edge_map_ms, tessellate_ms, total_ms  GPU stages (median of 3): lattice depths + flatness flags
//                                         (the seed's Laplacian + edge map), restriction + counts +
//                                         scan + emission + command (timeGpu's method: GL_TIME_ELAPSED
//                                         where it measures, else glFinish + wall clock, e.g. llvmpipe)
//   cpu_ms                                the CPU twin (lattice depths + tessellateLightVolume), once
//   triangles, floor_triangles            the mesh the GPU emitted (== the CPU twin's)
//   triangles_vs_static                   triangles / the static tessellation's (2 R^2 + 4 R)
//   err_floor_max                         lightVolumeFloorError: the floor's largest deviation from the
//                                         static surface, post-projective depth
//   gpu_equals_cpu                        1 when the GPU mesh equals the CPU twin's, word for word
// Not yet here: the volume render and the ray-marching baselines (issue 12's next step).
// PENUMBRA_BENCH_SMOKE=1: one scene at 64^2.
#include "bench_common.hpp"

#include <penumbra/gl/light_volume.hpp>
#include <penumbra/light_volume.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>

#include <chrono>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace {

using penumbra::bench::glContext;

/// The scene's shadow map at R^2 (depth texture and its floats), cached per (scene, R).
struct ShadowMap {
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    std::vector<float> depth;
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
    map.gbuffer = std::make_unique<penumbra::scene::GBuffer>(r, r);
    map.gbuffer->render(gpu_scene, light);
    map.depth.resize(size_t(r) * r);
    glGetTextureImage(map.gbuffer->depthTexture(), 0, GL_DEPTH_COMPONENT, GL_FLOAT, static_cast<GLsizei>(4 * map.depth.size()),
                      map.depth.data());
    return map;
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

const bool kRegistered = [] {
    const bool smoke = penumbra::bench::smokeRun();
    const std::vector<std::string> scenes = smoke ? std::vector<std::string>{"columns"}
                                                  : std::vector<std::string>{"torus_knot", "columns", "hairball", "grass"};
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
        }
    }
    return true;
}();

}  // namespace
