// Eye-view anti-aliasing of alias-free hard shadows (galoppo2010, penumbra/gl/shadow_edge_stencil.hpp):
// what the provable shadow-edge stencil costs, what multi-sampling only its flagged pixels saves
// against multi-sampling every pixel, and how many edge pixels galoppo2010's Chebyshev stencil
// (the "VSM pass": a conservative moment map + Chebyshev's bound) misses — all in one entry.
//
// BM_ShadowEdgeStencil/<scene>/<N>: scenes columns, hairball, grass (built-ins) and the first *.obj
// (by name) in PENUMBRA_SHARED_SCENES_DIR (its file stem; skipped with a message on stderr when
// the folder holds none); N sub-samples per flagged pixel (rotated grid): columns N in {4, 8, 16},
// the other scenes N = 4 (a full-mode run walks P (1 + N) samples: the run time on llvmpipe).
//
// Setup (untimed, once per entry): the scene's camera view rendered into a W x W G-buffer
// (penumbra/scene/gl_scene.hpp): P = W^2 centres (positions) and face normals. The point light at
// scene.light.position; its view-projection must see every centre and sub-sample (the stencil
// flags pixels with a point outside it), so one provable stencil run with the centres' box gives
// the sub-samples (readSubSamples), and the light is lightViewProjectionForBounds() of the box of
// centres and sub-samples, grown by kLightBoxSlack of its diagonal on every side. Every method
// uses that light; the hard pipeline refits it (sintorn2008 §4.3) from there.
// Objects: AliasFreeHardOptions with grid = W x W and defaults otherwise (exact, no caster culling:
// what ShadowEdgeStencil requires); one provable ShadowEdgeStencil, one Chebyshev ShadowEdgeStencil
// (ChebyshevStencilOptions defaults: galoppo2010's threshold 1%), both with that options object;
// one AliasFreeHardShadows per mode, each with those options on the square light grid its sample
// count calls for (afhGridSideForSamples: off P samples, W here; full P (1 + N); edge budget N,
// the flagged pixels' sub-samples), so no method is timed on a grid sized for another's samples.
// The casters: every triangle of the scene, drawn for the hard pipeline's open class (no class is
// culled).
//
// Methods, all timed in the same entry (penumbra::bench::timeInterleaved: one warm-up call each,
// then per iteration one call each, interleaved with a rotating start; medians):
//   stencil    the provable stencil's run() (sub-samples, footprint lists, light pass, bits).
//   edge_hard  writeSampleBuffer(Edge, budget) + AliasFreeHardShadows::run on sampleCount(Edge,
//              budget) = P + budget N slots (the flagged pixels' sub-samples packed after the P
//              centre slots, which are all empty: the stencil decided the unflagged pixels,
//              AaUnflagged::Proven; budget = the frame's flagged count, counted in an untimed
//              run: an engine would take the last frame's plus a margin) + resolve(Edge, budget).
//   full       writeSampleBuffer(Full) + the hard run (every pixel's sub-samples) + resolve(Full).
//   off        the hard run on the P centres (the G-buffer itself) + resolve(Off).
//   chebyshev  the Chebyshev stencil's run() (sub-samples, the moment map and its levels, the test).
//   chebyshev_inner  the same with inner_shadow_proof (its "fully shadowed" claim from the
//              inner-coverage channel).
// The entry's own manual time (the Time column) is the stencil method's.
//
// Counters (times in ms, medians; timer_gl_time_elapsed: 1 = GL_TIME_ELAPSED, 0 = glFinish + wall
// clock for every method of the entry, see bench_common.hpp):
//   ms_off, ms_stencil, ms_edge_hard, ms_full, ms_chebyshev, ms_chebyshev_inner   the methods above
//   ms_edge            ms_stencil + ms_edge_hard (a frame of --aa edge)
//   edge_over_off, full_over_off, edge_over_full   ratios of those times
//   surface            pixels with a surface (centre w != 0)
//   flagged_fraction   provable-flagged surface pixels / surface; extra_samples = flagged x N
//   seed_estimate      1 + N flagged_fraction: galoppo2010's estimate of the edge cost relative to
//                      one sample per pixel; edge_over_seed_estimate = edge_over_off / seed_estimate
//                      (target <= 1: the stencil pays for itself as the estimate says);
//                      edge_hard_over_seed_estimate: the same without the stencil pass (the
//                      multi-sampling alone, the stencil timed separately)
//   chebyshev_flagged_fraction, chebyshev_inner_flagged_fraction   the same share for the Chebyshev stencils
//   edge_pixels        surface pixels whose full-mode visibility is strictly inside (0, 1)
//   err_edge_vs_full_pixels      pixels whose resolved visibility differs between edge and full
//                      (must be 0: the provable stencil's claim)
//   err_missed_edge    edge pixels the provable stencil did not flag (must be 0)
//   err_chebyshev_missed_edge    edge pixels the Chebyshev stencil did not flag (a probability:
//                      galoppo2010 accepts misses); err_chebyshev_inner_missed_edge for chebyshev_inner
//   pairs, exact_tests, list_overflow   the provable stencil's readStatus() (PENUMBRA_AA_STATUS_PAIRS,
//                      _EXACT, _LIST_OVERFLOW: overflowing pixels are flagged, safe)
//   budget, err_budget_overflow  the edge layout's budget and the flagged pixels past it (0)
//   grid_off, grid_edge, grid_full   each mode's light grid side
//   untested_full      samples of the full run the hard pipeline left PENUMBRA_AFH_UNTESTED (outside
//                      its frustum or past its list blocks; 0 expected)
// Read-backs happen after the timed runs: one more untimed full and edge run give the visibilities.
// W = 512, 3 iterations (smoke runs, PENUMBRA_BENCH_SMOKE=1: W = 64, 1 iteration, columns/4 only).
// Example: PENUMBRA_GL=egl penumbra_bench --benchmark_filter='^BM_ShadowEdgeStencil/'
#include "bench_common.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/gl/shadow_edge_stencil.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

