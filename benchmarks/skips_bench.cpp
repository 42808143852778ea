// The work skips of the two GPU pipelines, measured: each skip alone and all of them against
// every skip off, timed interleaved inside one entry per scene, with the work each removes and a
// word-for-word comparison of every method's result with the skips-off result (the skips'
// contract: not one shadow bit changes). The skips and their mapping onto options are the
// soft_shadows demo's --skips (examples/soft_shadows/main.cpp):
//   soft (penumbra/gl/pipelines/sample_based_soft.hpp, SoftSkips):
//     empty  SoftSkips::empty_blocks: light-pass fragments of empty list blocks return at once
//     cull   SoftSkips::closed_casters: closed casters' triangles facing away from the whole light
//            are culled in the geometry stage (drawn as CasterClass::Closed: GpuScene::drawClass)
//     cut    SoftSkips::plane_cut (per pair) and InfluenceRegionOptions::cut_by_supporting_plane
//            (the influence regions; sintorn2008 §4.3)
//     fit    the light grid's view-projection is the §4.3 fit to the view samples
//            (fitLightFrustumCpu from lightViewProjectionForBounds(light centre, the samples'
//            box)) instead of the unfitted lightViewProjectionForBounds(light centre, the box of
//            the whole scene and its view samples); where no frustum of at most 85 degrees holds
//            that box (the builtins' light above their wide ground), the unfitted grid is the
//            uncropped frustum around the samples' box (counter unfitted_scene_box = 0)
//     silhouette  SoftSkips::silhouettes: outside every potential silhouette edge's influence region
//            one exact test from the light centre per pair (the casters' adjacency drawn by
//            GpuScene::drawAdjacency)
//     wedge  SoftSkips::wedges: view samples beyond one of a caster's wedge planes get no pair
//   hard (penumbra/gl/pipelines/alias_free_hard.hpp, AliasFreeHardOptions):
//     cull = light_facing_only, fit = fit_frustum, shadowed = skip_shadowed, box = clip_to_box,
//     empty = skip_empty_texels (the occupancy stencil).
//   Methods of an entry: off (every skip off), each skip alone, all (every skip on); soft entries
//   also off_fragment and all_fragment: off and all with SampleBasedSoftGpuOptions::deferred_pairs
//   = 0 (the light pass's pairs worked in its fragment stage; every other method defers them to
//   the compute pass, the default); counters deferral_speedup = ms_all_fragment / ms_all and
//   fragment_off_over_all = ms_off_fragment / ms_all_fragment (the skips' speed-up without deferral).
//
// BM_SoftSkips/<scene>: the scene's camera view rendered into a W x H G-buffer
// (penumbra/scene/gl_scene.hpp); every pixel is a view sample, its position lifted along its face
// normal by 1e-6 of the scene's box diagonal as in sample_based_soft_bench.cpp (the one position
// buffer every method reads). Light: the scene's spherical light (scene.light.position, radius);
// one set (K = 1) of N stratified samples (makeLightSampleSets, seed 2008), no rotation; mode
// Exact with the certified LUT (R = 64, generateLightLut on the CPU once per entry, untimed; the
// tolerance is sampleBasedSoftLutTolerance's for the light and the box of the scene and samples). Light grid G x G,
// its far plane at the farthest view sample of that grid's matrix (influenceFarPlaneAtDepth, the
// same rule with and without fit). Pipeline options as sample_based_soft_bench (list blocks of 16,
// at most 256 blocks). Timed: SampleBasedSoftShadows::run with count_work = false (lists +
// predicate + light pass + resolve; the G-buffer render is shared and excluded).
//
// BM_HardSkips/<scene>: the same scene's view in a W x H G-buffer (positions and face normals,
// unlifted: the hard pipeline's coplanar rule covers them), the point light at scene.light.position
// with the starting matrix lightViewProjectionForBounds() of the view samples' box (as the demo's
// --mode hard; fit = the pipeline's own GPU refit of it), AfhPrecision::Exact, light grid = the
// view's size (sintorn2008 §3). Timed: AliasFreeHardShadows::run with count_work = false.
//
// Scenes: torus_knot, columns (builtins, default arguments) and the shared scene spot.obj
// (PENUMBRA_SHARED_SCENES_DIR/spot.obj, loadObj defaults: normalised, with ground); when that file
// is absent its entries end with SkipWithError("skipped: ... is absent").
//
// Timing: penumbra::bench::timeGpu for every timed call (GL_TIME_ELAPSED where the driver really
// measures the region, else glFinish + wall clock; one reading for every method of an entry:
// timer_gl_time_elapsed). One warm-up call of every method, then per benchmark iteration one
// timed call of every method, interleaved (the first method rotates with the iteration); each
// method's time is the median over the iterations. The entry's manual time is off's.
//
// Counters (per method m of off, <skips>, all):
//   ms_<m>                 median ms
//   off_over_<m>           ms_off / ms_<m> for every m but off (target: off_over_all >= 2)
//   mismatched_words_<m>   words of m's result that differ from off's (soft: the mask words of
//                          every view-sample id; hard: the per-sample states): must be 0; any
//                          other value ends the entry with SkipWithError after printing them
//   compared_words         words compared per method
//   soft work, from a separate untimed run per method with count_work = true:
//     pairs_<m>, fragments_<m>, fragments_skipped_<m>, triangles_culled_<m>, pairs_cut_<m>, pairs_hard_<m>,
//     pairs_recovered_<m>, pairs_wedged_<m>,
//     exact_tests_<m>, passes_<m>, overflow_<m> (samples past the last list block: untested),
//     pairs_deferred_<m> ((triangle, texel) pairs the compute pass worked)
//   hard work, likewise: fragments_<m>, tests_<m>, triangles_emitted_<m>, passes_<m>, overflow_<m>
//   scene: samples (surface view samples), triangles, closed_triangles (of closed meshes: what
//   cull may act on), grid, N, lut_resolution, fit_valid, unfitted_scene_box (soft).
//
// Sizes: soft W x H = 128 x 96, N = 256, G = 256, R = 64, 3 iterations; hard W x H = 256 x 192,
// 5 iterations.
// Smoke runs (PENUMBRA_BENCH_SMOKE=1): soft 32 x 24, N = 32, G = 64, R = 32; hard 32 x 24; the
// torus knot at tessellation 16; 1 iteration (llvmpipe, 2 cores: 17 s with a warm shader cache,
// 36 s with an empty one).
// llvmpipe runs every stage on the CPU cores: ratios, not times, are what carries over to GPUs.
// Example: PENUMBRA_GL=egl penumbra_bench_skips --benchmark_format=json > skips.json
#include "bench_common.hpp"

