// Sample-based soft shadows (sintorn2008 §4, penumbra/gl/pipelines/sample_based_soft.hpp): run
// time next to error against the exact oracle, the seed's §5 measurements. Every entry reports
// err_* counters; ratios between methods are measured inside one entry, the methods timed
// interleaved.
//
// Scene and view samples (untimed, cached): the torus knot with its ground
// (penumbra::scene::torusKnot(tessellation), default tessellation 64 = 8194 triangles) rendered
// by its default camera into a W x H G-buffer (penumbra/scene/gl_scene.hpp); every pixel is a view
// sample (background pixels have w = 0). The G-buffer's positions, lifted along their face normal
// by 1e-6 of the scene's box diagonal (see View: without it float rounding leaves a few percent of
// them just inside their own surface, self-shadowed for the oracle and the pipeline), are the one
// position buffer every method reads, and in double the oracle's receivers. Light: the scene's
// spherical light (scene.light.position, radius scene.light.radius x radius%/100); one set (K = 1)
// of N stratified samples (makeLightSampleSets, seed 2008), so every method — the pipeline, the
// averaged shadow maps, the oracle — uses the very same world light samples for every view sample
// (no per-pixel set choice: the baselines would need K x N maps). Certified LUT, R = 64
// (generateLightLut on the CPU, built once per (N, tolerance) outside every timed region; the
// tolerance is sampleBasedSoftLutTolerance's for the light, 1e-6 but for near-point lights).
// Light grid: G x G from lightViewProjectionForBounds(light centre, the samples' box) cropped to
// the samples by the §4.3 fit (fitLightFrustumCpu on the positions the pipeline reads), far
// plane at the farthest view sample (influenceFarPlaneAtDepth), as soft_shadows --mode soft.
// G = 256 for the 128 x 96 view: a finer grid makes the influence regions cover fewer samples
// they cannot shadow (pairs), a coarser one emits fewer empty fragments; on the fitted grid
// (soft_shadows --mode soft --view-samples exact --width 128 --height 96 --sets 1 --rotations 1,
// N = 128, llvmpipe) G = 64 / 128 / 256 / 512 took 2.4 / 1.17 / 1.13 / 2.0 s (1.32M / 0.97M /
// 0.82M / 0.75M pairs, 0.33M / 0.48M / 1.6M / 5.9M fragments).
// Oracle: reference::VisibilityOracle on the scene's triangles, default tolerances (the pipeline's
// options.oracle), evaluated once per (scene, radius, N) on the surface samples.
//
// Timing: penumbra::bench::timeGpu for every timed call (GL_TIME_ELAPSED where the driver really
// measures the region, else glFinish + wall clock). One warm-up call of
// every method, then per benchmark iteration one timed call of every method of the entry,
// interleaved (the first method rotates with the iteration); each method's time is the median over
// the iterations (ms, ms_<method>), read the same way for every method of the entry
// (timer_gl_time_elapsed says which). The entry's manual time is its first method's. Timed for the
// pipeline: SampleBasedSoftShadows::run with count_work = false (lists + predicate + light pass +
// resolve; the G-buffer render is shared and excluded). Work counters come from a separate,
// untimed run with count_work = true.
//
// Error counters (the first method's unsuffixed, the others' with _<method>), on the surface
// samples, against the oracle with the same light samples:
//   err_mismatched_bits   mismatched bits / compared bits (sample x light sample), the oracle's
//                         ties excluded (exact and brute: 0 by construction)
//   err_mismatched_count  mismatched bits; ties = oracle tie bits; untested = samples the method
//                         left without a verdict (counted as fully visible in the RMSE)
//   err_visibility_rmse   RMS over the surface samples of (visible fraction - the oracle's
//                         1 - blocked / N); err_visibility_max its largest absolute difference
//
// Entries:
//   BM_SoftShadows/<N>/<mode>        N = 128, 256, 512, 1024; mode exact and lut (brute at 128).
//                                    Work: pairs, pairs_front (decided at once: the whole light
//                                    in front of one plane, no table read), fragments, passes,
//                                    exact_tests, uncertain_bits
//                                    (fraction of the pairs' bits the certified LUT left to the
//                                    exact test), tests_per_sample (pairs / surface samples),
//                                    overflow, max_list_length, pairs_deferred ((triangle,
//                                    texel) pairs the compute pass worked: deferred_pairs, sized
//                                    W * H * 128 here, at most 16 776 960), deferral_fallbacks
//                                    (passes drawn again by the fragment stage after an overflow;
//                                    with the compute pass: runs whose pairs the coverage pass
//                                    worked itself), chunks (compute pass: runs of the deferred
//                                    passes that had work), gpu_bytes (memoryBytes(): all the
//                                    pipeline allocated), gpu_bytes_bound (memoryBound(): known
//                                    before construction, >= gpu_bytes), ns_per_pair (ms / pairs).
//   BM_SoftShadowsNScaling           exact and lut at N = 128 and 1024, all four interleaved:
//                                    n1024_over_n128 = ms_exact_n1024 / ms (exact at 128; target
//                                    <= 1.5, the seed's Fig. 13 ~2), n1024_over_n128_lut.
//   BM_SoftShadowsComputeNScaling    the same with the compute light pass.
//   BM_SoftShadowsCoverage           exact and lut at N = 256, each with the coverage pass
//                                    (SampleBasedSoftGpuOptions::coverage_texels, the default) and
//                                    with every influence region drawn (_drawn, coverage_texels = 0),
//                                    all four interleaved: coverage_speedup = ms_drawn / ms,
//                                    coverage_speedup_lut = ms_lut_drawn / ms_lut.
//   BM_SoftShadowsCompute            exact and lut at N = 256 with the compute light pass
//                                    (SoftLightPass::Compute: casters as buffers, no draw) and the
//                                    raster one (_raster, the default options), all four
//                                    interleaved: compute_speedup = ms_raster / ms,
//                                    compute_speedup_lut = ms_lut_raster / ms_lut.
//   BM_SoftShadowsRadius/<percent>   exact, N = 256, the light radius at 10 ... 400 % of the
//                                    scene's (sintorn2008 Fig. 12).
//   BM_SoftShadowsTriangles/<tess>   exact, N = 128, torusKnot(tess): 2 tess^2 + 2 triangles
//                                    (sintorn2008 Fig. 11); counter triangles.
//   BM_SoftShadowsComputeTriangles/<tess>  exact, N = 256, compute light pass, torusKnot(tess) at
//                                    tess 64 ... 512 (8k ... 524k triangles): how the time per pair
//                                    (ns_per_pair; per_pair_over_first against tess 64 in the same
//                                    run, target <= 2), chunks and gpu_bytes grow with triangles.
//   BM_SoftShadowsComputeRadius/<percent>  the same at tess 64 with the light radius x1, x4, x16.
//   BM_ShadowMapsAveraged/256        N = 256 depth maps, one per light sample, averaged
//                                    (soft_baselines.hpp: map_size^2 GL_DEPTH_COMPONENT32F,
//                                    polygon offset (2, 4), nearest texel); ours (exact, N = 256)
//                                    timed interleaved: ours_speedup = ms / ms_ours (target >= 20,
//                                    the seed's §5 ~10), ours_error_le_maps = 1 when ours' mismatch
//                                    and RMSE are both <= the maps'; the same for our lut mode
//                                    (ms_ours_lut, err_*_ours_lut, ours_lut_speedup,
//                                    ours_lut_error_le_maps: the seed's approximation, whose
//                                    error is far below the maps'); and ours (exact) with the
//                                    compute light pass (ms_ours_compute, ours_compute_speedup).
//   BM_ShadowMapsAveraged/256/map:<S> the same at other map sizes S (512, 2048, 4096, 8192; smoke:
//                                    64, 256): the maps' time against their error, which falls
//                                    slowly with S (their bias and texel aliasing), with ours
//                                    timed again in each entry (ours_speedup at every S).
//   BM_Pcss                          PCSS from one map_size^2 map at the light's centre (32
//                                    blocker-search taps, 64 filter taps); its RMSE against the
//                                    N = 256 oracle (err_visibility_rmse) and, because ours equals
//                                    that oracle, also both methods against an oracle with another
//                                    set of 1024 samples (the continuous-light proxy:
//                                    err_visibility_rmse_n1024, err_visibility_rmse_n1024_ours);
//                                    pcss_rmse_over_ours (n1024 figures) and pcss_time_over_ours =
//                                    ms / ms_ours: its error relative to ours, and at what time.
//   BM_Pcss/equal_time               PCSS given our time: per map size (map_size, 2x, 4x) the taps
//                                    grow by sqrt(2) steps (up to 128x) until one run takes at least
//                                    ours; the configuration closest to the proxy is timed against
//                                    ours with BM_Pcss's counters (map_size, blocker_taps,
//                                    filter_taps: the one chosen).
// Sizes: W x H = 128 x 96, G = 256, maps 1024^2, 3 iterations (llvmpipe: one exact run at N = 1024
// takes ~10 s). Smoke runs (PENUMBRA_BENCH_SMOKE=1):
// 32 x 24, G = 32, tessellation 8, R = 32, maps 128^2, N = 128 only (1024 in the scaling entry),
// two radii and two tessellations, 1 iteration. PENUMBRA_SOFT_BENCH_VIEW=WxH[xG] sets the view and
// the grid of a full run (sintorn2008 §5 measured at 512^2: 512x512x1024 on a real GPU; the
// oracle's cost grows with W H N, on every core); a malformed value stops every entry with a
// message naming it.
// llvmpipe runs every stage on the CPU cores: ratios, not times, are what carries over to GPUs.
// Example: PENUMBRA_GL=egl penumbra_bench_soft --benchmark_format=json > soft.json
//          /usr/bin/python3 tools/plot_bench.py soft.json -o soft_plots/
#include "bench_common.hpp"
#include "soft_baselines.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/pipelines/sample_based_soft.hpp>
#include <penumbra/influence_region.hpp>
#include <penumbra/light_lut.hpp>
#include <penumbra/light_samples.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace {

