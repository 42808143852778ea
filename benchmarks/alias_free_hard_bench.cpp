// Alias-free hard shadows (sintorn2008 §3) against standard shadow maps on the same view samples:
// run time next to error against the exact oracle, the seed's §5 picture. Sintorn2008's target:
// the alias-free pipeline within 3x the time of an 8192^2 shadow map.
//
// Setup per scene (torus_knot, columns, hairball, grass, and spot from PENUMBRA_SHARED_SCENES_DIR
// "/spot.obj" when present), done once and shared by every benchmark of the scene, untimed: the
// scene's camera view rendered into a W x W G-buffer (penumbra/scene/gl_scene.hpp) whose view
// samples feed both methods; the point light at scene.light.position with the starting matrix
// lightViewProjectionForBounds() of the view samples' box; one exact pipeline run that gives the
// §4.3-fitted light matrix and the tested set = the samples whose state is PENUMBRA_AFH_LIT or
// _SHADOWED (light-front-facing, inside the light frustum); the oracle
// (reference::VisibilityOracle on GpuScene::positions()/indices(), the one light sample = the
// point light, coplanar_epsilon = the pipeline's) on those samples' float positions.
//
//   BM_HardShadows/<scene>        AliasFreeHardShadows::run with AfhPrecision::Exact: fit + lists +
//                                 light pass + resolve, W x W view and W x W light grid (the G-buffer
//                                 render is excluded: both methods share it).
//   BM_HardShadows/<scene>/fast   the same with AfhPrecision::Fast (float planes, no offset).
//   BM_ShadowMap/<scene>/<res>    res^2 GL_DEPTH_COMPONENT32F map rendered from the pipeline's fitted
//                                 light matrix (the tightest frustum a shadow map could get), every
//                                 mesh, no culling, GL_DEPTH_CLAMP, glPolygonOffset(2, 4) (slope
//                                 factor 2, 4 units: a typical slope-scaled bias), then
//                                 shaders/penumbra/shadow_map/lookup.comp.glsl over every view
//                                 sample: project, nearest texel, `>`. Timed: clear + depth render +
//                                 lookup. res = 2048 and 8192.
//
// GPU time: glFinish before and after the region, wall clock (llvmpipe's GL_TIME_ELAPSED answers
// 1 ns), manual time, after one warm-up run; ms.
// Counters (error computed once, after the timed runs, on the tested set):
//   err_mismatch        mismatches / (samples - ties): the method says SHADOWED where the oracle
//                       says lit or the reverse (shadow map: anything but SHADOWED counts as lit);
//   err_mismatch_count  mismatches; samples = tested samples; ties = oracle ties (excluded);
//   BM_HardShadows (exact) work counters from a separate run with count_work = true:
//     fragments, tests_per_sample (blocker tests / tested sample), triangles_emitted, passes,
//     max_list_length;
//   BM_ShadowMap: shadow_map_texels = res^2, untested (tested samples the map did not cover),
//     hard_over_map = BM_HardShadows/<scene> time / this time when both ran in this process.
// W = 512 (smoke runs, PENUMBRA_BENCH_SMOKE=1: W = 64 and only the 2048 map).
// Example: PENUMBRA_GL=egl penumbra_bench --benchmark_filter='BM_(HardShadows|ShadowMap)'
#include "bench_common.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>
#include <glm/gtc/type_ptr.hpp>

#include <chrono>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace {

namespace gl = penumbra::gl;

// glPolygonOffset(factor, units) of the shadow-map depth render.
constexpr float kShadowMapSlopeBias = 2.0f;
constexpr float kShadowMapConstantBias = 4.0f;

uint32_t viewSize() { return penumbra::bench::smokeRun() ? 64u : 512u; }

std::vector<uint32_t> shadowMapSizes() {
    if (penumbra::bench::smokeRun()) return {2048u};
    return {2048u, 8192u};
}

std::string spotPath() { return std::string(PENUMBRA_SHARED_SCENES_DIR) + "/spot.obj"; }

