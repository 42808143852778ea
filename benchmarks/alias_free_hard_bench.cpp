// Alias-free hard shadows (sintorn2008 §3) against standard shadow maps on the same view samples,
// every ratio measured inside one entry per scene: run time next to error against the exact
// oracle, the seed's §5 picture. Sintorn2008's target: the alias-free pipeline within 3x the time
// of an 8192^2 shadow map (counter hard_over_map8192 <= 3).
//
// BM_HardShadows/<scene>, one entry per scene: the built-in scenes (penumbra::scene::builtinNames())
// and every *.obj in PENUMBRA_SHARED_SCENES_DIR, sorted (skipped with a message on stderr when the
// folder is absent).
//
// Setup (untimed, once per entry): the scene's camera view rendered into a W x W G-buffer
// (penumbra/scene/gl_scene.hpp) whose view samples (positions + face normals) feed every method;
// the point light at scene.light.position with the starting matrix lightViewProjectionForBounds()
// of the view samples' box; one exact pipeline run (reserve + validate first) that gives the
// §4.3-fitted light matrix and the pipeline's tested set T = the samples whose state is
// PENUMBRA_AFH_LIT or _SHADOWED; the oracle (reference::VisibilityOracle on GpuScene::positions()/
// indices(), coplanar_epsilon = the pipeline's) through reference::hardReference on the samples'
// float positions (the one comparison code of tests, benchmarks and demo: reference/compare.hpp).
//
// Methods, each with its own objects, all timed in the same entry:
//   hard        AliasFreeHardShadows::run, AfhPrecision::Exact, default options (the filtered exact
//               blocker test: float with a proven bound, double only where the sign is uncertain):
//               fit + lists + light pass + resolve, W x W view and W x W light grid (the G-buffer
//               render is excluded: every method shares it).
//   hard_fp64   the same with AliasFreeHardOptions::fp64_only = true (every blocker test in double).
//   hard_back_faces  the exact pipeline with back_faces_only = true (sintorn2008 §3.3: closed casters
//               cast only light-back-facing triangles); back_faces_over_all = its time / hard's,
//               err_mismatch_back_faces its disagreement with the oracle on T.
//   fast        the same with AfhPrecision::Fast (float planes, no offset).
//   hard_compute  the hard method with AfhLightPass::Compute (casters as CasterBuffer ranges: setup,
//               scan, tiles passes; no draw): raster_over_compute = ms_hard / ms_hard_compute (> 1:
//               compute is faster), same_bits_compute (1 = the same states), err_mismatch_compute,
//               and its work (untimed count_work run): compute_items, compute_texels,
//               compute_chunks, compute_tests_per_sample.
//   map<res>    a res^2 GL_DEPTH_COMPONENT32F map rendered from the pipeline's fitted light matrix
//               (the tightest frustum a shadow map could get), every mesh, no culling,
//               GL_DEPTH_CLAMP, glPolygonOffset(2, 4) (slope factor 2, 4 units: a typical
//               slope-scaled bias), then shaders/penumbra/shadow_map/lookup.comp.glsl over every
//               view sample: project, nearest texel, `>`. Timed: clear + depth render + lookup.
//               res = 2048 and 8192.
//
// Timing: penumbra::bench::timeGpu for every timed call (GL_TIME_ELAPSED where the driver really
// measures the region, else glFinish + wall clock). One warm-up call of every method, then per
// benchmark iteration one timed call of every method, interleaved (the starting method rotates
// with the iteration so none is always first after the others); each method's time is the median
// over the iterations. So that every method of an entry is timed the same way, the ms_* counters
// use the GL_TIME_ELAPSED readings only when the query measured every timed call of the entry,
// else the glFinish + wall-clock readings of all of them (llvmpipe answers some calls with what
// looks like a timestamp, e.g. 3253 s, so there it is the wall clock). The entry's own manual time
// per iteration is timeGpu's result for the hard method. Read-backs, host validation
// (reserve/validate) and the error analysis are outside every timed region.
//
// Counters:
//   ms_hard, ms_hard_fp64, ms_fast, ms_map2048, ms_map8192   medians, ms
//   hard_over_map8192, hard_over_map2048   ms_hard / ms_map<res> (sintorn2008: <= 3 for 8192)
//   filtered_over_fp64                     ms_hard / ms_hard_fp64 (< 1: the filter pays off)
//   fast_over_exact                        ms_fast / ms_hard
//   timer_gl_time_elapsed                  1 = the ms_* are GL_TIME_ELAPSED, 0 = glFinish + wall
//   same_bits_fp64      1 when the filtered and fp64-only runs wrote identical states, i.e. the
//                       same resolved shadow bit for every sample id (must be 1), else 0. (The raw
//                       shadow-bit words are per list slot; slot order inside a list follows the
//                       scatter's atomics, so words of two runs may be permuted.)
//   Exactness on the pipeline's tested set T (compareHardStates, oracle ties excluded):
//     err_mismatch, err_mismatch_count   hard (must be 0); tested = |T|, ties = oracle ties in T
//     err_mismatch_fp64                  hard_fp64 on T (must be 0)
//     err_mismatch_fast                  fast on T
//   Dark/lit error on ALL surface samples, every method (err_hard, err_hard_fp64, err_fast,
//   err_map2048, err_map8192 = errors / (surface - ties_all), err_<method>_count = errors):
//     "dark" rule, the same for every method and the oracle: a sample is dark when it faces away
//     from the light, or when it faces the light and is shadowed. Faces away = !(dot(n, light - p)
//     > 0) with the G-buffer's face normal n and position p, evaluated in float exactly as the
//     pipeline's classification does (sample_lists project.glsl: products rounded one by one,
//     summed x, y, z; no FMA): a renderer's N.L makes such samples dark whatever the shadow method
//     says. Oracle: dark = faces away, or the oracle's segment p -> light is blocked. A method on a
//     light-facing sample: dark = state SHADOWED or BACK_FACING, lit = state LIT; any other state
//     (a shadow map's UNTESTED: outside the map; the pipeline's UNTESTED: list overflow) is an
//     error. Compared: every non-background sample (surface = position.w != 0); the light-facing
//     ones through compareHardStates on the oracle reference, the others agree by the rule (they
//     stay in the denominator). Oracle ties are excluded (ties_all).
//     back_facing = surface samples that face away; uncovered_map<res> = light-facing samples the
//     map did not cover (counted as errors); facing_disagree = samples where the hard pipeline's
//     BACK_FACING state differs from the host rule (0 unless the driver's float rounding differs).
//   Work, from a separate run with count_work = true (default = filtered options, untimed):
//     fragments, tests_per_sample (blocker tests / |T|), triangles_emitted, passes,
//     max_list_length, overflow, fallbacks (blocker tests the filter left to double),
//     fallback_rate = fallbacks / blocker tests; shadow_map_texels_max = the largest res^2.
// W = 512, 5 iterations (smoke runs, PENUMBRA_BENCH_SMOKE=1: W = 64, only the 2048 map, 1 iteration).
// Example: PENUMBRA_GL=egl penumbra_bench --benchmark_filter=BM_HardShadows
#include "bench_common.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/detail/float_ops.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/reference/compare.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