#include <penumbra/error.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/pipelines/sample_based_soft.hpp>
#include <penumbra/influence_region.hpp>
#include <penumbra/light_lut.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace {

namespace gl = penumbra::gl;
using penumbra::bench::timeGpu;

constexpr uint32_t kSampleSeed = 2008u;
constexpr uint32_t kSmokeTessellation = 16;  // the torus knot's under smoke runs (514 triangles)
constexpr float kLift = 1e-6f;  // soft view samples' normal offset, relative to the scene's box diagonal

struct Sizes {
    uint32_t soft_width, soft_height, samples, grid, lut_resolution;
    uint32_t hard_width, hard_height;
    int64_t soft_iterations, hard_iterations;
};

const Sizes& sizes() {
    static const Sizes s = penumbra::bench::smokeRun() ? Sizes{32, 24, 32, 64, 32, 32, 24, 1, 1}
                                                       : Sizes{128, 96, 256, 256, 64, 256, 192, 3, 5};
    return s;
}

/// A scene of the entries: a builtin (empty path) or an OBJ file.
struct SceneSpec {
    std::string name, path;
};

std::vector<SceneSpec> sceneSpecs() {
    std::vector<SceneSpec> specs = {{"torus_knot", ""}, {"columns", ""}};
#ifdef PENUMBRA_SHARED_SCENES_DIR
    specs.push_back({"spot", (std::filesystem::path(penumbra::test::sharedScenesDir()) / "spot.obj").string()});
#else
    specs.push_back({"spot", "spot.obj"});  // not found: the entry says so
#endif
    return specs;
}