std::vector<std::string> sceneNames() {
    std::vector<std::string> names = penumbra::scene::builtinNames();
    if (std::filesystem::exists(spotPath())) names.push_back("spot");
    return names;
}

using penumbra::bench::timeGpu;

struct Comparison {
    size_t samples = 0, ties = 0, mismatched = 0, untested = 0;
    double errMismatch() const {
        const size_t decided = samples - ties;
        return decided ? double(mismatched) / double(decided) : 0.0;
    }
};

/// One scene's view samples, light, exact reference and oracle verdicts (built once, untimed).
struct Fixture {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    uint32_t size = 0;
    std::vector<glm::vec4> positions;
    penumbra::SampleListsLight light;
    glm::mat4 fitted_view_projection{1.0f};  ///< the pipeline's §4.3 fit: the shadow maps use it too
    double coplanar_epsilon = 0.0;
    std::vector<uint32_t> tested;  ///< sample ids the pipeline tests (state LIT or SHADOWED)
    std::vector<uint8_t> oracle_blocked, oracle_tie;  ///< per tested sample

    Fixture(penumbra::scene::Scene s, uint32_t w) : scene(std::move(s)), size(w) {
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(w, w);
        gbuffer->render(*gpu, scene.camera.projection(1.0f) * scene.camera.view());
        positions = gbuffer->positionBuffer().download<glm::vec4>();
        const auto [lo, hi] = penumbra::viewSampleBounds(positions.data(), positions.size());
        light.light = glm::vec4(scene.light.position, 1.0f);
        light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);

        penumbra::AliasFreeHardOptions options = pipelineOptions(penumbra::AfhPrecision::Exact);
        coplanar_epsilon = options.coplanar_epsilon;
        penumbra::AliasFreeHardShadows pipeline(options);
        pipeline.reserve(samples());
        pipeline.run(input(), samples(), light, drawer());
        fitted_view_projection = pipeline.readFrame().light_view_projection;
        const std::vector<uint32_t> states = pipeline.stateBuffer().download<uint32_t>(0, samples());
        std::vector<glm::dvec3> receivers;
        for (uint32_t id = 0; id < samples(); ++id) {
            if (states[id] != PENUMBRA_AFH_LIT && states[id] != PENUMBRA_AFH_SHADOWED) continue;
            tested.push_back(id);
            receivers.emplace_back(glm::vec3(positions[id]));
        }
        penumbra::reference::VisibilityOracle oracle(gpu->positions(), gpu->indices());
        penumbra::reference::VisibilityOptions oracle_options;
        oracle_options.coplanar_epsilon = coplanar_epsilon;
        const auto result = oracle.evaluate(receivers, {glm::dvec3(scene.light.position)}, oracle_options);
        oracle_blocked.resize(receivers.size());
        oracle_tie.resize(receivers.size());
        for (size_t r = 0; r < receivers.size(); ++r) {
            oracle_blocked[r] = result.isBlocked(r, 0);
            oracle_tie[r] = result.isTie(r, 0);
        }
    }

    penumbra::AliasFreeHardOptions pipelineOptions(penumbra::AfhPrecision precision) const {
        penumbra::AliasFreeHardOptions options;
        options.grid_width = options.grid_height = size;  // sintorn2008: the light grid has the view's size
        options.precision = precision;
        return options;
    }
    penumbra::SampleBufferInput input() const {
        auto r = [](const penumbra::gl::Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
        return {r(gbuffer->positionBuffer()), r(gbuffer->faceBuffer())};
    }
    uint32_t samples() const { return size * size; }
    penumbra::AliasFreeHardShadows::DrawCasters drawer() const {
        return [this](penumbra::CasterClass cls) {
            for (const auto& r : gpu->ranges()) {
                if (r.closed == (cls == penumbra::CasterClass::Closed)) gpu->draw(r);
            }
        };
    }

    /// A method's states (one per sample id) against the oracle on the tested set.
    Comparison compare(const std::vector<uint32_t>& states) const {
        Comparison c;
        c.samples = tested.size();
        for (size_t r = 0; r < tested.size(); ++r) {
            const uint32_t state = states[tested[r]];
            c.untested += state != PENUMBRA_AFH_LIT && state != PENUMBRA_AFH_SHADOWED;
            if (oracle_tie[r]) {
                ++c.ties;
                continue;
            }
            c.mismatched += (state == PENUMBRA_AFH_SHADOWED) != (oracle_blocked[r] != 0);
        }
        return c;
    }
};