namespace gl = penumbra::gl;
namespace ref = penumbra::reference;
using penumbra::SoftMode;
using penumbra::bench::timeGpu;

constexpr uint32_t kSampleSeed = 2008u;
constexpr float kLift = 1e-6f;  // view samples' normal offset, relative to the scene's box diagonal
constexpr uint32_t kBaselineSamples = 256;  // BM_ShadowMapsAveraged/256, BM_Pcss
constexpr uint32_t kPcssBlockerTaps = 32, kPcssFilterTaps = 64;
constexpr int kPcssMaxTapSteps = 14;  // BM_Pcss/equal_time: taps up to 128x (sqrt(2) steps)

struct Sizes {
    uint32_t width, height, grid, lut_resolution, map_size, tessellation;
    int64_t iterations;
};

/// PENUMBRA_SOFT_BENCH_VIEW=WxH or WxHxG replaces the view's W x H (and the light grid's G) of a
/// full run, e.g. 512x512x1024 for sintorn2008 §5's 512^2 viewport on a real GPU; W, H in
/// [8, 4096], G in [16, 4096] (G stays 256 when not given). Anything else leaves the defaults and
/// every entry stops with sizesError()'s message, which names the variable and its value.
std::string& sizesErrorSlot() {
    static std::string error;
    return error;
}
const std::string& sizesError() { return sizesErrorSlot(); }

Sizes makeSizes() {
    if (penumbra::bench::smokeRun()) return Sizes{32, 24, 32, 32, 128, 8, 1};
    Sizes s{128, 96, 256, 64, 1024, 64, 3};
    const char* env = std::getenv("PENUMBRA_SOFT_BENCH_VIEW");
    if (!env || !*env) return s;
    unsigned long values[3] = {0, 0, s.grid};
    const char* at = env;
    int parsed = 0;
    for (; parsed < 3; ++parsed) {
        if (*at < '0' || *at > '9') break;
        char* end = nullptr;
        values[parsed] = std::strtoul(at, &end, 10);
        at = end;
        if (*at != 'x') {
            ++parsed;
            break;
        }
        ++at;
    }
    const bool ok = *at == '\0' && parsed >= 2 && values[0] >= 8 && values[0] <= 4096 && values[1] >= 8 &&
                    values[1] <= 4096 && values[2] >= 16 && values[2] <= 4096;
    if (!ok) {
        sizesErrorSlot() = std::string("PENUMBRA_SOFT_BENCH_VIEW must be WxH or WxHxG (W, H in [8, 4096], G in [16, 4096]), got '") +
                           env + "'";
        return s;
    }
    s.width = uint32_t(values[0]);
    s.height = uint32_t(values[1]);
    s.grid = uint32_t(values[2]);
    return s;
}