namespace {

namespace gl = penumbra::gl;
namespace ref = penumbra::reference;
using penumbra::bench::timeGpu;

// glPolygonOffset(factor, units) of the shadow-map depth render.
constexpr float kShadowMapSlopeBias = 2.0f;
constexpr float kShadowMapConstantBias = 4.0f;

uint32_t viewSize() { return penumbra::bench::smokeRun() ? 64u : 512u; }
int64_t iterationCount() { return penumbra::bench::smokeRun() ? 1 : 5; }

std::vector<uint32_t> shadowMapSizes() {
    if (penumbra::bench::smokeRun()) return {2048u};
    return {2048u, 8192u};
}

/// A scene to run: a built-in (empty path) or an OBJ file.
struct SceneSpec {
    std::string name, path;
};

std::vector<SceneSpec> sceneSpecs() {
    std::vector<SceneSpec> specs;
    for (const std::string& name : penumbra::scene::builtinNames()) specs.push_back({name, ""});
#ifdef PENUMBRA_SHARED_SCENES_DIR
    const std::filesystem::path dir = penumbra::test::sharedScenesDir();
    std::error_code ec;
    if (std::filesystem::is_directory(dir, ec)) {
        std::vector<std::filesystem::path> files;
        for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
            if (e.path().extension() == ".obj") files.push_back(e.path());
        }
        std::sort(files.begin(), files.end());
        for (const auto& file : files) specs.push_back({file.stem().string(), file.string()});
    } else {
        std::fprintf(stderr, "alias_free_hard_bench: %s is absent: the OBJ scenes are skipped\n", dir.string().c_str());
    }
#else
    std::fprintf(stderr, "alias_free_hard_bench: PENUMBRA_SHARED_SCENES_DIR is not defined: the OBJ scenes are skipped\n");
#endif
    return specs;
}