/// False when the scene's file is absent (its entries then skip).
bool sceneAvailable(const SceneSpec& spec) {
    std::error_code ec;
    return spec.path.empty() || std::filesystem::is_regular_file(spec.path, ec);
}

penumbra::scene::Scene loadScene(const SceneSpec& spec) {
    if (!spec.path.empty()) return penumbra::scene::loadObj(spec.path);
    if (spec.name == "torus_knot" && penumbra::bench::smokeRun()) return penumbra::scene::torusKnot(kSmokeTessellation);
    return penumbra::scene::builtin(spec.name);
}

size_t closedTriangles(const penumbra::scene::Scene& scene) {
    size_t n = 0;
    for (const penumbra::scene::Mesh& m : scene.meshes) n += m.closed ? m.triangleCount() : 0;
    return n;
}

// ---------------------------------------------------------------------------------------------
// Timing (as sample_based_soft_bench.cpp)

using Method = penumbra::bench::TimedMethod;

/// penumbra::bench::timeInterleaved (the manual time is methods[0]'s), then ms_<name> and
/// off_over_<name> (methods[0] is off); returns the medians in ms.
std::vector<double> timeMethods(benchmark::State& state, std::vector<Method>& methods) {
    const bool query_measures = penumbra::bench::timeInterleaved(state, methods);
    std::vector<double> ms;
    for (const Method& m : methods) ms.push_back(m.ms(query_measures));
    for (size_t k = 0; k < methods.size(); ++k) {
        state.counters["ms_" + methods[k].name] = ms[k];
        if (k) state.counters["off_over_" + methods[k].name] = ms[k] > 0.0 ? ms[0] / ms[k] : 0.0;
    }
    return ms;
}