const Sizes& sizes() {
    static const Sizes s = makeSizes();
    return s;
}

/// Stops the entry when PENUMBRA_SOFT_BENCH_VIEW could not be read (sizesError()).
bool sizesRejected(benchmark::State& state) {
    if (sizesError().empty()) return false;
    state.SkipWithError(sizesError().c_str());
    return true;
}

std::vector<uint32_t> sampleCounts() {
    if (penumbra::bench::smokeRun()) return {128u};
    return {128u, 256u, 512u, 1024u};
}
std::vector<uint32_t> radiusPercents() {
    if (penumbra::bench::smokeRun()) return {50u, 200u};
    return {10u, 50u, 100u, 200u, 400u};
}
/// BM_ShadowMapsAveraged/256/map:<size>: the maps' sizes besides sizes().map_size.
std::vector<uint32_t> mapSizeSweep() {
    if (penumbra::bench::smokeRun()) return {64u, 256u};
    return {512u, 2048u, 4096u, 8192u};
}
std::vector<uint32_t> tessellations() {
    if (penumbra::bench::smokeRun()) return {8u, 16u};
    return {16u, 32u, 64u, 128u};
}
/// BM_SoftShadowsComputeTriangles: 8k, 32k, 131k and 524k triangles.
std::vector<uint32_t> computeTessellations() {
    if (penumbra::bench::smokeRun()) return {8u, 16u};
    return {64u, 128u, 256u, 512u};
}
/// BM_SoftShadowsComputeRadius: the light radius x1, x4, x16.
std::vector<uint32_t> computeRadiusPercents() {
    if (penumbra::bench::smokeRun()) return {100u, 400u};
    return {100u, 400u, 1600u};
}

// ---------------------------------------------------------------------------------------------
// Fixtures (untimed, cached across entries and repetitions)

/// One torus knot seen through the G-buffer: the view samples and the oracle's scene.
struct View {
    penumbra::scene::Scene scene;
    std::unique_ptr<penumbra::scene::GpuScene> gpu;
    std::unique_ptr<penumbra::scene::GBuffer> gbuffer;
    uint32_t count = 0;                 ///< view samples (pixels)
    std::vector<uint32_t> surface;      ///< ids with a surface (w != 0), ascending
    std::vector<glm::dvec3> receivers;  ///< their float positions in double: the oracle's receivers
    glm::vec3 lo{0.0f}, hi{0.0f};       ///< the surface samples' box
    std::vector<glm::vec4> positions;   ///< vec4 per view-sample id: the positions every method uses
    gl::Buffer lifted;                  ///< ... on the GPU
    std::unique_ptr<ref::VisibilityOracle> oracle;

    explicit View(uint32_t tessellation) : scene(penumbra::scene::torusKnot(tessellation)) {
        const Sizes& z = sizes();
        gpu = std::make_unique<penumbra::scene::GpuScene>(scene);
        gbuffer = std::make_unique<penumbra::scene::GBuffer>(z.width, z.height);
        gbuffer->render(*gpu, scene.camera.projection(float(z.width) / float(z.height)) * scene.camera.view());
        count = z.width * z.height;
        // sintorn2008 §4 tests every view sample against every caster whose influence region
        // covers it, the sample's own triangle included; the oracle ignores a triangle only
        // within its coplanar tolerance (1e-9 relative, the pipeline's default). The G-buffer's
        // float positions lie up to ~1e-7 off their triangle, so a few percent of them (where
        // the rounding went inwards) would be shadowed by their own surface for every light
        // sample, in the oracle and in the pipeline alike, while the baselines' depth bias hides
        // it. Lift every sample along its face normal by kLift of the scene's size (an engine's
        // normal offset, far below any shadow feature) and give every method the lifted positions.
        positions = gbuffer->positionBuffer().download<glm::vec4>(0, count);
        const std::vector<glm::vec4> faces = gbuffer->faceBuffer().download<glm::vec4>(0, count);
        const penumbra::scene::Bounds box = scene.bounds();
        const float lift = kLift * glm::length(box.max - box.min);
        for (uint32_t id = 0; id < count; ++id) {
            if (positions[id].w == 0.0f) continue;
            positions[id] = glm::vec4(glm::vec3(positions[id]) + lift * glm::vec3(faces[id]), 1.0f);
            surface.push_back(id);
            receivers.push_back(glm::dvec3(glm::vec3(positions[id])));
        }
        PENUMBRA_CHECK(!surface.empty(), "sample_based_soft_bench: the view shows no surface");
        std::tie(lo, hi) = penumbra::viewSampleBounds(positions.data(), positions.size());
        lifted = gl::Buffer::fromVector(positions);
        oracle = std::make_unique<ref::VisibilityOracle>(gpu->positions(), gpu->indices());
    }
    penumbra::SampleBufferInput input() const {
        return {{lifted.id(), 0, lifted.size()}, {}};
    }
};

View& view(uint32_t tessellation) {
    static std::map<uint32_t, std::unique_ptr<View>> cache;
    auto& v = cache[tessellation];
    if (!v) v = std::make_unique<View>(tessellation);
    return *v;
}

/// A light of the view's scene at radius% of its radius, N samples: sets, grid, influence
/// regions and the oracle's verdicts on the view's surface samples.
struct LightConfig {
    penumbra::Light light;
    penumbra::LightSampleSets sets;
    glm::mat4 view_projection{1.0f};
    penumbra::InfluenceRegionSetup influence;
    ref::VisibilityResult truth;
    double tolerance = 1e-6;  ///< the certified LUT's (sampleBasedSoftLutTolerance)