penumbra::scene::Scene loadScene(const SceneSpec& spec) {
    return spec.path.empty() ? penumbra::scene::builtin(spec.name) : penumbra::scene::loadObj(spec.path);
}

/// Faces away from the point light: !(dot(n, light - p) > 0) in float, the pipeline's rule
/// (sample_lists project.glsl / penumbra::detail::classifySample: each product rounded, summed
/// x, y, z, no contraction).
bool facesAway(const glm::vec4& p, const glm::vec4& n, const glm::vec3& light) {
    using penumbra::detail::mulRounded;
    const float lx = light.x - p.x, ly = light.y - p.y, lz = light.z - p.z;
    float facing = mulRounded(n.x, lx) + mulRounded(n.y, ly);
    facing = facing + mulRounded(n.z, lz);
    return !(facing > 0.0f);
}

/// The reference restricted to `ids` (ascending, each one of all.ids).
ref::HardReference subsetReference(const ref::HardReference& all, const std::vector<uint32_t>& ids) {
    ref::HardReference out;
    size_t r = 0;
    for (uint32_t id : ids) {
        while (r < all.ids.size() && all.ids[r] < id) ++r;
        PENUMBRA_CHECK(r < all.ids.size() && all.ids[r] == id, "alias_free_hard_bench: sample ", id, " has no oracle verdict");
        out.ids.push_back(id);
        out.blocked.push_back(all.blocked[r]);
        out.tie.push_back(all.tie[r]);
        out.receivers.push_back(all.receivers[r]);
        out.light_ends.push_back(all.light_ends[r]);
    }
    return out;
}

/// A method's dark/lit decisions on every surface sample against the oracle (the file comment's rule).
struct DarkComparison {
    size_t surface = 0, ties = 0, errors = 0, uncovered = 0;
    double rate() const {
        const size_t decided = surface - ties;
        return decided ? double(errors) / double(decided) : 0.0;
    }
};

/// One scene's view samples, light and oracle verdicts (built once per entry, untimed).
struct Fixture {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    uint32_t size = 0;
    std::vector<glm::vec4> positions, normals;
    penumbra::SampleListsLight light;
    ref::HardLight hard_light;
    glm::mat4 fitted_view_projection{1.0f};  ///< the pipeline's §4.3 fit: the shadow maps use it too
    double coplanar_epsilon = 0.0;
    std::vector<uint32_t> setup_states;  ///< the exact pipeline's states of the setup run
    std::vector<uint8_t> faces_away;     ///< per sample id (surface samples only)
    size_t surface = 0, back_facing = 0;
    ref::HardReference tested;  ///< oracle on the pipeline's tested set T
    ref::HardReference facing;  ///< oracle on every light-facing surface sample