uint64_t mismatchedWords(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    if (a.size() != b.size()) return std::max(a.size(), b.size());
    uint64_t n = 0;
    for (size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
    return n;
}

/// Sets mismatched_words_<m> for every method but off; prints and returns a message naming
/// the methods whose results differ from off's (empty: every one is identical).
std::string checkIdentity(benchmark::State& state, const char* entry, const std::string& scene,
                          const std::vector<std::string>& names, const std::vector<std::vector<uint32_t>>& results) {
    std::string failed;
    state.counters["compared_words"] = double(results[0].size());
    for (size_t k = 1; k < names.size(); ++k) {
        const uint64_t n = mismatchedWords(results[k], results[0]);
        state.counters["mismatched_words_" + names[k]] = double(n);
        if (n == 0) continue;
        std::fprintf(stderr, "skips_bench %s/%s: %s differs from off in %llu of %zu words\n", entry, scene.c_str(),
                     names[k].c_str(), static_cast<unsigned long long>(n), results[0].size());
        failed += (failed.empty() ? "" : ", ") + names[k] + " (" + std::to_string(n) + " words)";
    }
    return failed.empty() ? failed : std::string("skips are not bit-identical to off: ") + failed;
}

void leaveNoBindings() {
    glBindTextureUnit(0, 0);
    for (GLuint b = 0; b < 16; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
    for (GLuint b = 0; b < 4; ++b) glBindBufferBase(GL_UNIFORM_BUFFER, b, 0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(0);
}

// ---------------------------------------------------------------------------------------------
// Soft

/// A soft method: the demo's skips as options.
struct SoftMethod {
    std::string name;
    penumbra::SoftSkips skips;
    bool fit = false;  ///< §4.3-fitted light grid
    bool cut = false;  ///< InfluenceRegionOptions::cut_by_supporting_plane (with skips.plane_cut)
    uint32_t deferred_pairs = penumbra::SampleBasedSoftGpuOptions{}.deferred_pairs;  ///< its default but in all_fragment
};

std::vector<SoftMethod> softMethods() {
    penumbra::SoftSkips none;
    none.empty_blocks = none.closed_casters = none.plane_cut = none.silhouettes = none.wedges = false;
    SoftMethod off{"off", none}, empty{"empty", none}, cull{"cull", none}, cut{"cut", none}, fit{"fit", none},
        silhouette{"silhouette", none}, wedge{"wedge", none}, all{"all", none, true, true};
    empty.skips.empty_blocks = true;
    cull.skips.closed_casters = true;
    cut.skips.plane_cut = true;
    cut.cut = true;
    fit.fit = true;
    silhouette.skips.silhouettes = true;
    wedge.skips.wedges = true;
    all.skips.empty_blocks = all.skips.closed_casters = all.skips.plane_cut = all.skips.silhouettes = all.skips.wedges = true;
    // The same two with every pair worked in the light pass's fragment stage (deferred_pairs = 0).
    SoftMethod off_fragment = off, all_fragment = all;
    off_fragment.name = "off_fragment";
    all_fragment.name = "all_fragment";
    off_fragment.deferred_pairs = all_fragment.deferred_pairs = 0;
    return {off, empty, cull, cut, fit, silhouette, wedge, all, off_fragment, all_fragment};
}

/// One scene seen through the soft G-buffer, its light samples, LUT and both light grids.
struct SoftScene {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    uint32_t count = 0;                ///< view samples (pixels)
    size_t surface = 0;                ///< with a surface (w != 0)
    std::vector<glm::vec4> positions;  ///< lifted, vec4 per view-sample id: what every method reads
    gl::Buffer lifted;
    penumbra::Light light;
    penumbra::LightSampleSets sets;
    penumbra::LightLutSetup lut;
    gl::Buffer lut_table;
    glm::mat4 unfitted{1.0f}, fitted{1.0f};
    bool fit_valid = false;
    bool unfitted_scene_box = false;  ///< the unfitted grid frames the whole scene (else the view samples' box)

    explicit SoftScene(penumbra::scene::Scene s) : scene(std::move(s)) {
        const Sizes& z = sizes();
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(z.soft_width, z.soft_height);
        gbuffer->render(*gpu, scene.camera.projection(float(z.soft_width) / float(z.soft_height)) * scene.camera.view());
        count = z.soft_width * z.soft_height;
        // sample_based_soft_bench.cpp's lift (there for the oracle; here so that both benches
        // time the same work).
        positions = gbuffer->positionBuffer().download<glm::vec4>(0, count);
        const std::vector<glm::vec4> faces = gbuffer->faceBuffer().download<glm::vec4>(0, count);
        const penumbra::scene::Bounds box = scene.bounds();
        const float lift = kLift * glm::length(box.max - box.min);
        for (uint32_t id = 0; id < count; ++id) {
            if (positions[id].w == 0.0f) continue;
            positions[id] = glm::vec4(glm::vec3(positions[id]) + lift * glm::vec3(faces[id]), 1.0f);
            ++surface;
        }
        PENUMBRA_CHECK(surface > 0, "skips_bench: the soft view shows no surface of ", scene.name);
        lifted = gl::Buffer::fromVector(positions);

        light.center = glm::dvec3(scene.light.position);
        light.size = glm::dvec3(double(scene.light.radius));
        penumbra::LightSampleOptions so;
        so.count = z.samples;
        so.sets = 1;
        so.seed = kSampleSeed;
        sets = penumbra::makeLightSampleSets(light, so);

        // The box of the scene and its view samples: the LUT's tolerance and the unfitted grid.
        const auto [samples_lo, samples_hi] = penumbra::viewSampleBounds(positions.data(), positions.size());
        const glm::vec3 all_lo = glm::min(box.min, samples_lo), all_hi = glm::max(box.max, samples_hi);

        // The LUT (certified, CPU, untimed) with the tolerance Exact needs for this light and scene.
        penumbra::SampleBasedSoftGpuOptions o;
        o.grid_width = o.grid_height = z.grid;
        penumbra::LightLutOptions lo;
        lo.resolution = z.lut_resolution;
        lo.certified = true;
        lo.tolerance = penumbra::sampleBasedSoftLutTolerance(o, sets.frame, glm::dvec3(all_lo), glm::dvec3(all_hi));
        lut = penumbra::lightLutSetup(sets, lo);
        lut_table = gl::Buffer::fromVector(penumbra::generateLightLut(lut));

        // The grids, as the demo's --skips fit: fitted = a frustum from the light centre around the
        // view samples' box, cropped to the samples by the §4.3 fit (the sample-list block's CPU
        // twin on the positions the pipeline reads, as the soft pipeline builds its lists: no
        // back-face cull, unclipped depth); unfitted = a frustum around the whole scene and its
        // view samples. Where that frustum cannot exist (a cone over 85 degrees: the light above a
        // wide ground, or inside the scene's box), the unfitted grid is the uncropped frustum
        // around the view samples' box (counter unfitted_scene_box = 0).
        penumbra::SampleListsLight fit_light;
        fit_light.light = glm::vec4(scene.light.position, 1.0f);
        fit_light.view_projection = penumbra::lightViewProjectionForBounds(fit_light.light, samples_lo, samples_hi);
        try {
            unfitted = penumbra::lightViewProjectionForBounds(fit_light.light, all_lo, all_hi);
            unfitted_scene_box = true;
        } catch (const penumbra::Error& e) {
            std::fprintf(stderr, "skips_bench %s: no frustum around the whole scene (%s): unfitted = around the view samples\n",
                         scene.name.c_str(), e.what());
            unfitted = fit_light.view_projection;
        }
        penumbra::SampleListsOptions fit_options;
        fit_options.cull_back_facing = false;
        fit_options.depth_range = penumbra::LightDepthRange::Unclipped;
        const penumbra::LightFrustumFit fit = penumbra::fitLightFrustumCpu(penumbra::sampleListsSetup(z.grid, z.grid, count),
                                                                           fit_light, positions.data(), nullptr, fit_options);
        fit_valid = fit.valid;
        fitted = fit.valid ? fit.view_projection : fit_light.view_projection;
    }

    penumbra::SampleBufferInput input() const { return {{lifted.id(), 0, lifted.size()}, {}}; }
    penumbra::BufferRange table() const { return {lut_table.id(), 0, lut_table.size()}; }

    /// The influence setup of a grid matrix: far plane just beyond the farthest view sample.
    penumbra::InfluenceRegionSetup influence(const glm::mat4& vp, bool cut) const {
        double far_depth = 0.0;
        for (const glm::vec4& p : positions) {
            if (p.w == 0.0f) continue;
            far_depth = std::max(far_depth, double((vp * glm::vec4(glm::vec3(p), 1.0f)).w));
        }
        penumbra::InfluenceRegionOptions io;
        io.grid_width = io.grid_height = int(sizes().grid);
        io.far_plane = penumbra::influenceFarPlaneAtDepth(vp, far_depth * 1.01 + 1e-3);
        io.cut_by_supporting_plane = cut;
        return penumbra::influenceRegionSetup(light, vp, io);
    }
};

/// The pipeline of one soft method, reserved and validated.
struct SoftRun {
    const SoftScene& s;
    penumbra::SampleBasedSoftShadows pipeline;
    penumbra::SampleBufferInput input;
    penumbra::BufferRange table;
    penumbra::SampleBasedSoftShadows::DrawCasters draw;
    penumbra::SampleBasedSoftShadows::DrawAdjacency draw_adjacency;
    bool ok = true;

    static penumbra::SampleBasedSoftGpuOptions options(const SoftMethod& m, bool count_work) {
        penumbra::SampleBasedSoftGpuOptions o;
        o.mode = penumbra::SoftMode::Exact;
        o.grid_width = o.grid_height = sizes().grid;
        o.max_list_blocks = 256;  // lists up to 4096 samples (the ground seen at a grazing angle)
        o.count_work = count_work;
        o.skips = m.skips;
        o.deferred_pairs = m.deferred_pairs;
        return o;
    }
    SoftRun(const SoftScene& scene, const SoftMethod& m, bool count_work)
        : s(scene),
          pipeline(options(m, count_work), scene.sets, &scene.lut, scene.influence(m.fit ? scene.fitted : scene.unfitted, m.cut),
                   m.fit ? scene.fitted : scene.unfitted),
          input(scene.input()), table(scene.table()),
          draw([&scene](penumbra::CasterClass c) { scene.gpu->drawClass(c == penumbra::CasterClass::Closed); }),
          draw_adjacency([&scene] { scene.gpu->drawAdjacency(); }) {
        pipeline.reserve(s.count);
        pipeline.validate(input, s.count, table);
    }
    void run() { ok &= pipeline.run(input, s.count, table, draw, {}, draw_adjacency) == penumbra::Status::Ok; }
};

void BM_SoftSkips(benchmark::State& state, const SceneSpec& spec) {
    if (!sceneAvailable(spec)) {
        state.SkipWithError(("skipped: " + spec.path + " is absent (the shared scenes beside the repository)").c_str());
        return;
    }
    penumbra::bench::glContext();
    try {
        const SoftScene s(loadScene(spec));
        const std::vector<SoftMethod> ms = softMethods();
        std::vector<std::unique_ptr<SoftRun>> runs;
        std::vector<Method> methods;
        for (const SoftMethod& m : ms) {
            runs.push_back(std::make_unique<SoftRun>(s, m, false));
            SoftRun* r = runs.back().get();
            methods.push_back({m.name, [r] { r->run(); }});
        }
        const std::vector<double> ms_soft = timeMethods(state, methods);
        // Methods ..., all, off_fragment, all_fragment.
        const double ms_all = ms_soft[ms.size() - 3], ms_off_fragment = ms_soft[ms.size() - 2], ms_all_fragment = ms_soft.back();
        state.counters["deferral_speedup"] = ms_all > 0.0 ? ms_all_fragment / ms_all : 0.0;
        state.counters["fragment_off_over_all"] = ms_all_fragment > 0.0 ? ms_off_fragment / ms_all_fragment : 0.0;
        gl::checkErrors("skips_bench (soft)");
        for (size_t k = 0; k < runs.size(); ++k) {
            if (!runs[k]->ok) {
                state.SkipWithError(("SampleBasedSoftShadows::run returned an error Status (" + ms[k].name + ")").c_str());
                return;
            }
        }
        std::vector<std::string> names;
        std::vector<std::vector<uint32_t>> masks;
        for (size_t k = 0; k < runs.size(); ++k) {
            names.push_back(ms[k].name);
            masks.push_back(runs[k]->pipeline.readMasks());
        }
        runs.clear();
        // Work counters: one untimed count_work run per method (one pipeline alive at a time).
        for (const SoftMethod& m : ms) {
            SoftRun counting(s, m, true);
            counting.run();
            PENUMBRA_CHECK(counting.ok, "skips_bench: the soft count_work run failed (", m.name, ")");
            const penumbra::SampleBasedSoftFrame f = counting.pipeline.readFrame();
            state.counters["pairs_" + m.name] = double(f.pairs);
            state.counters["fragments_" + m.name] = double(f.fragments);
            state.counters["fragments_skipped_" + m.name] = double(f.fragments_skipped);
            state.counters["triangles_culled_" + m.name] = double(f.triangles_culled);
            state.counters["pairs_cut_" + m.name] = double(f.pairs_cut);
            state.counters["pairs_hard_" + m.name] = double(f.pairs_hard);
            state.counters["pairs_recovered_" + m.name] = double(f.pairs_recovered);
            state.counters["pairs_wedged_" + m.name] = double(f.pairs_wedged);
            state.counters["exact_tests_" + m.name] = double(f.exact_tests);
            state.counters["passes_" + m.name] = double(f.passes);
            state.counters["overflow_" + m.name] = double(f.overflow);
            state.counters["pairs_deferred_" + m.name] = double(f.pairs_deferred);
        }
        state.counters["samples"] = double(s.surface);
        state.counters["triangles"] = double(s.scene.triangleCount());
        state.counters["closed_triangles"] = double(closedTriangles(s.scene));
        state.counters["grid"] = double(sizes().grid);
        state.counters["N"] = double(sizes().samples);
        state.counters["lut_resolution"] = double(sizes().lut_resolution);
        state.counters["fit_valid"] = s.fit_valid ? 1.0 : 0.0;
        state.counters["unfitted_scene_box"] = s.unfitted_scene_box ? 1.0 : 0.0;
        leaveNoBindings();
        const std::string failed = checkIdentity(state, "BM_SoftSkips", spec.name, names, masks);
        if (!failed.empty()) state.SkipWithError(failed.c_str());
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

// ---------------------------------------------------------------------------------------------
// Hard

struct HardMethod {
    std::string name;
    bool cull = false, fit = false, shadowed = false, box = false, empty = false;
};

std::vector<HardMethod> hardMethods() {
    return {{"off", false, false, false, false, false},     {"cull", true, false, false, false, false},
            {"fit", false, true, false, false, false},      {"shadowed", false, false, true, false, false},
            {"box", false, false, false, true, false},      {"empty", false, false, false, false, true},
            {"all", true, true, true, true, true}};
}

/// One scene seen through the hard G-buffer and its point light.
struct HardScene {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    uint32_t width = 0, height = 0;
    size_t surface = 0;
    penumbra::SampleListsLight light;

    explicit HardScene(penumbra::scene::Scene s) : scene(std::move(s)) {
        const Sizes& z = sizes();
        width = z.hard_width;
        height = z.hard_height;
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(width, height);
        gbuffer->render(*gpu, scene.camera.projection(float(width) / float(height)) * scene.camera.view());
        const std::vector<glm::vec4> positions = gbuffer->positionBuffer().download<glm::vec4>(0, samples());
        const auto [lo, hi] = penumbra::viewSampleBounds(positions.data(), positions.size(), &surface);
        PENUMBRA_CHECK(surface > 0, "skips_bench: the hard view shows no surface of ", scene.name);
        light.light = glm::vec4(scene.light.position, 1.0f);
        light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo, hi);
    }
    uint32_t samples() const { return width * height; }
    penumbra::SampleBufferInput input() const {
        auto r = [](const gl::Buffer& b) { return penumbra::BufferRange{b.id(), 0, b.size()}; };
        return {r(gbuffer->positionBuffer()), r(gbuffer->faceBuffer())};
    }
    penumbra::AliasFreeHardOptions options(const HardMethod& m, bool count_work) const {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = width;  // sintorn2008: the light grid has the view's size
        o.grid_height = height;
        o.precision = penumbra::AfhPrecision::Exact;
        o.count_work = count_work;
        o.light_facing_only = m.cull;
        o.fit_frustum = m.fit;
        o.skip_shadowed = m.shadowed;
        o.clip_to_box = m.box;
        o.skip_empty_texels = m.empty;
        return o;
    }
};

/// The pipeline of one hard method, reserved and validated.
struct HardRun {
    const HardScene& s;
    penumbra::AliasFreeHardShadows pipeline;
    penumbra::SampleBufferInput input;
    penumbra::AliasFreeHardShadows::DrawCasters draw;
    bool ok = true;

    HardRun(const HardScene& scene, const HardMethod& m, bool count_work)
        : s(scene), pipeline(scene.options(m, count_work)), input(scene.input()),
          draw([&scene](penumbra::CasterClass c) { scene.gpu->drawClass(c == penumbra::CasterClass::Closed); }) {
        pipeline.reserve(s.samples());
        pipeline.validate(input, s.samples());
    }
    void run() { ok &= pipeline.run(input, s.samples(), s.light, draw) == penumbra::Status::Ok; }
};

void BM_HardSkips(benchmark::State& state, const SceneSpec& spec) {
    if (!sceneAvailable(spec)) {
        state.SkipWithError(("skipped: " + spec.path + " is absent (the shared scenes beside the repository)").c_str());
        return;
    }
    penumbra::bench::glContext();
    try {
        const HardScene s(loadScene(spec));
        const std::vector<HardMethod> ms = hardMethods();
        std::vector<std::unique_ptr<HardRun>> runs;
        std::vector<Method> methods;
        for (const HardMethod& m : ms) {
            runs.push_back(std::make_unique<HardRun>(s, m, false));
            HardRun* r = runs.back().get();
            methods.push_back({m.name, [r] { r->run(); }});
        }
        timeMethods(state, methods);
        gl::checkErrors("skips_bench (hard)");
        for (size_t k = 0; k < runs.size(); ++k) {
            if (!runs[k]->ok) {
                state.SkipWithError(("AliasFreeHardShadows::run returned an error Status (" + ms[k].name + ")").c_str());
                return;
            }
        }
        std::vector<std::string> names;
        std::vector<std::vector<uint32_t>> states;
        for (size_t k = 0; k < runs.size(); ++k) {
            names.push_back(ms[k].name);
            states.push_back(runs[k]->pipeline.stateBuffer().download<uint32_t>(0, s.samples()));
        }
        runs.clear();
        for (const HardMethod& m : ms) {
            HardRun counting(s, m, true);
            counting.run();
            PENUMBRA_CHECK(counting.ok, "skips_bench: the hard count_work run failed (", m.name, ")");
            const penumbra::AliasFreeHardFrame f = counting.pipeline.readFrame();
            state.counters["fragments_" + m.name] = double(f.fragments);
            state.counters["tests_" + m.name] = double(f.tests);
            state.counters["triangles_emitted_" + m.name] = double(f.triangles_emitted);
            state.counters["passes_" + m.name] = double(f.passes);
            state.counters["overflow_" + m.name] = double(f.overflow);
            state.counters["spill_overflow_" + m.name] = double(f.spill_overflow);
        }
        state.counters["samples"] = double(s.surface);
        state.counters["triangles"] = double(s.scene.triangleCount());
        state.counters["closed_triangles"] = double(closedTriangles(s.scene));
        state.counters["grid"] = double(s.width) * double(s.height);
        leaveNoBindings();
        const std::string failed = checkIdentity(state, "BM_HardSkips", spec.name, names, states);
        if (!failed.empty()) state.SkipWithError(failed.c_str());
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

benchmark::internal::Benchmark* configure(benchmark::internal::Benchmark* b, int64_t iterations) {
    return b->UseManualTime()->Iterations(iterations)->Unit(benchmark::kMillisecond);
}

[[maybe_unused]] const bool kRegistered = [] {
    // The smoke run (ctest, both GL backends) keeps the torus knot alone: every method's pipeline
    // is compiled per entry, which dominates a smoke run on llvmpipe.
    const bool smoke = penumbra::bench::smokeRun();
    for (const SceneSpec& spec : sceneSpecs()) {
        if (smoke && spec.name != "torus_knot") continue;
        configure(benchmark::RegisterBenchmark(("BM_SoftSkips/" + spec.name).c_str(),
                                               [spec](benchmark::State& st) { BM_SoftSkips(st, spec); }),
                  sizes().soft_iterations);
    }
    for (const SceneSpec& spec : sceneSpecs()) {
        if (smoke && spec.name != "torus_knot") continue;
        configure(benchmark::RegisterBenchmark(("BM_HardSkips/" + spec.name).c_str(),
                                               [spec](benchmark::State& st) { BM_HardSkips(st, spec); }),
                  sizes().hard_iterations);
    }
    return true;
}();

}  // namespace