    LightConfig(const View& v, uint32_t radius_percent, uint32_t n, uint32_t seed) {
        light.center = glm::dvec3(v.scene.light.position);
        light.size = glm::dvec3(double(v.scene.light.radius) * radius_percent / 100.0);
        penumbra::LightSampleOptions so;
        so.count = n;
        so.sets = 1;
        so.seed = seed;
        sets = penumbra::makeLightSampleSets(light, so);
        // The grid: a frustum around the samples cropped to them by the §4.3 fit (the sample-list
        // block's CPU twin on the positions the pipeline reads), as soft_shadows --mode soft does.
        penumbra::SampleListsLight fit_light;
        fit_light.light = glm::vec4(v.scene.light.position, 1.0f);
        fit_light.view_projection = penumbra::lightViewProjectionForBounds(fit_light.light, v.lo, v.hi);
        penumbra::SampleListsOptions fit_options;
        fit_options.cull_back_facing = false;  // as the soft pipeline builds its lists
        fit_options.depth_range = penumbra::LightDepthRange::Unclipped;
        const penumbra::LightFrustumFit fit = penumbra::fitLightFrustumCpu(
            penumbra::sampleListsSetup(sizes().grid, sizes().grid, v.count), fit_light, v.positions.data(), nullptr, fit_options);
        view_projection = fit.valid ? fit.view_projection : fit_light.view_projection;
        // The LUT tolerance Exact needs to prove pairs for this light and scene (near-point lights
        // need more than the default 1e-6: sampleBasedSoftLutTolerance).
        const penumbra::scene::Bounds box = v.scene.bounds();
        penumbra::SampleBasedSoftGpuOptions o;
        o.grid_width = o.grid_height = sizes().grid;
        tolerance = penumbra::sampleBasedSoftLutTolerance(o, sets.frame, glm::dvec3(box.min), glm::dvec3(box.max));
        double far_depth = 0.0;
        for (const glm::dvec3& p : v.receivers)
            far_depth = std::max(far_depth, double((view_projection * glm::vec4(glm::vec3(p), 1.0f)).w));
        penumbra::InfluenceRegionOptions io;
        io.grid_width = io.grid_height = int(sizes().grid);
        io.far_plane = penumbra::influenceFarPlaneAtDepth(view_projection, far_depth * 1.01 + 1e-3);
        influence = penumbra::influenceRegionSetup(light, view_projection, io);
        truth = v.oracle->evaluate(v.receivers, std::vector<glm::dvec3>(sets.worldSet(0), sets.worldSet(0) + n));
    }
    std::vector<glm::dvec3> worldSamples() const {
        return std::vector<glm::dvec3>(sets.worldSet(0), sets.worldSet(0) + sets.count());
    }
};

LightConfig& lightConfig(uint32_t tessellation, uint32_t radius_percent, uint32_t n, uint32_t seed = kSampleSeed) {
    static std::map<std::tuple<uint32_t, uint32_t, uint32_t, uint32_t>, std::unique_ptr<LightConfig>> cache;
    auto& c = cache[{tessellation, radius_percent, n, seed}];
    if (!c) c = std::make_unique<LightConfig>(view(tessellation), radius_percent, n, seed);
    return *c;
}

/// The certified LUT for N samples and a tolerance (the normalised samples do not depend on the
/// radius; the tolerance does, for near-point lights).
struct Lut {
    std::vector<glm::dvec3> local;  ///< the samples it was built for (checked on reuse)
    penumbra::LightLutSetup setup;
    gl::Buffer table;
};

const Lut& lut(const penumbra::LightSampleSets& sets, double tolerance) {
    static std::map<std::pair<uint32_t, double>, std::unique_ptr<Lut>> cache;
    auto& l = cache[{sets.count(), tolerance}];
    if (!l) {
        l = std::make_unique<Lut>();
        l->local = sets.local;
        penumbra::LightLutOptions options;
        options.resolution = sizes().lut_resolution;
        options.certified = true;
        options.tolerance = tolerance;
        l->setup = penumbra::lightLutSetup(sets, options);
        l->table = gl::Buffer::fromVector(penumbra::generateLightLut(l->setup));
    }
    PENUMBRA_CHECK(l->local == sets.local, "sample_based_soft_bench: the cached LUT was built for other samples");
    return *l;
}

/// The pipeline on a view and a light, ready to run (reserved and validated).
struct Ours {
    const View& v;
    const Lut& l;
    SoftMode mode;
    penumbra::SoftLightPass light_pass;
    penumbra::SampleBasedSoftShadows pipeline;
    penumbra::SampleBufferInput input;
    penumbra::BufferRange table;
    penumbra::SampleBasedSoftShadows::DrawCasters draw;
    bool ok = true;

    static penumbra::SampleBasedSoftGpuOptions options(SoftMode mode, bool count_work, uint32_t coverage_texels,
                                                       penumbra::SoftLightPass light_pass) {
        penumbra::SampleBasedSoftGpuOptions o;
        o.light_pass = light_pass;
        o.coverage_texels = coverage_texels;
        o.mode = mode;
        o.grid_width = o.grid_height = sizes().grid;
        o.max_list_blocks = 256;  // lists up to 4096 samples (the ground seen at a grazing angle)
        o.count_work = count_work;
        // Deferred pairs sized to the view as an engine would (the scenes here take 20-60 pairs per
        // view sample, up to ~480 with the largest light; fragments past the pairs buffer go whole
        // to the fragments buffer, and a draw that overflows that too is drawn again by the
        // fragment stage).
        const uint32_t per_view = std::min<uint32_t>(65535u * 256u, sizes().width * sizes().height * 128u);
        o.deferred_pairs = std::max<uint32_t>(o.deferred_pairs, per_view);
        o.deferred_fragments = std::min<uint32_t>(65535u * 256u, 2 * per_view);
        o.deferred_triangles = light_pass == penumbra::SoftLightPass::Compute ? 0u : 1u << 18;  // Compute: its own default
        return o;
    }
    Ours(const View& view, const LightConfig& c, const Lut& lut, SoftMode m, bool count_work,
         uint32_t coverage_texels = penumbra::SampleBasedSoftGpuOptions{}.coverage_texels,
         penumbra::SoftLightPass pass = penumbra::SoftLightPass::Raster)
        : v(view), l(lut), mode(m), light_pass(pass),
          pipeline(options(m, count_work, coverage_texels, pass), c.sets, m == SoftMode::Brute ? nullptr : &lut.setup, c.influence,
                   c.view_projection),
          input(view.input()),
          table(m == SoftMode::Brute ? penumbra::BufferRange{} : penumbra::BufferRange{lut.table.id(), 0, lut.table.size()}),
          draw([&view](penumbra::CasterClass c) { view.gpu->drawClass(c == penumbra::CasterClass::Closed); }) {
        pipeline.reserve(v.count);
        pipeline.validate(input, v.count, table);
    }
    void run() {
        if (light_pass == penumbra::SoftLightPass::Compute) {
            const std::vector<penumbra::CasterBuffer>& casters = v.gpu->casterBuffers();
            ok &= pipeline.run(input, v.count, table, casters.data(), static_cast<uint32_t>(casters.size())) == penumbra::Status::Ok;
        } else {
            ok &= pipeline.run(input, v.count, table, draw) == penumbra::Status::Ok;
        }
    }
};