namespace {

namespace gl = penumbra::gl;

/// The light's box grows by this share of its diagonal on every side (float rounding of the
/// sub-samples against the box corners).
constexpr float kLightBoxSlack = 0.02f;

uint32_t viewSize() { return penumbra::bench::smokeRun() ? 64u : 512u; }
int64_t iterationCount() { return penumbra::bench::smokeRun() ? 1 : 3; }

/// An entry's scene: a built-in by name, or an OBJ file when `obj` is set.
struct StencilScene {
    std::string name;
    std::string obj;
};

/// The alphabetically first *.obj of the shared scenes folder; empty when there is none.
std::string firstSharedObj() {
    const std::string dir = penumbra::test::sharedScenesDir();
    std::string first;
    if (dir.empty()) return first;
    std::error_code ec;
    for (std::filesystem::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string path = it->path().string();
        if (it->path().extension() == ".obj" && (first.empty() || path < first)) first = path;
    }
    return first;
}

penumbra::BufferRange whole(const gl::Buffer& b) { return {b.id(), 0, b.size()}; }

/// One view of a scene: G-buffer centres and normals, caster buffers, the camera (untimed setup).
struct StencilFrame {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    uint32_t size = 0, pixels = 0;
    std::vector<glm::vec4> centres;
    penumbra::SampleListsView view;