    Fixture(penumbra::scene::Scene s, uint32_t w) : scene(std::move(s)), size(w) {
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(w, w);
        gbuffer->render(*gpu, scene.camera.projection(1.0f) * scene.camera.view());
        positions = gbuffer->positionBuffer().download<glm::vec4>();
        normals = gbuffer->faceBuffer().download<glm::vec4>();
        const auto [lo, hi] = penumbra::viewSampleBounds(positions.data(), positions.size());
        light.light = glm::vec4(scene.light.position, 1.0f);
        light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);

        const penumbra::AliasFreeHardOptions o = options(penumbra::AfhPrecision::Exact, false);
        coplanar_epsilon = o.coplanar_epsilon;
        hard_light = ref::hardLight(light.light, o.directional_reach);
        penumbra::AliasFreeHardShadows pipeline(o);
        pipeline.reserve(samples());
        pipeline.validate(input(), samples());
        PENUMBRA_CHECK(pipeline.run(input(), samples(), light, drawer()) == penumbra::Status::Ok,
                       "alias_free_hard_bench: the setup run failed");
        fitted_view_projection = pipeline.readFrame().light_view_projection;
        setup_states = pipeline.stateBuffer().download<uint32_t>(0, samples());

        // One oracle evaluation for T and the light-facing samples (T is a subset unless the
        // driver's facing disagrees with the host rule).
        const std::vector<uint32_t> tested_ids = ref::testedSamples(setup_states);
        std::vector<uint32_t> facing_ids, all_ids;
        faces_away.assign(samples(), 0);
        for (uint32_t id = 0; id < samples(); ++id) {
            if (positions[id].w == 0.0f) continue;
            ++surface;
            faces_away[id] = facesAway(positions[id], normals[id], glm::vec3(light.light));
            back_facing += faces_away[id];
            if (!faces_away[id]) facing_ids.push_back(id);
        }
        std::set_union(tested_ids.begin(), tested_ids.end(), facing_ids.begin(), facing_ids.end(), std::back_inserter(all_ids));
        const ref::VisibilityOracle oracle(gpu->positions(), gpu->indices());
        ref::VisibilityOptions oracle_options;
        oracle_options.coplanar_epsilon = coplanar_epsilon;
        const ref::HardReference all = ref::hardReference(oracle, positions, all_ids, hard_light, oracle_options);
        tested = subsetReference(all, tested_ids);
        facing = subsetReference(all, facing_ids);
    }

    penumbra::AliasFreeHardOptions options(penumbra::AfhPrecision precision, bool fp64_only,
                                           bool back_faces_only = false) const {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = o.grid_height = size;  // sintorn2008: the light grid has the view's size
        o.precision = precision;
        o.fp64_only = fp64_only;
        o.back_faces_only = back_faces_only;
        return o;
    }
    penumbra::SampleBufferInput input() const {
        auto r = [](const gl::Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
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

    /// The file comment's dark/lit rule on every surface sample. Light-facing samples go through
    /// compareHardStates: dark (SHADOWED or BACK_FACING) -> SHADOWED, LIT -> LIT, anything else
    /// (not covered / not decided) -> the opposite of the oracle's verdict, i.e. an error.
    DarkComparison compareDark(const std::vector<uint32_t>& states) const {
        DarkComparison d;
        std::vector<uint32_t> dark(states.size(), PENUMBRA_AFH_NO_SAMPLE);
        for (size_t r = 0; r < facing.ids.size(); ++r) {
            const uint32_t id = facing.ids[r];
            const uint32_t s = states[id];
            if (s == PENUMBRA_AFH_SHADOWED || s == PENUMBRA_AFH_BACK_FACING) {
                dark[id] = PENUMBRA_AFH_SHADOWED;
            } else if (s == PENUMBRA_AFH_LIT) {
                dark[id] = PENUMBRA_AFH_LIT;
            } else {
                ++d.uncovered;
                dark[id] = facing.blocked[r] ? PENUMBRA_AFH_LIT : PENUMBRA_AFH_SHADOWED;
            }
        }
        const ref::HardComparison c = ref::compareHardStates(facing, dark, 0);
        d.surface = surface;  // faces-away samples: dark for the oracle and every method
        d.ties = c.ties;
        d.errors = c.mismatched;
        return d;
    }

    /// Samples where the pipeline's BACK_FACING state and the host rule disagree.
    size_t facingDisagreements(const std::vector<uint32_t>& states) const {
        size_t n = 0;
        for (uint32_t id = 0; id < samples(); ++id) {
            if (positions[id].w == 0.0f) continue;
            n += (states[id] == PENUMBRA_AFH_BACK_FACING) != (faces_away[id] != 0);
        }
        return n;
    }
};

/// A res^2 depth map from the fitted light matrix and the lookup over every view sample.
class ShadowMap {
public:
    ShadowMap(const Fixture& f, uint32_t resolution)
        : f_(f), resolution_(resolution), map_(GL_TEXTURE_2D), fbo_(gl::Framebuffer::create()),
          states_(size_t(f.samples()) * 4) {
        glTextureStorage2D(map_.id(), 1, GL_DEPTH_COMPONENT32F, GLsizei(resolution), GLsizei(resolution));
        glTextureParameteri(map_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTextureParameteri(map_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTextureParameteri(map_.id(), GL_TEXTURE_COMPARE_MODE, GL_NONE);
        glNamedFramebufferTexture(fbo_.id(), GL_DEPTH_ATTACHMENT, map_.id(), 0);
        glNamedFramebufferDrawBuffer(fbo_.id(), GL_NONE);
        glNamedFramebufferReadBuffer(fbo_.id(), GL_NONE);
        PENUMBRA_CHECK(glCheckNamedFramebufferStatus(fbo_.id(), GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
                       "alias_free_hard_bench: shadow-map framebuffer incomplete");
        light_texture_ = penumbra::lightTextureMatrix(f.fitted_view_projection, penumbra::LightDepthRange::MinusOneToOne);
        grid_ = penumbra::detail::foldDispatch(penumbra::detail::divUp(f.samples(), 256));
        gl::checkErrors("alias_free_hard_bench: shadow map setup");
    }

    void run() const {
        static const gl::Program depth_program = gl::buildProgram({"penumbra/scene/depth_only.vert.glsl"});
        static const gl::Program lookup_program = gl::buildComputeProgram("penumbra/shadow_map/lookup.comp.glsl");
        glBindFramebuffer(GL_FRAMEBUFFER, fbo_.id());
        glViewport(0, 0, GLsizei(resolution_), GLsizei(resolution_));
        glDepthMask(GL_TRUE);
        const float far_depth = 1.0f;
        glClearNamedFramebufferfv(fbo_.id(), GL_DEPTH, 0, &far_depth);
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
        glDisable(GL_CULL_FACE);
        glDisable(GL_RASTERIZER_DISCARD);
        glEnable(GL_DEPTH_CLAMP);  // casters in front of the fitted near plane still cast
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(kShadowMapSlopeBias, kShadowMapConstantBias);
        depth_program.use();
        glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(f_.fitted_view_projection));
        f_.gpu->draw();
        glDisable(GL_POLYGON_OFFSET_FILL);
        glDisable(GL_DEPTH_CLAMP);
        glDisable(GL_DEPTH_TEST);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);

        lookup_program.use();
        glUniformMatrix4fv(0, 1, GL_FALSE, glm::value_ptr(light_texture_));
        glUniform1ui(1, f_.samples());
        glBindTextureUnit(0, map_.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, f_.gbuffer->positionBuffer().id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, states_.id());
        glDispatchCompute(grid_.x, grid_.y, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT);
    }

    std::vector<uint32_t> states() const { return states_.download<uint32_t>(0, f_.samples()); }
    uint32_t resolution() const { return resolution_; }

private:
    const Fixture& f_;
    uint32_t resolution_;
    gl::Texture map_;
    gl::Framebuffer fbo_;
    gl::Buffer states_;
    glm::mat4 light_texture_{1.0f};
    penumbra::detail::DispatchGrid grid_;
};


/// One timed method of the entry.
struct Method : penumbra::bench::TimedMethod {
    Method(std::string n, std::function<void()> r, std::vector<double> w = {}, std::vector<double> q = {})
        : penumbra::bench::TimedMethod{std::move(n), std::move(r), std::move(w), std::move(q)} {}
    double medianMs(bool use_query) const { return ms(use_query); }
};

void BM_HardShadows(benchmark::State& state, const SceneSpec& spec) {
    penumbra::bench::glContext();
    try {
        const Fixture f(loadScene(spec), viewSize());
        const uint32_t n = f.samples();

        // Load time (untimed): every method's objects, reserved and validated.
        auto makePipeline = [&](penumbra::AfhPrecision precision, bool fp64_only, bool back_faces_only = false) {
            penumbra::AliasFreeHardShadows p(f.options(precision, fp64_only, back_faces_only));
            p.reserve(n);
            p.validate(f.input(), n);
            return p;
        };
        penumbra::AliasFreeHardShadows hard = makePipeline(penumbra::AfhPrecision::Exact, false);
        penumbra::AliasFreeHardShadows hard_fp64 = makePipeline(penumbra::AfhPrecision::Exact, true);
        penumbra::AliasFreeHardShadows fast = makePipeline(penumbra::AfhPrecision::Fast, false);
        // §3.3: closed casters cast only light-back-facing triangles (an option; off by default).
        penumbra::AliasFreeHardShadows back_faces = makePipeline(penumbra::AfhPrecision::Exact, false, true);
        // The compute light pass (AfhLightPass::Compute): the hard method's options, casters as buffers.
        const std::vector<penumbra::CasterBuffer>& casters = f.gpu->casterBuffers();
        const uint32_t ranges = static_cast<uint32_t>(casters.size());
        penumbra::AliasFreeHardOptions compute_options = f.options(penumbra::AfhPrecision::Exact, false);
        compute_options.light_pass = penumbra::AfhLightPass::Compute;
        penumbra::AliasFreeHardShadows compute(compute_options);
        compute.reserve(n);
        compute.validate(f.input(), n);
        compute.validateCasters(casters.data(), ranges);
        std::vector<std::unique_ptr<ShadowMap>> maps;
        for (uint32_t res : shadowMapSizes()) maps.push_back(std::make_unique<ShadowMap>(f, res));

        const penumbra::SampleBufferInput input = f.input();
        const penumbra::AliasFreeHardShadows::DrawCasters draw = f.drawer();
        bool runs_ok = true;
        auto pipelineRun = [&](penumbra::AliasFreeHardShadows& p) {
            return [&p, &input, &f, &draw, &runs_ok, n] { runs_ok &= p.run(input, n, f.light, draw) == penumbra::Status::Ok; };
        };
        std::vector<Method> methods;
        methods.push_back({"hard", pipelineRun(hard), {}, {}});
        methods.push_back({"hard_fp64", pipelineRun(hard_fp64), {}, {}});
        methods.push_back({"fast", pipelineRun(fast), {}, {}});
        methods.push_back({"hard_back_faces", pipelineRun(back_faces), {}, {}});
        methods.push_back({"hard_compute",
                           [&] { runs_ok &= compute.run(input, n, f.light, casters.data(), ranges) == penumbra::Status::Ok; },
                           {},
                           {}});
        for (const auto& m : maps) {
            const ShadowMap* map = m.get();
            methods.push_back({"map" + std::to_string(map->resolution()), [map] { map->run(); }, {}, {}});
        }

        // One timing method for the whole entry: GL_TIME_ELAPSED only when it measured every
        // timed call (llvmpipe answers some calls with a timestamp, not a duration), else the
        // glFinish + wall-clock reading of every call.
        std::vector<penumbra::bench::TimedMethod> timed(methods.begin(), methods.end());
        const bool query_measures = penumbra::bench::timeInterleaved(state, timed);
        for (size_t k = 0; k < methods.size(); ++k) {
            methods[k].wall = timed[k].wall;
            methods[k].query = timed[k].query;
        }
        gl::checkErrors("alias_free_hard_bench");
        if (!runs_ok) {
            state.SkipWithError("AliasFreeHardShadows::run returned an error Status");
            return;
        }

        // Times and ratios, measured in this entry.
        auto ms = [&](const std::string& name) {
            for (const Method& m : methods) {
                if (m.name == name) return m.medianMs(query_measures);
            }
            return 0.0;
        };
        auto ratio = [](double a, double b) { return b > 0.0 ? a / b : 0.0; };
        for (const Method& m : methods) state.counters["ms_" + m.name] = m.medianMs(query_measures);
        for (const auto& m : maps) {
            const std::string res = std::to_string(m->resolution());
            state.counters["hard_over_map" + res] = ratio(ms("hard"), ms("map" + res));
        }
        state.counters["filtered_over_fp64"] = ratio(ms("hard"), ms("hard_fp64"));
        state.counters["fast_over_exact"] = ratio(ms("fast"), ms("hard"));
        state.counters["back_faces_over_all"] = ratio(ms("hard_back_faces"), ms("hard"));
        state.counters["raster_over_compute"] = ratio(ms("hard"), ms("hard_compute"));  // > 1: compute is faster
        state.counters["timer_gl_time_elapsed"] = query_measures ? 1.0 : 0.0;

        // Read-backs and errors (after the timed runs: the last iteration's results).
        const std::vector<uint32_t> hard_states = hard.stateBuffer().download<uint32_t>(0, n);
        const std::vector<uint32_t> fp64_states = hard_fp64.stateBuffer().download<uint32_t>(0, n);
        const std::vector<uint32_t> fast_states = fast.stateBuffer().download<uint32_t>(0, n);
        const std::vector<uint32_t> back_faces_states = back_faces.stateBuffer().download<uint32_t>(0, n);
        // Per sample id (the shadow-bit words are per list slot, and a list's slot order follows
        // the scatter's atomics, so two runs' words may be permuted; the states are the resolved bits).
        state.counters["same_bits_fp64"] = hard_states == fp64_states ? 1.0 : 0.0;
        const std::vector<uint32_t> compute_states = compute.stateBuffer().download<uint32_t>(0, n);
        state.counters["same_bits_compute"] = hard_states == compute_states ? 1.0 : 0.0;

        const ref::HardComparison exact = ref::compareHardStates(f.tested, hard_states);
        state.counters["err_mismatch"] = exact.mismatchRate();
        state.counters["err_mismatch_count"] = double(exact.mismatched);
        state.counters["tested"] = double(exact.samples);
        state.counters["ties"] = double(exact.ties);
        state.counters["err_mismatch_fp64"] = ref::compareHardStates(f.tested, fp64_states).mismatchRate();
        state.counters["err_mismatch_fast"] = ref::compareHardStates(f.tested, fast_states).mismatchRate();
        state.counters["err_mismatch_compute"] = ref::compareHardStates(f.tested, compute_states).mismatchRate();
        const ref::HardComparison back = ref::compareHardStates(f.tested, back_faces_states);
        state.counters["err_mismatch_back_faces"] = back.mismatchRate();
        state.counters["err_mismatch_back_faces_count"] = double(back.mismatched);
        for (const auto& c : exact.first_mismatches) {
            std::fprintf(stderr, "alias_free_hard_bench %s: mismatch at sample %u (%.9g, %.9g, %.9g): pipeline %d oracle %d\n",
                         spec.name.c_str(), c.sample, c.position.x, c.position.y, c.position.z, int(c.shadowed), int(c.blocked));
        }

        auto setDark = [&](const std::string& name, const DarkComparison& d) {
            state.counters["err_" + name] = d.rate();
            state.counters["err_" + name + "_count"] = double(d.errors);
        };
        const DarkComparison dark_hard = f.compareDark(hard_states);
        setDark("hard", dark_hard);
        setDark("hard_fp64", f.compareDark(fp64_states));
        setDark("fast", f.compareDark(fast_states));
        setDark("hard_back_faces", f.compareDark(back_faces_states));
        for (const auto& m : maps) {
            const DarkComparison d = f.compareDark(m->states());
            const std::string name = "map" + std::to_string(m->resolution());
            setDark(name, d);
            state.counters["uncovered_" + name] = double(d.uncovered);
        }
        state.counters["surface"] = double(f.surface);
        state.counters["back_facing"] = double(f.back_facing);
        state.counters["ties_all"] = double(dark_hard.ties);
        state.counters["facing_disagree"] = double(f.facingDisagreements(hard_states));

        // Work counters: a separate run with count_work (default = filtered options), untimed.
        penumbra::AliasFreeHardOptions counting_options = f.options(penumbra::AfhPrecision::Exact, false);
        counting_options.count_work = true;
        penumbra::AliasFreeHardShadows counting(counting_options);
        counting.reserve(n);
        counting.validate(input, n);
        if (counting.run(input, n, f.light, draw) != penumbra::Status::Ok) {
            state.SkipWithError("AliasFreeHardShadows::run (count_work) returned an error Status");
            return;
        }
        const penumbra::AliasFreeHardFrame frame = counting.readFrame();
        state.counters["fragments"] = double(frame.fragments);
        state.counters["tests_per_sample"] = f.tested.ids.empty() ? 0.0 : double(frame.tests) / double(f.tested.ids.size());
        state.counters["triangles_emitted"] = double(frame.triangles_emitted);
        state.counters["passes"] = double(frame.passes);
        state.counters["max_list_length"] = double(frame.statistics.max_list_length);
        state.counters["overflow"] = double(frame.overflow);
        state.counters["fallbacks"] = double(frame.fallbacks);
        state.counters["fallback_rate"] = frame.tests ? double(frame.fallbacks) / double(frame.tests) : 0.0;
        // The compute light pass's work, counted the same way (untimed).
        compute_options.count_work = true;
        penumbra::AliasFreeHardShadows compute_counting(compute_options);
        compute_counting.reserve(n);
        if (compute_counting.run(input, n, f.light, casters.data(), ranges) != penumbra::Status::Ok) {
            state.SkipWithError("AliasFreeHardShadows::run (compute, count_work) returned an error Status");
            return;
        }
        const penumbra::AliasFreeHardFrame cf = compute_counting.readFrame();
        state.counters["compute_items"] = double(cf.items);
        state.counters["compute_texels"] = double(cf.fragments);
        state.counters["compute_chunks"] = double(cf.chunks);
        state.counters["compute_tests_per_sample"] = f.tested.ids.empty() ? 0.0 : double(cf.tests) / double(f.tested.ids.size());
        state.counters["shadow_map_texels_max"] = double(shadowMapSizes().back()) * double(shadowMapSizes().back());

        // Leave no binding of ours behind for the next entry.
        glBindTextureUnit(0, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, 0);
        glUseProgram(0);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

[[maybe_unused]] const bool kRegistered = [] {
    for (const SceneSpec& spec : sceneSpecs()) {
        benchmark::RegisterBenchmark(("BM_HardShadows/" + spec.name).c_str(), [spec](benchmark::State& s) { BM_HardShadows(s, spec); })
            ->UseManualTime()
            ->Iterations(iterationCount())
            ->Unit(benchmark::kMillisecond);
    }
    return true;
}();

}  // namespace