penumbra::scene::Scene loadScene(const std::string& name) {
    if (name == "spot") return penumbra::scene::loadObj(spotPath());
    return penumbra::scene::builtin(name);
}

Fixture& fixture(const std::string& name) {
    static std::map<std::string, std::unique_ptr<Fixture>> fixtures;
    auto& slot = fixtures[name];
    if (!slot) slot = std::make_unique<Fixture>(loadScene(name), viewSize());
    return *slot;
}

// BM_HardShadows/<scene> seconds per run, for the shadow maps' hard_over_map counter.
std::map<std::string, double>& hardShadowSeconds() {
    static std::map<std::string, double> seconds;
    return seconds;
}

void setErrorCounters(benchmark::State& state, const Comparison& c) {
    state.counters["err_mismatch"] = c.errMismatch();
    state.counters["err_mismatch_count"] = double(c.mismatched);
    state.counters["samples"] = double(c.samples);
    state.counters["ties"] = double(c.ties);
}

void BM_HardShadows(benchmark::State& state, const std::string& name, penumbra::AfhPrecision precision) {
    penumbra::bench::glContext();
    try {
        Fixture& f = fixture(name);
        penumbra::AliasFreeHardShadows pipeline(f.pipelineOptions(precision));
        pipeline.reserve(f.samples());
        auto run = [&] { pipeline.run(f.input(), f.samples(), f.light, f.drawer()); };
        run();  // warm-up
        double total = 0.0;
        for (auto _ : state) {
            const double seconds = timeGpu(run);
            total += seconds;
            state.SetIterationTime(seconds);
        }
        if (precision == penumbra::AfhPrecision::Exact && state.iterations() > 0) {
            hardShadowSeconds()[name] = total / double(state.iterations());
        }
        setErrorCounters(state, f.compare(pipeline.stateBuffer().download<uint32_t>(0, f.samples())));
        if (precision == penumbra::AfhPrecision::Exact) {
            penumbra::AliasFreeHardOptions options = f.pipelineOptions(precision);
            options.count_work = true;
            penumbra::AliasFreeHardShadows counting(options);
            counting.reserve(f.samples());
            counting.run(f.input(), f.samples(), f.light, f.drawer());
            const auto frame = counting.readFrame();
            state.counters["fragments"] = double(frame.fragments);
            state.counters["tests_per_sample"] = f.tested.empty() ? 0.0 : double(frame.tests) / double(f.tested.size());
            state.counters["triangles_emitted"] = double(frame.triangles_emitted);
            state.counters["passes"] = double(frame.passes);
            state.counters["max_list_length"] = double(frame.statistics.max_list_length);
        }
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

void BM_ShadowMap(benchmark::State& state, const std::string& name, uint32_t resolution) {
    penumbra::bench::glContext();
    try {
        Fixture& f = fixture(name);
        static gl::Program depth_program = gl::buildProgram({"penumbra/scene/depth_only.vert.glsl"});
        static gl::Program lookup_program = gl::buildComputeProgram("penumbra/shadow_map/lookup.comp.glsl");
        gl::Texture map(GL_TEXTURE_2D);
        glTextureStorage2D(map.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(resolution), GLsizei(resolution));
        glTextureParameteri(map.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(map.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTextureParameteri(map.id(), GL_TEXTURE_COMPARE_MODE, GL_NONE);
        GLuint fbo = 0;
        glCreateFramebuffers(1, &fbo);
        glNamedFramebufferTexture(fbo, GL_DEPTH_ATTACHMENT, map.id(), 0);
        glNamedFramebufferDrawBuffer(fbo, GL_NONE);
        glNamedFramebufferReadBuffer(fbo, GL_NONE);
        PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                       "alias_free_hard_bench: shadow-map framebuffer incomplete");
        gl::Buffer states(size_t(f.samples()) * 4);
        const glm::mat4 light_texture =
            penumbra::lightTextureMatrix(f.fitted_view_projection, penumbra::LightDepthRange::MinusOneToOne);
        const penumbra::detail::DispatchGrid grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(f.samples(), 256));

        auto run = [&] {
            glBindFramebuffer(GL_FRAMEBUFFER, fbo);
            glViewport(0, 0, GLsizei(resolution), GLsizei(resolution));
            glDepthMask(GL_TRUE);
            const float far_depth = 1.0f;
            glClearNamedFramebufferfv(fbo, GL_DEPTH, 0, &far_depth);
            glEnable(GL_DEPTH_TEST);
            glDepthFunc(GL_LESS);
            glDisable(GL_CULL_FACE);
            glDisable(GL_RASTERIZER_DISCARD);
            glEnable(GL_DEPTH_CLAMP);  // casters in front of the fitted near plane still cast
            glEnable(GL_POLYGON_OFFSET_FILL);
            glPolygonOffset(kShadowMapSlopeBias, kShadowMapConstantBias);
            depth_program.use();
            glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(f.fitted_view_projection));
            f.gpu->draw();
            glDisable(GL_POLYGON_OFFSET_FILL);
            glDisable(GL_DEPTH_CLAMP);
            glDisable(GL_DEPTH_TEST);
            glBindFramebuffer(GL_FRAMEBUFFER, 0);

            lookup_program.use();
            glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(light_texture));
            glUniform1ui(1, f.samples());
            glBindTextureUnit(0, map.id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, f.gbuffer->positionBuffer().id());
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, states.id());
            glDispatchCompute(grid.x, grid.y, 1);
            glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
        };
        run();  // warm-up
        double total = 0.0;
        for (auto _ : state) {
            const double seconds = timeGpu(run);
            total += seconds;
            state.SetIterationTime(seconds);
        }
        gl::checkErrors("alias_free_hard_bench shadow map");
        const Comparison c = f.compare(states.download<uint32_t>(0, f.samples()));
        setErrorCounters(state, c);
        state.counters["untested"] = double(c.untested);
        state.counters["shadow_map_texels"] = double(resolution) * double(resolution);
        const auto hard = hardShadowSeconds().find(name);
        if (hard != hardShadowSeconds().end() && state.iterations() > 0 && total > 0.0) {
            state.counters["hard_over_map"] = hard->second / (total / double(state.iterations()));
        }
        glBindTextureUnit(0, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, 0);
        glUseProgram(0);
        glDeleteFramebuffers(1, &fbo);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

// Per scene: the pipeline, its fast variant, then the shadow maps, so one run prints each
// scene's time-against-error picture together.
[[maybe_unused]] const bool kRegistered = [] {
    const int64_t iterations = penumbra::bench::smokeRun() ? 1 : 5;
    for (const std::string& name : sceneNames()) {
        benchmark::RegisterBenchmark(("BM_HardShadows/" + name).c_str(),
                                     [name](benchmark::State& s) { BM_HardShadows(s, name, penumbra::AfhPrecision::Exact); })
            ->UseManualTime()
            ->Iterations(iterations)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("BM_HardShadows/" + name + "/fast").c_str(),
                                     [name](benchmark::State& s) { BM_HardShadows(s, name, penumbra::AfhPrecision::Fast); })
            ->UseManualTime()
            ->Iterations(iterations)
            ->Unit(benchmark::kMillisecond);
        for (uint32_t resolution : shadowMapSizes()) {
            benchmark::RegisterBenchmark(("BM_ShadowMap/" + name + "/" + std::to_string(resolution)).c_str(),
                                         [name, resolution](benchmark::State& s) { BM_ShadowMap(s, name, resolution); })
                ->UseManualTime()
                ->Iterations(iterations)
                ->Unit(benchmark::kMillisecond);
        }
    }
    return true;
}();

}  // namespace