    StencilFrame(const StencilScene& spec, uint32_t w)
        : scene(spec.obj.empty() ? penumbra::scene::builtin(spec.name) : penumbra::scene::loadObj(spec.obj)), size(w),
          pixels(w * w) {
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(w, w);
        const glm::mat4 camera = scene.camera.projection(1.0f) * scene.camera.view();
        gbuffer->render(*gpu, camera);
        centres = gbuffer->positionBuffer().download<glm::vec4>();
        view.width = view.height = w;
        view.inverse_view_projection = glm::inverse(camera);
    }
    penumbra::BufferRange centreRange() const { return whole(gbuffer->positionBuffer()); }
    penumbra::BufferRange normalRange() const { return whole(gbuffer->faceBuffer()); }
    /// Every triangle; GpuScene interleaves position and normal (24 bytes a vertex).
    gl::AaCasterBuffers casters() const {
        gl::AaCasterBuffers c;
        c.stride = 24;
        c.index_count = gpu->indexCount();
        c.positions = {gpu->vertexBuffer(), 0, uint64_t(c.stride) * gpu->positions().size()};
        c.indices = {gpu->indexBuffer(), 0, 4ull * c.index_count};
        return c;
    }
    /// The point light seeing the box [lo, hi] grown by kLightBoxSlack of its diagonal.
    penumbra::SampleListsLight lightSeeing(const glm::vec3& lo, const glm::vec3& hi) const {
        penumbra::SampleListsLight light;
        light.light = glm::vec4(scene.light.position, 1.0f);
        const glm::vec3 pad(kLightBoxSlack * glm::length(hi - lo));
        light.view_projection = penumbra::lightViewProjectionForBounds(light.light, lo - pad, hi + pad);
        return light;
    }
};

double ratio(double a, double b) { return b > 0.0 ? a / b : 0.0; }

void BM_ShadowEdgeStencil(benchmark::State& state, const StencilScene& spec, uint32_t samples) {
    penumbra::bench::glContext();
    try {
        const StencilFrame f(spec, viewSize());
        const uint32_t p = f.pixels, extended = p * (1 + samples);
        penumbra::AaPatternOptions pattern;
        pattern.samples = samples;
        penumbra::AliasFreeHardOptions options;  // exact, no caster culling: what the stencil reproduces
        options.grid_width = options.grid_height = f.size;

        // Load time (untimed): programs, buffers, the light that sees every sub-sample.
        gl::ShadowEdgeStencil stencil(f.size, f.size, options, pattern);
        gl::ShadowEdgeStencil chebyshev(f.size, f.size, options, pattern, {}, 1u, penumbra::ShaderLibrary::embedded(),
                                        gl::AaStencilKind::Chebyshev);
        penumbra::ChebyshevStencilOptions inner_options;
        inner_options.inner_shadow_proof = true;
        gl::ShadowEdgeStencil chebyshev_inner(f.size, f.size, options, pattern, {}, 1u, penumbra::ShaderLibrary::embedded(),
                                              gl::AaStencilKind::Chebyshev, inner_options);
        // One hard pipeline per mode, each on the grid its sample count calls for
        // (afhGridSideForSamples: one texel per sample, as sintorn2008's view-sized grid); edge's
        // follows the budget, below.
        auto hardOptions = [&](uint64_t sample_count) {
            penumbra::AliasFreeHardOptions o = options;
            o.grid_width = o.grid_height = penumbra::afhGridSideForSamples(sample_count);
            return o;
        };
        const penumbra::AliasFreeHardOptions off_options = hardOptions(p), full_options = hardOptions(extended);
        penumbra::AliasFreeHardShadows hard_off(off_options), hard_full(full_options);
        hard_off.reserve(p);
        hard_full.reserve(extended);
        gl::Buffer sample_pos(stencil.sampleBufferBytes()), sample_nrm(stencil.sampleBufferBytes()), visible(4ull * p);
        const penumbra::SampleBufferInput centre_input{f.centreRange(), f.normalRange()};
        const penumbra::SampleBufferInput extended_input{whole(sample_pos), whole(sample_nrm)};
        hard_off.validate(centre_input, p);
        hard_full.validate(extended_input, extended);
        const gl::AaCasterBuffers casters = f.casters();

        auto [lo, hi] = penumbra::viewSampleBounds(f.centres.data(), f.centres.size());
        if (stencil.run(f.centreRange(), f.normalRange(), f.view, f.lightSeeing(lo, hi), casters) != penumbra::Status::Ok) {
            state.SkipWithError("ShadowEdgeStencil::run (sub-sample pass) returned an error Status");
            return;
        }
        const std::vector<glm::vec4> subs = stencil.readSubSamples();
        size_t sub_count = 0;
        const auto [sub_lo, sub_hi] = penumbra::viewSampleBounds(subs.data(), subs.size(), &sub_count);
        if (sub_count > 0) {
            lo = glm::min(lo, sub_lo);
            hi = glm::max(hi, sub_hi);
        }
        const penumbra::SampleListsLight light = f.lightSeeing(lo, hi);

        const penumbra::AliasFreeHardShadows::DrawCasters draw = [&f](penumbra::CasterClass cls) {
            if (cls == penumbra::CasterClass::Open) f.gpu->draw();  // every triangle, never culled
        };
        // The edge layout's budget: this frame's flagged count (an engine would take the last
        // frame's plus a margin), from one more untimed run with the final light.
        const bool runs_ok_setup = stencil.run(f.centreRange(), f.normalRange(), f.view, light, casters) == penumbra::Status::Ok;
        uint32_t budget = 0;
        for (uint32_t word : stencil.readStencil()) budget += (word & PENUMBRA_AA_FLAG) != 0;
        const penumbra::AliasFreeHardOptions edge_options = hardOptions(uint64_t(budget) * samples);
        penumbra::AliasFreeHardShadows hard_edge(edge_options);
        hard_edge.reserve(stencil.sampleCount(penumbra::AaMode::Edge, budget));
        hard_edge.validate(extended_input, stencil.sampleCount(penumbra::AaMode::Edge, budget));
        bool runs_ok = runs_ok_setup;
        auto stencilRun = [&](gl::ShadowEdgeStencil* s) {
            return [&, s] {
                runs_ok &= s->run(f.centreRange(), f.normalRange(), f.view, light, casters) == penumbra::Status::Ok;
            };
        };
        auto hardAndResolve = [&](penumbra::AaMode mode) {
            if (mode != penumbra::AaMode::Off)
                runs_ok &= stencil.writeSampleBuffer(mode, whole(sample_pos), whole(sample_nrm), budget) == penumbra::Status::Ok;
            const bool off = mode == penumbra::AaMode::Off;
            penumbra::AliasFreeHardShadows& hard = off ? hard_off : mode == penumbra::AaMode::Edge ? hard_edge : hard_full;
            const uint32_t count = stencil.sampleCount(mode, budget);
            runs_ok &= hard.run(off ? centre_input : extended_input, count, light, draw) == penumbra::Status::Ok;
            runs_ok &= stencil.resolve(mode, {hard.stateBuffer().id(), 0, 4ull * count}, whole(visible), budget) ==
                       penumbra::Status::Ok;
        };
        std::vector<penumbra::bench::TimedMethod> methods;
        methods.push_back({"stencil", stencilRun(&stencil), {}, {}});
        methods.push_back({"edge_hard", [&] { hardAndResolve(penumbra::AaMode::Edge); }, {}, {}});
        methods.push_back({"full", [&] { hardAndResolve(penumbra::AaMode::Full); }, {}, {}});
        methods.push_back({"off", [&] { hardAndResolve(penumbra::AaMode::Off); }, {}, {}});
        methods.push_back({"chebyshev", stencilRun(&chebyshev), {}, {}});
        methods.push_back({"chebyshev_inner", stencilRun(&chebyshev_inner), {}, {}});
        const bool query_measures = penumbra::bench::timeInterleaved(state, methods);
        gl::checkErrors("shadow_edge_stencil_bench");
        if (!runs_ok) {
            state.SkipWithError("a ShadowEdgeStencil or AliasFreeHardShadows call returned an error Status");
            return;
        }

        // Times and ratios, measured in this entry.
        auto ms = [&](const char* name) {
            for (const auto& m : methods) {
                if (m.name == name) return m.ms(query_measures);
            }
            return 0.0;
        };
        const double ms_edge = ms("stencil") + ms("edge_hard");
        for (const auto& m : methods) state.counters["ms_" + m.name] = m.ms(query_measures);
        state.counters["ms_edge"] = ms_edge;
        const double edge_over_off = ratio(ms_edge, ms("off"));
        state.counters["edge_over_off"] = edge_over_off;
        state.counters["full_over_off"] = ratio(ms("full"), ms("off"));
        state.counters["edge_over_full"] = ratio(ms_edge, ms("full"));

        // Read-backs (untimed): both stencils of the last timed runs, then one full and one edge run.
        const std::vector<uint32_t> words = stencil.readStencil();
        const std::vector<uint32_t> cheb_words = chebyshev.readStencil();
        const std::vector<uint32_t> inner_words = chebyshev_inner.readStencil();
        const auto status = stencil.readStatus();
        hardAndResolve(penumbra::AaMode::Full);
        const std::vector<float> full_visible = visible.download<float>();
        const std::vector<uint32_t> full_states = hard_full.stateBuffer().download<uint32_t>(0, extended);
        hardAndResolve(penumbra::AaMode::Edge);
        const std::vector<float> edge_visible = visible.download<float>();
        if (!runs_ok) {
            state.SkipWithError("a read-back run returned an error Status");
            return;
        }

        size_t surface = 0, flagged = 0, cheb_flagged = 0, edge_pixels = 0, missed = 0, cheb_missed = 0, differing = 0;
        size_t inner_flagged = 0, inner_missed = 0;
        for (uint32_t i = 0; i < p; ++i) {
            differing += edge_visible[i] != full_visible[i];
            if (f.centres[i].w == 0.0f) continue;
            ++surface;
            const bool flag = (words[i] & PENUMBRA_AA_FLAG) != 0, cheb_flag = (cheb_words[i] & PENUMBRA_AA_FLAG) != 0;
            flagged += flag;
            cheb_flagged += cheb_flag;
            const bool inner_flag = (inner_words[i] & PENUMBRA_AA_FLAG) != 0;
            inner_flagged += inner_flag;
            if (full_visible[i] > 0.0f && full_visible[i] < 1.0f) {
                ++edge_pixels;
                missed += !flag;
                cheb_missed += !cheb_flag;
                inner_missed += !inner_flag;
            }
        }
        size_t untested = 0;
        for (uint32_t s : full_states) untested += s == PENUMBRA_AFH_UNTESTED;
        const double flagged_fraction = surface ? double(flagged) / double(surface) : 0.0;
        const double seed_estimate = 1.0 + double(samples) * flagged_fraction;
        state.counters["surface"] = double(surface);
        state.counters["flagged_fraction"] = flagged_fraction;
        state.counters["extra_samples"] = double(flagged) * samples;
        state.counters["seed_estimate"] = seed_estimate;
        state.counters["edge_over_seed_estimate"] = edge_over_off / seed_estimate;
        state.counters["edge_hard_over_seed_estimate"] = ratio(ms("edge_hard"), ms("off")) / seed_estimate;
        state.counters["chebyshev_inner_flagged_fraction"] = surface ? double(inner_flagged) / double(surface) : 0.0;
        state.counters["err_chebyshev_inner_missed_edge"] = double(inner_missed);
        state.counters["chebyshev_flagged_fraction"] = surface ? double(cheb_flagged) / double(surface) : 0.0;
        state.counters["edge_pixels"] = double(edge_pixels);
        state.counters["err_edge_vs_full_pixels"] = double(differing);
        state.counters["err_missed_edge"] = double(missed);
        state.counters["err_chebyshev_missed_edge"] = double(cheb_missed);
        state.counters["pairs"] = double(status[PENUMBRA_AA_STATUS_PAIRS]);
        state.counters["exact_tests"] = double(status[PENUMBRA_AA_STATUS_EXACT]);
        state.counters["list_overflow"] = double(status[PENUMBRA_AA_STATUS_LIST_OVERFLOW]);
        state.counters["untested_full"] = double(untested);
        state.counters["budget"] = double(budget);
        state.counters["grid_off"] = double(off_options.grid_width);
        state.counters["grid_edge"] = double(edge_options.grid_width);
        state.counters["grid_full"] = double(full_options.grid_width);
        state.counters["err_budget_overflow"] = double(stencil.readStatus()[PENUMBRA_AA_STATUS_BUDGET_OVERFLOW]);
        if (differing + missed > 0) {
            std::fprintf(stderr, "shadow_edge_stencil_bench %s/%u: %zu pixels differ between edge and full, %zu edge pixels"
                                 " unflagged\n", spec.name.c_str(), samples, differing, missed);
        }

        // Leave no binding of ours behind for the next entry.
        glUseProgram(0);
        glBindVertexArray(0);
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

void registerEntry(const StencilScene& spec, uint32_t samples) {
    const std::string name = "BM_ShadowEdgeStencil/" + spec.name + "/" + std::to_string(samples);
    benchmark::RegisterBenchmark(name.c_str(), [spec, samples](benchmark::State& s) { BM_ShadowEdgeStencil(s, spec, samples); })
        ->UseManualTime()
        ->Iterations(iterationCount())
        ->Unit(benchmark::kMillisecond);
}

[[maybe_unused]] const bool kRegistered = [] {
    // The smoke run (ctest, both GL backends) keeps columns/4 alone: each entry compiles the
    // stencil's, the Chebyshev pass's and the hard pipeline's programs, which dominates on llvmpipe.
    const bool smoke = penumbra::bench::smokeRun();
    for (uint32_t n : {4u, 8u, 16u}) {
        if (!smoke || n == 4) registerEntry({"columns", ""}, n);
    }
    if (smoke) return true;
    registerEntry({"hairball", ""}, 4);
    registerEntry({"grass", ""}, 4);
    const std::string obj = firstSharedObj();
    if (obj.empty()) {
        std::fprintf(stderr, "shadow_edge_stencil_bench: no *.obj in '%s': the OBJ entry is skipped\n",
                     penumbra::test::sharedScenesDir().c_str());
    } else {
        registerEntry({std::filesystem::path(obj).stem().string(), obj}, 4);
    }
    return true;
}();

}  // namespace