// ---------------------------------------------------------------------------------------------
// Errors against the oracle

struct Errors {
    uint64_t bits = 0, ties = 0, mismatched = 0, untested = 0;
    double rmse = 0.0, max_abs = 0.0;
    double mismatchRate() const { return bits > ties ? double(mismatched) / double(bits - ties) : 0.0; }
};

/// `masks` (words per view-sample id; empty: no per-light-sample bits) and `visibility` (per id)
/// against the oracle's verdicts on the view's surface samples.
Errors compareWithOracle(const View& v, const ref::VisibilityResult& truth, const std::vector<uint32_t>& masks, uint32_t words,
                         const std::vector<float>& visibility) {
    Errors e;
    double squares = 0.0;
    for (size_t r = 0; r < v.surface.size(); ++r) {
        const uint32_t id = v.surface[r];
        float visible = visibility[id];
        if (visible < 0.0f) {
            ++e.untested;
            visible = 1.0f;
        } else if (!masks.empty()) {
            for (uint32_t s = 0; s < truth.samples; ++s) {
                ++e.bits;
                if (truth.isTie(r, s)) {
                    ++e.ties;
                    continue;
                }
                const bool blocked = (masks[size_t(id) * words + s / 32] >> (s % 32)) & 1u;
                e.mismatched += blocked != truth.isBlocked(r, s);
            }
        }
        const double d = double(visible) - truth.visibleFraction(r);
        squares += d * d;
        e.max_abs = std::max(e.max_abs, std::abs(d));
    }
    e.rmse = std::sqrt(squares / double(v.surface.size()));
    return e;
}

Errors compareOurs(const Ours& o, const ref::VisibilityResult& truth) {
    return compareWithOracle(o.v, truth, o.pipeline.readMasks(), o.pipeline.wordsPerSample(), o.pipeline.readVisibility());
}

void setErrors(benchmark::State& state, const Errors& e, const std::string& suffix = "") {
    state.counters["err_mismatched_bits" + suffix] = e.mismatchRate();
    state.counters["err_mismatched_count" + suffix] = double(e.mismatched);
    state.counters["err_visibility_rmse" + suffix] = e.rmse;
    state.counters["err_visibility_max" + suffix] = e.max_abs;
    state.counters["ties" + suffix] = double(e.ties);
    state.counters["untested" + suffix] = double(e.untested);
}

/// Work counters of `mode` (with `pass`) from an untimed count_work run; returns its frame.
penumbra::SampleBasedSoftFrame setWork(benchmark::State& state, const View& v, const LightConfig& c, const Lut& l, SoftMode mode,
                                       penumbra::SoftLightPass pass = penumbra::SoftLightPass::Raster) {
    Ours counting(v, c, l, mode, true, penumbra::SampleBasedSoftGpuOptions{}.coverage_texels, pass);
    counting.run();
    PENUMBRA_CHECK(counting.ok, "sample_based_soft_bench: the count_work run failed");
    const penumbra::SampleBasedSoftFrame f = counting.pipeline.readFrame();
    const double n = double(c.sets.count());
    state.counters["pairs"] = double(f.pairs);
    state.counters["pairs_front"] = double(f.pairs_front);
    state.counters["fragments"] = double(f.fragments);
    state.counters["passes"] = double(f.passes);
    state.counters["exact_tests"] = double(f.exact_tests);
    state.counters["uncertain_bits"] = f.pairs ? double(f.uncertain_bits) / (double(f.pairs) * n) : 0.0;
    state.counters["tests_per_sample"] = double(f.pairs) / double(v.surface.size());
    state.counters["overflow"] = double(f.overflow);
    state.counters["max_list_length"] = double(f.statistics.max_list_length);
    state.counters["pairs_deferred"] = double(f.pairs_deferred);
    state.counters["deferral_fallbacks"] = double(f.deferral_fallbacks);
    state.counters["chunks"] = double(f.chunks);
    state.counters["gpu_bytes"] = double(counting.pipeline.memoryBytes());
    state.counters["gpu_bytes_bound"] = double(penumbra::SampleBasedSoftShadows::memoryBound(
        Ours::options(mode, true, penumbra::SampleBasedSoftGpuOptions{}.coverage_texels, pass), c.sets, c.influence, v.count));
    return f;
}

void setScene(benchmark::State& state, const View& v, uint32_t n) {
    state.counters["N"] = double(n);
    state.counters["samples"] = double(v.surface.size());
    state.counters["triangles"] = double(v.scene.triangleCount());
    state.counters["grid"] = double(sizes().grid);
    state.counters["lut_resolution"] = double(sizes().lut_resolution);
}

// ---------------------------------------------------------------------------------------------
// Timing

using Method = penumbra::bench::TimedMethod;

/// penumbra::bench::timeInterleaved, then ms (methods[0]) and ms_<name> (the others). Returns
/// whether the GL_TIME_ELAPSED query measured every call (else every ms_* uses the wall clock).
bool timeMethods(benchmark::State& state, std::vector<Method>& methods) {
    const bool query_measures = penumbra::bench::timeInterleaved(state, methods);
    for (const Method& m : methods) state.counters[m.name.empty() ? "ms" : "ms_" + m.name] = m.ms(query_measures);
    return query_measures;
}

/// Pipelines timed interleaved (the first one's counters unsuffixed, the others' ms_<name>), each
/// one's errors against the oracle of its light (err_*_<name>): the methods' times, or empty (the
/// entry skipped) when a run returned an error.
std::vector<double> timeOurs(benchmark::State& state, const std::vector<std::pair<std::string, Ours*>>& ours,
                             const std::vector<const ref::VisibilityResult*>& truths) {
    std::vector<Method> methods;
    for (const auto& [name, o] : ours) methods.push_back({name, [o = o] { o->run(); }});
    const bool q = timeMethods(state, methods);
    gl::checkErrors("sample_based_soft_bench");
    std::vector<double> ms;
    for (size_t i = 0; i < ours.size(); ++i) {
        if (!ours[i].second->ok) {
            state.SkipWithError("SampleBasedSoftShadows::run returned an error Status");
            return {};
        }
        setErrors(state, compareOurs(*ours[i].second, *truths[i]), ours[i].first.empty() ? "" : "_" + ours[i].first);
        ms.push_back(methods[i].ms(q));
    }
    return ms;
}

double ratio(double a, double b) { return b > 0.0 ? a / b : 0.0; }

void leaveNoBindings() {
    glBindTextureUnit(0, 0);
    for (GLuint b = 0; b < 3; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b, 0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glBindVertexArray(0);
}

// ---------------------------------------------------------------------------------------------
// Entries

/// BM_SoftShadows, BM_SoftShadowsRadius, BM_SoftShadowsTriangles and the compute light pass's
/// BM_SoftShadowsComputeTriangles, BM_SoftShadowsComputeRadius: one pipeline run per iteration.
/// ns_per_pair: ms / pairs (pairs, not pairs_deferred, which an overflow leaves at 0);
/// per_pair_over_first: that against the first entry of the same family (`family`, the smallest
/// size or radius) in this run.
void softEntry(benchmark::State& state, uint32_t tessellation, uint32_t radius_percent, uint32_t n, SoftMode mode,
               penumbra::SoftLightPass pass = penumbra::SoftLightPass::Raster, const std::string& family = "") {
    if (sizesRejected(state)) return;
    penumbra::bench::glContext();
    try {
        const View& v = view(tessellation);
        const LightConfig& c = lightConfig(tessellation, radius_percent, n);
        const Lut& l = lut(c.sets, c.tolerance);
        Ours ours(v, c, l, mode, false, penumbra::SampleBasedSoftGpuOptions{}.coverage_texels, pass);
        std::vector<Method> methods;
        methods.push_back({"", [&ours] { ours.run(); }});
        const bool q = timeMethods(state, methods);
        gl::checkErrors("sample_based_soft_bench");
        if (!ours.ok) {
            state.SkipWithError("SampleBasedSoftShadows::run returned an error Status");
            return;
        }
        setErrors(state, compareOurs(ours, c.truth));
        const penumbra::SampleBasedSoftFrame f = setWork(state, v, c, l, mode, pass);
        const double ns_per_pair = f.pairs ? 1e6 * methods[0].ms(q) / double(f.pairs) : 0.0;
        state.counters["ns_per_pair"] = ns_per_pair;
        if (!family.empty()) {
            static std::map<std::string, double> first;
            const double base = first.emplace(family, ns_per_pair).first->second;
            state.counters["per_pair_over_first"] = ratio(ns_per_pair, base);
        }
        setScene(state, v, n);
        state.counters["radius"] = c.light.size.x;
        leaveNoBindings();
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

/// N = 128 against N = 1024 in one entry (sintorn2008 Fig. 13: the cost "roughly only doubles"),
/// with the light pass `pass`.
void BM_SoftShadowsNScaling(benchmark::State& state, penumbra::SoftLightPass pass) {
    if (sizesRejected(state)) return;
    penumbra::bench::glContext();
    try {
        const uint32_t tessellation = sizes().tessellation;
        const View& v = view(tessellation);
        const LightConfig& c128 = lightConfig(tessellation, 100, 128);
        const LightConfig& c1024 = lightConfig(tessellation, 100, 1024);
        const uint32_t texels = penumbra::SampleBasedSoftGpuOptions{}.coverage_texels;
        Ours exact128(v, c128, lut(c128.sets, c128.tolerance), SoftMode::Exact, false, texels, pass);
        Ours exact1024(v, c1024, lut(c1024.sets, c1024.tolerance), SoftMode::Exact, false, texels, pass);
        Ours lut128(v, c128, lut(c128.sets, c128.tolerance), SoftMode::Lut, false, texels, pass);
        Ours lut1024(v, c1024, lut(c1024.sets, c1024.tolerance), SoftMode::Lut, false, texels, pass);
        const std::vector<double> ms = timeOurs(
            state, {{"", &exact128}, {"exact_n1024", &exact1024}, {"lut_n128", &lut128}, {"lut_n1024", &lut1024}},
            {&c128.truth, &c1024.truth, &c128.truth, &c1024.truth});
        if (ms.empty()) return;
        state.counters["n1024_over_n128"] = ratio(ms[1], ms[0]);
        state.counters["n1024_over_n128_lut"] = ratio(ms[3], ms[2]);
        setScene(state, v, 128);
        leaveNoBindings();
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

/// SampleBasedSoftGpuOptions::coverage_texels: the small regions covered by the coverage pass
/// (the default) against every region drawn, exact and lut at N = 256, interleaved.
/// Ours against another configuration of ours (`make(v, c, mode, other, count_work)`), exact and lut, all four
/// interleaved: <counter>_speedup = ms_<other> / ms, <counter>_speedup_lut = ms_lut_<other> / ms_lut; work_*: ours
/// (exact) counted in one more run.
template <class Make>
void oursAgainst(benchmark::State& state, const std::string& other, const std::string& counter, const Make& make) {
    if (sizesRejected(state)) return;
    penumbra::bench::glContext();
    try {
        const uint32_t tessellation = sizes().tessellation;
        const View& v = view(tessellation);
        const LightConfig& c = lightConfig(tessellation, 100, kBaselineSamples);
        Ours ours = make(v, c, SoftMode::Exact, false, false);
        Ours theirs = make(v, c, SoftMode::Exact, true, false);
        Ours ours_lut = make(v, c, SoftMode::Lut, false, false);
        Ours theirs_lut = make(v, c, SoftMode::Lut, true, false);
        const std::vector<double> ms = timeOurs(
            state, {{"", &ours}, {other, &theirs}, {"lut", &ours_lut}, {"lut_" + other, &theirs_lut}},
            {&c.truth, &c.truth, &c.truth, &c.truth});
        if (ms.empty()) return;
        state.counters[counter + "_speedup"] = ratio(ms[1], ms[0]);
        state.counters[counter + "_speedup_lut"] = ratio(ms[3], ms[2]);
        {  // work counters of ours (exact), from a counting run after the timed ones
            Ours counted = make(v, c, SoftMode::Exact, false, true);
            counted.run();
            const penumbra::SampleBasedSoftFrame f = counted.pipeline.readFrame();
            state.counters["list_blocks"] = double(f.passes);  // blocks the longest list needed
            state.counters["work_fragments"] = double(f.fragments);
            state.counters["work_pairs"] = double(f.pairs_deferred);
            state.counters["work_pairs_wedged"] = double(f.pairs_wedged);
            state.counters["work_exact_tests"] = double(f.exact_tests);
        }
        setScene(state, v, kBaselineSamples);
        leaveNoBindings();
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

void BM_SoftShadowsCoverage(benchmark::State& state) {
    oursAgainst(state, "drawn", "coverage", [](const View& v, const LightConfig& c, SoftMode mode, bool drawn, bool count_work) {
        return Ours(v, c, lut(c.sets, c.tolerance), mode, count_work, drawn ? 0u : penumbra::SampleBasedSoftGpuOptions{}.coverage_texels);
    });
}

/// SoftLightPass::Compute against Raster (each with its defaults: the coverage pass for small
/// regions), exact and lut, interleaved.
void BM_SoftShadowsCompute(benchmark::State& state) {
    oursAgainst(state, "raster", "compute", [](const View& v, const LightConfig& c, SoftMode mode, bool raster, bool count_work) {
        return Ours(v, c, lut(c.sets, c.tolerance), mode, count_work, penumbra::SampleBasedSoftGpuOptions{}.coverage_texels,
                    raster ? penumbra::SoftLightPass::Raster : penumbra::SoftLightPass::Compute);
    });
}

/// sintorn2008 §5's alternative: one shadow map per light sample, averaged; ours timed with it.
void BM_ShadowMapsAveraged(benchmark::State& state, uint32_t map_size) {
    if (sizesRejected(state)) return;
    penumbra::bench::glContext();
    try {
        const uint32_t tessellation = sizes().tessellation;
        const View& v = view(tessellation);
        const LightConfig& c = lightConfig(tessellation, 100, kBaselineSamples);
        const penumbra::bench::AveragedShadowMaps maps(*v.gpu, v.lifted, v.count, c.worldSamples(), v.lo, v.hi, map_size);
        Ours ours(v, c, lut(c.sets, c.tolerance), SoftMode::Exact, false);
        Ours ours_lut(v, c, lut(c.sets, c.tolerance), SoftMode::Lut, false);
        Ours ours_compute(v, c, lut(c.sets, c.tolerance), SoftMode::Exact, false, penumbra::SampleBasedSoftGpuOptions{}.coverage_texels,
                          penumbra::SoftLightPass::Compute);
        std::vector<Method> methods;
        methods.push_back({"", [&maps] { maps.run(); }});
        methods.push_back({"ours", [&ours] { ours.run(); }});
        methods.push_back({"ours_lut", [&ours_lut] { ours_lut.run(); }});
        methods.push_back({"ours_compute", [&ours_compute] { ours_compute.run(); }});
        const bool q = timeMethods(state, methods);
        gl::checkErrors("sample_based_soft_bench");
        if (!ours.ok || !ours_lut.ok || !ours_compute.ok) {
            state.SkipWithError("SampleBasedSoftShadows::run returned an error Status");
            return;
        }
        const Errors e_maps = compareWithOracle(v, c.truth, maps.readMasks(), maps.words(), maps.readVisibility());
        const Errors e_ours = compareOurs(ours, c.truth);
        const Errors e_lut = compareOurs(ours_lut, c.truth);
        const Errors e_compute = compareOurs(ours_compute, c.truth);
        setErrors(state, e_maps);
        setErrors(state, e_ours, "_ours");
        setErrors(state, e_lut, "_ours_lut");
        setErrors(state, e_compute, "_ours_compute");
        state.counters["ours_speedup"] = ratio(methods[0].ms(q), methods[1].ms(q));
        state.counters["ours_error_le_maps"] =
            (e_ours.mismatchRate() <= e_maps.mismatchRate() && e_ours.rmse <= e_maps.rmse) ? 1.0 : 0.0;
        state.counters["ours_lut_speedup"] = ratio(methods[0].ms(q), methods[2].ms(q));
        state.counters["ours_lut_error_le_maps"] =
            (e_lut.mismatchRate() <= e_maps.mismatchRate() && e_lut.rmse <= e_maps.rmse) ? 1.0 : 0.0;
        state.counters["ours_compute_speedup"] = ratio(methods[0].ms(q), methods[3].ms(q));
        state.counters["map_size"] = double(maps.mapSize());
        state.counters["maps_per_batch"] = double(maps.batchLayers());
        setScene(state, v, kBaselineSamples);
        leaveNoBindings();
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

/// One PCSS configuration: map size and taps.
struct PcssConfig {
    uint32_t map = 0, blocker = 0, filter = 0;
};

/// BM_Pcss: PCSS from one map at the light's centre (map_size, 32 blocker and 64 filter taps);
/// ours timed with it. BM_Pcss/equal_time (`equal_time`): PCSS given our time. Per map size
/// (map_size, 2x, 4x) its taps grow by sqrt(2) steps from (32, 64) until one run takes at least
/// ours (medians of 3, after a warm-up); of those configurations, the one closest to the
/// continuous-light proxy is timed against ours the same way.
void BM_Pcss(benchmark::State& state, bool equal_time) {
    if (sizesRejected(state)) return;
    penumbra::bench::glContext();
    try {
        const uint32_t tessellation = sizes().tessellation;
        const View& v = view(tessellation);
        const LightConfig& c = lightConfig(tessellation, 100, kBaselineSamples);
        // The continuous-light proxy: another, denser sample set (seed + 1, N = 1024).
        const LightConfig& proxy = lightConfig(tessellation, 100, 1024, kSampleSeed + 1);
        Ours ours(v, c, lut(c.sets, c.tolerance), SoftMode::Exact, false);
        const auto makePcss = [&](const PcssConfig& k) {
            return std::make_unique<penumbra::bench::Pcss>(*v.gpu, v.lifted, v.count, v.scene.light.position,
                                                           float(c.light.size.x), v.lo, v.hi, k.map, k.blocker, k.filter);
        };
        PcssConfig config{sizes().map_size, kPcssBlockerTaps, kPcssFilterTaps};
        if (equal_time) {
            const auto medianMs = [](const std::function<void()>& run) {
                penumbra::bench::timeGpu(run);
                std::vector<double> ms;
                for (int i = 0; i < 3; ++i) ms.push_back(1e3 * penumbra::bench::timeGpu(run));
                return penumbra::bench::median(ms);
            };
            const double ours_ms = medianMs([&ours] { ours.run(); });
            double best_rmse = std::numeric_limits<double>::infinity();
            for (const uint32_t map : {sizes().map_size, 2 * sizes().map_size, 4 * sizes().map_size}) {
                for (int step = 0; step <= kPcssMaxTapSteps; ++step) {
                    const double scale = std::pow(2.0, 0.5 * step);
                    const PcssConfig k{map, uint32_t(std::lround(kPcssBlockerTaps * scale)),
                                       uint32_t(std::lround(kPcssFilterTaps * scale))};
                    const auto pcss = makePcss(k);
                    if (medianMs([&pcss] { pcss->run(); }) < ours_ms && step < kPcssMaxTapSteps) continue;
                    const double rmse = compareWithOracle(v, proxy.truth, {}, 0, pcss->readVisibility()).rmse;
                    if (rmse < best_rmse) best_rmse = rmse, config = k;
                    break;
                }
            }
        }
        const auto pcss = makePcss(config);
        std::vector<Method> methods;
        methods.push_back({"", [&pcss] { pcss->run(); }});
        methods.push_back({"ours", [&ours] { ours.run(); }});
        const bool q = timeMethods(state, methods);
        gl::checkErrors("sample_based_soft_bench");
        if (!ours.ok) {
            state.SkipWithError("SampleBasedSoftShadows::run returned an error Status");
            return;
        }
        const std::vector<float> pcss_visibility = pcss->readVisibility();
        const Errors e_pcss = compareWithOracle(v, c.truth, {}, 0, pcss_visibility);
        const Errors e_ours = compareOurs(ours, c.truth);
        const Errors p_pcss = compareWithOracle(v, proxy.truth, {}, 0, pcss_visibility);
        const Errors p_ours = compareWithOracle(v, proxy.truth, {}, 0, ours.pipeline.readVisibility());
        state.counters["err_visibility_rmse"] = e_pcss.rmse;
        state.counters["err_visibility_max"] = e_pcss.max_abs;
        setErrors(state, e_ours, "_ours");
        state.counters["err_visibility_rmse_n1024"] = p_pcss.rmse;
        state.counters["err_visibility_rmse_n1024_ours"] = p_ours.rmse;
        state.counters["pcss_rmse_over_ours"] = ratio(p_pcss.rmse, p_ours.rmse);
        state.counters["pcss_time_over_ours"] = ratio(methods[0].ms(q), methods[1].ms(q));
        state.counters["map_size"] = double(pcss->mapSize());
        state.counters["blocker_taps"] = double(config.blocker);
        state.counters["filter_taps"] = double(config.filter);
        setScene(state, v, kBaselineSamples);
        leaveNoBindings();
    } catch (const std::exception& e) {
        state.SkipWithError(e.what());
    }
}

benchmark::internal::Benchmark* configure(benchmark::internal::Benchmark* b) {
    return b->UseManualTime()->Iterations(sizes().iterations)->Unit(benchmark::kMillisecond);
}

[[maybe_unused]] const bool kRegistered = [] {
    const uint32_t tessellation = sizes().tessellation;
    for (const uint32_t n : sampleCounts()) {
        std::vector<SoftMode> modes = {SoftMode::Exact, SoftMode::Lut};
        if (n == 128) modes.push_back(SoftMode::Brute);
        for (const SoftMode mode : modes) {
            const std::string name = "BM_SoftShadows/" + std::to_string(n) + "/" + penumbra::softModeName(mode);
            configure(benchmark::RegisterBenchmark(name.c_str(),
                                                   [=](benchmark::State& s) { softEntry(s, tessellation, 100, n, mode); }));
        }
    }
    configure(benchmark::RegisterBenchmark(
        "BM_SoftShadowsNScaling", [](benchmark::State& s) { BM_SoftShadowsNScaling(s, penumbra::SoftLightPass::Raster); }));
    configure(benchmark::RegisterBenchmark(
        "BM_SoftShadowsComputeNScaling", [](benchmark::State& s) { BM_SoftShadowsNScaling(s, penumbra::SoftLightPass::Compute); }));
    configure(benchmark::RegisterBenchmark("BM_SoftShadowsCoverage", BM_SoftShadowsCoverage));
    configure(benchmark::RegisterBenchmark("BM_SoftShadowsCompute", BM_SoftShadowsCompute));
    for (const uint32_t percent : radiusPercents()) {
        const std::string name = "BM_SoftShadowsRadius/" + std::to_string(percent);
        configure(benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& s) {
            softEntry(s, tessellation, percent, kBaselineSamples, SoftMode::Exact);
        }));
    }
    const std::string maps_name = "BM_ShadowMapsAveraged/" + std::to_string(kBaselineSamples);
    configure(benchmark::RegisterBenchmark(maps_name.c_str(),
                                           [](benchmark::State& s) { BM_ShadowMapsAveraged(s, sizes().map_size); }));
    for (const uint32_t size : mapSizeSweep()) {
        const std::string name = maps_name + "/map:" + std::to_string(size);
        configure(benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& s) { BM_ShadowMapsAveraged(s, size); }));
    }
    configure(benchmark::RegisterBenchmark("BM_Pcss", [](benchmark::State& s) { BM_Pcss(s, false); }));
    configure(benchmark::RegisterBenchmark("BM_Pcss/equal_time", [](benchmark::State& s) { BM_Pcss(s, true); }));
    for (const uint32_t t : tessellations()) {
        const std::string name = "BM_SoftShadowsTriangles/" + std::to_string(t);
        configure(benchmark::RegisterBenchmark(name.c_str(),
                                               [=](benchmark::State& s) { softEntry(s, t, 100, 128, SoftMode::Exact); }));
    }
    for (const uint32_t t : computeTessellations()) {
        const std::string name = "BM_SoftShadowsComputeTriangles/" + std::to_string(t);
        configure(benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& s) {
            softEntry(s, t, 100, kBaselineSamples, SoftMode::Exact, penumbra::SoftLightPass::Compute, "triangles");
        }));
    }
    for (const uint32_t percent : computeRadiusPercents()) {
        const std::string name = "BM_SoftShadowsComputeRadius/" + std::to_string(percent);
        configure(benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& s) {
            softEntry(s, tessellation, percent, kBaselineSamples, SoftMode::Exact, penumbra::SoftLightPass::Compute, "radius");
        }));
    }
    return true;
}();

}  // namespace
