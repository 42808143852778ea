// Deep shadow maps (penumbra/deep_shadow_map.hpp, lokovic2000): the CPU twin's build stages, its
// compression (§3.3) against the error bound it promises, its lookups against the exact
// transmittance oracle (reference/transmittance.hpp), and the regular shadow map with 3x3 PCF a
// user would get instead at the same memory. One run prints every number (console or
// --benchmark_format=json). CPU only: no GL context is created.
//
// Scenes: penumbra::scene::builtin("hairball") and builtin("grass"); the casters are every mesh of
// the scene except the ground plane (named "ground"; for the builtins: the object alone), all with
// one per-mesh opacity kOpacity = 0.5 (a ground plane under the object would only add an opaque
// floor below every receiver and every texel function: nothing to compress or look up). Light
// (dsmBenchLight): a perspective spot light at the scene's own light direction (-0.6, 1, 0.45),
// 3.5 bounding radii from the centre of the casters' bounds, looking at that centre; the bounding
// sphere is centred there with the farthest caster vertex as radius, and the square frustum is
// fitted to it (half-angle asin(radius / distance), near / far = distance -/+ 1.01 radius).
// Box filter of radius 0.5 (each texel's function is the average of its own S sub-samples).
//
// Entries (times in ms; every entry is single-threaded and uses Google Benchmark's default CPU
// timer: on a shared machine the Time column (wall) can exceed CPU, and items_per_second is per
// CPU second; counters per entry):
//   BM_DsmCompressionTable/<scene>/<S>/<eps_div>   R = tableResolution() (128; the environment
//       variable PENUMBRA_DSM_TABLE_RES sets another), S in {16, 64, 256},
//       eps = 1 / (eps_div S), eps_div in {1, 2, 4}; and BM_DsmCompressionTable/<scene>/<S>/paper,
//       eps = 1 / (4 sqrt S): lokovic2000's own setting (Fig. 7 compressed with half the expected
//       error 1 / (2 sqrt S) of S samples; 1/64 at S = 256, 4x the loosest eps, for
//       comparison with the seed's memory figures). Time: merge + compression of level 0
//       (buildDsmMapCpu, levels = 1). The fragments (rasterization) and the uncompressed map are
//       built once per (scene, S) and cached (tableData, one (scene, S) at a time). Counters:
//       vertices_before (uncompressed level-0 vertices), vertices_after, bytes_level0
//       (DsmMapCpu::levelBytes: 4 (R^2 + 1) offset bytes + 6 bytes per grey vertex),
//       depth_map_bytes (R^2 S 4: a plain depth map holding the same S samples per texel),
//       ratio = depth_map_bytes / bytes_level0,
//       err_linf (max over every texel of dsmFunctionDistance(uncompressed, compressed), double;
//       must be <= eps), err_linf_over_eps, eps, fragments, resolution. A texel over eps is also
//       printed to stderr (texel, eps, distance, vertex counts). vertices_lower_bound: the sum of
//       dsmVerticesLowerBound over the texels (no function within eps of each texel's has fewer
//       vertices, wherever it puts them); ratio_upper_bound: depth_map_bytes over what that many
//       vertices would take in this storage (counts padded to even): no map in this format can
//       beat it; bound_over_compressor: texels where the bound exceeds the compressor's count
//       (must be 0).
//   BM_DsmBuildFragments/<R>/<S>, BM_DsmMergeCompress/<R>/<S>, BM_DsmMips/<R>/<S>   hairball,
//       R in {64, 128, 256}, S in {16, 64}, eps = 1 / (2 S) (the default). BuildFragments:
//       buildDsmFragmentsCpu (rasterization + sort); MergeCompress: level 0 (merge + compression);
//       Mips: the whole mip chain (levels 1 .. log2 R) from a prebuilt level 0 (buildMipsCpu: the
//       twin's own level > 0 loop replayed alone, as the GPU's mip pass is its own kernel; compared
//       bit for bit with buildDsmMapCpu(levels = 0), counter identical_to_twin, must be 1).
//       Counters: fragments, vertices (every level built: level 0 for MergeCompress, all levels for
//       Mips, with vertices_mips = levels >= 1), bytes (BuildFragments: the GPU's fragment storage,
//       4 (R^2 S + 1) offset bytes + one 16-byte record per fragment; MergeCompress / Mips:
//       DsmMapCpu::bytes(), offsets + vertices of every level, with bytes_mips = levels >= 1).
//   BM_DsmLookup/<R>/<S>   hairball, R in {128, 256}, S in {16, 64}, eps = 1 / (2 S).
//       timedReceivers() (65536) receivers drawn uniformly in the casters' bounds (seeded, counter
//       seed) and kept when they project into the map; per lookup dsmCoord + dsmVisibility of the
//       texel containing the receiver (nearest texel, level 0). items_per_second = lookups per
//       second. Error against the oracle on the first oracleReceivers() (2000) receivers: the
//       reference is the oracle's transmittance averaged over the same S sub-sample rays of that
//       texel (dsmSubSample; the open segment from the light's eye to the ray's point at the
//       receiver's light depth): exactly what the box-filtered texel function stands for, so
//       err = |dsmVisibility - reference| is the compression error (<= eps) plus rasterization
//       differences (float edges and depths against the double oracle; rare). Counters: err_rmse,
//       err_max, err_over_eps (share of receivers with err > eps), oracle_receivers,
//       oracle_tie_receivers (receivers with a fragile oracle ray), eps, bytes_level0, seed.
//   BM_DsmPcfBaseline/<R>/<S>   the regular shadow map a user would use instead, at equal memory:
//       Rb x Rb float depths, Rb = floor(sqrt(bytes_level0 / 4)) of the DSM of BM_DsmLookup/<R>/<S>;
//       each texel holds the nearest caster depth along its centre ray (buildDepthMap: the DSM
//       rasterizer's rule at texel centres, i.e. buildDsmFragmentsCpu with S = 1 and the sample at
//       the centre, bit for bit). Lookup: dsmCoord + 3x3 PCF around the texel containing the
//       receiver, transmittance = share of taps whose depth >= the receiver's (opaque depth-map
//       semantics; receivers are points in space, no bias needed). Errors against the same
//       references and receivers as BM_DsmLookup/<R>/<S>. Counters: err_rmse, err_max, err_over_eps
//       (against the DSM's eps), resolution_b, bytes, dsm_bytes_level0, build_ms (not timed).
// PENUMBRA_BENCH_SMOKE=1 (ctest's smoke run): one small entry of each kind (R = 32, S = 4).
// Example: penumbra_bench --benchmark_filter='BM_Dsm' --benchmark_format=json
//
// GPU entries: reuse dsmBenchScene (casters, light, opacity), dsmBenchSetup, dsmBenchReceivers /
// dsmBenchLookupReference (receivers and oracle references) and tableData (the fragments and the
// exact merged functions of level 0, to measure a GPU map's compression error against).
#include "bench_common.hpp"

#include <penumbra/deep_shadow_map.hpp>
#include <penumbra/gl/deep_shadow_map.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/reference/transmittance.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

namespace {

constexpr float kOpacity = 0.5f;
constexpr uint64_t kReceiverSeed = 20000701u;  // lokovic2000 appeared at SIGGRAPH 2000, July

bool smoke() { return penumbra::bench::smokeRun(); }
/// The table's map resolution: 128 (smoke: 32), or PENUMBRA_DSM_TABLE_RES (an integer in [1, 4096])
/// to see how the ratio changes with R; 0 when that variable holds anything else (the entries
/// then stop with an error naming it).
uint32_t tableResolution() {
    const char* env = std::getenv("PENUMBRA_DSM_TABLE_RES");
    if (!env || !*env) return smoke() ? 32u : 128u;
    char* end = nullptr;
    const long r = std::strtol(env, &end, 10);
    return (*end == '\0' && r >= 1 && r <= 4096) ? static_cast<uint32_t>(r) : 0u;
}
size_t timedReceivers() { return smoke() ? 512u : 65536u; }
size_t oracleReceivers() { return smoke() ? 64u : 2000u; }

struct Rng {  // splitmix64: the same sequence with every standard library
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    double uniform(double lo, double hi) { return lo + (hi - lo) * (static_cast<double>(next() >> 11) * 0x1.0p-53); }
};

double msSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// ---- scene, light, setup (reusable by GPU entries) ----

struct DsmBenchLight {
    penumbra::DsmLight light;
    glm::vec3 eye{0.0f};     ///< the light's position (the eye of `light.view`)
    glm::vec3 centre{0.0f};  ///< the bounding sphere's centre (the casters' bounds' centre)
    float radius = 0.0f;     ///< the bounding sphere's radius (the farthest caster vertex)
};

/// A perspective spot light above the casters, looking at the centre of their bounds, its square
/// frustum fitted to their bounding sphere (see the header comment).
DsmBenchLight dsmBenchLight(const penumbra::scene::Mesh& mesh) {
    DsmBenchLight l;
    l.centre = mesh.bounds().center();
    for (const glm::vec3& p : mesh.positions) l.radius = std::max(l.radius, glm::length(p - l.centre));
    const glm::vec3 direction = glm::normalize(glm::vec3(-0.6f, 1.0f, 0.45f));  // the builtin scenes' light side
    const float distance = 3.5f * l.radius;
    l.eye = l.centre + direction * distance;
    l.light.view = glm::lookAt(l.eye, l.centre, glm::vec3(0.0f, 1.0f, 0.0f));
    l.light.projection = glm::perspective(2.0f * std::asin(l.radius / distance), 1.0f, distance - 1.01f * l.radius,
                                          distance + 1.01f * l.radius);
    return l;
}

struct DsmBenchScene {
    std::string name;
    penumbra::scene::Mesh casters;
    penumbra::scene::Bounds bounds;
    DsmBenchLight light;
    penumbra::DsmOpacity opacity;
    std::unique_ptr<penumbra::reference::TransmittanceOracle> oracle;  ///< built on first use (oracleOf)
};

/// The builtin scene `name` as the DSM benchmarks see it (built once).
DsmBenchScene& dsmBenchScene(const std::string& name) {
    static std::map<std::string, std::unique_ptr<DsmBenchScene>> cache;
    auto& s = cache[name];
    if (!s) {
        s = std::make_unique<DsmBenchScene>();
        s->name = name;
        s->casters = penumbra::scene::builtin(name).casters();
        s->bounds = s->casters.bounds();
        s->light = dsmBenchLight(s->casters);
        s->opacity.mesh = glm::vec3(kOpacity);
    }
    return *s;
}

const penumbra::reference::TransmittanceOracle& oracleOf(DsmBenchScene& scene) {
    if (!scene.oracle)
        scene.oracle = std::make_unique<penumbra::reference::TransmittanceOracle>(scene.casters.positions,
                                                                                  scene.casters.indices,
                                                                                  static_cast<double>(kOpacity));
    return *scene.oracle;
}

/// eps 0 = the default 1 / (2 S); levels 0 = the full chain.
penumbra::DsmSetup dsmBenchSetup(uint32_t resolution, uint32_t samples, float eps = 0.0f, uint32_t levels = 1) {
    penumbra::DsmOptions o;
    o.resolution = resolution;
    o.samples = samples;
    o.tolerance = eps;
    o.levels = levels;
    return penumbra::deepShadowMapSetup(o);
}

penumbra::DsmFragmentsCpu buildFragments(const DsmBenchScene& s, const penumbra::DsmSetup& setup) {
    return penumbra::buildDsmFragmentsCpu(setup, s.light.light, s.casters.positions, s.casters.indices, s.opacity);
}

using Key = std::tuple<std::string, uint32_t, uint32_t>;  // scene, R, S

/// The fragments of (scene, R, S), cached (they depend on neither eps nor levels).
const penumbra::DsmFragmentsCpu& dsmBenchFragments(const std::string& scene, uint32_t R, uint32_t S,
                                                   penumbra::DsmFragmentsCpu* built = nullptr) {
    static std::map<Key, std::unique_ptr<penumbra::DsmFragmentsCpu>> cache;
    auto& f = cache[{scene, R, S}];
    if (!f) {
        f = std::make_unique<penumbra::DsmFragmentsCpu>(
            built ? std::move(*built) : buildFragments(dsmBenchScene(scene), dsmBenchSetup(R, S)));
    }
    return *f;
}

/// Level 0 compressed at the default eps (cached): what the lookups read.
const penumbra::DsmMapCpu& dsmBenchMap(const std::string& scene, uint32_t R, uint32_t S) {
    static std::map<Key, std::unique_ptr<penumbra::DsmMapCpu>> cache;
    auto& m = cache[{scene, R, S}];
    if (!m)
        m = std::make_unique<penumbra::DsmMapCpu>(
            penumbra::buildDsmMapCpu(dsmBenchSetup(R, S), dsmBenchFragments(scene, R, S), true));
    return *m;
}

uint64_t levelBytes(const penumbra::DsmMapCpu& map, uint32_t level) { return map.levelBytes(level); }

struct Receivers {
    std::vector<glm::vec3> points;  ///< uniform in the casters' bounds, projecting into the map
};

/// timedReceivers() points of `scene` (seeded; the first oracleReceivers() carry references).
const Receivers& dsmBenchReceivers(const std::string& scene) {
    static std::map<std::string, std::unique_ptr<Receivers>> cache;
    auto& r = cache[scene];
    if (!r) {
        r = std::make_unique<Receivers>();
        const DsmBenchScene& s = dsmBenchScene(scene);
        const penumbra::DsmParams params = penumbra::deepShadowMapParams(dsmBenchSetup(1, 1), s.light.light, s.opacity);
        Rng rng(kReceiverSeed);
        while (r->points.size() < timedReceivers()) {
            const glm::vec3 p(static_cast<float>(rng.uniform(s.bounds.min.x, s.bounds.max.x)),
                              static_cast<float>(rng.uniform(s.bounds.min.y, s.bounds.max.y)),
                              static_cast<float>(rng.uniform(s.bounds.min.z, s.bounds.max.z)));
            const penumbra::DsmCoord c = penumbra::dsmCoord(params, p);
            if (c.inside && c.depth > 0.0f) r->points.push_back(p);
        }
    }
    return *r;
}

/// The texel of an R x R map containing (u, v) (nearest texel; u = 1 belongs to the last).
uint32_t texelOf(float u, float v, uint32_t R) {
    const uint32_t x = std::min(R - 1, static_cast<uint32_t>(std::max(0.0f, std::floor(u * static_cast<float>(R)))));
    const uint32_t y = std::min(R - 1, static_cast<uint32_t>(std::max(0.0f, std::floor(v * static_cast<float>(R)))));
    return y * R + x;
}

struct LookupReference {
    std::vector<double> transmittance;  ///< per oracle receiver: the oracle's texel average
    uint64_t tie_receivers = 0;         ///< receivers with at least one fragile oracle ray
};

/// For each of the first oracleReceivers() receivers: the oracle's transmittance averaged over the
/// S sub-sample rays of the R-map texel containing it, each ray from the light's eye to its point
/// at the receiver's light depth (cached per (scene, R, S)).
const LookupReference& dsmBenchLookupReference(const std::string& scene, uint32_t R, uint32_t S) {
    static std::map<Key, std::unique_ptr<LookupReference>> cache;
    auto& ref = cache[{scene, R, S}];
    if (ref) return *ref;
    ref = std::make_unique<LookupReference>();
    DsmBenchScene& s = dsmBenchScene(scene);
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
    const penumbra::DsmParams params = penumbra::deepShadowMapParams(setup, s.light.light, s.opacity);
    const glm::dmat4 inverse = glm::inverse(glm::dmat4(params.light_view_projection));
    const glm::dvec4 row(params.depth_row);
    const glm::dvec3 eye(s.light.eye);
    auto depthOf = [&](const glm::dvec3& p) { return row.x * p.x + row.y * p.y + row.z * p.z + row.w; };
    const double eye_depth = depthOf(eye);
    const Receivers& receivers = dsmBenchReceivers(scene);
    const size_t n = std::min(oracleReceivers(), receivers.points.size());
    std::vector<penumbra::reference::TransmittanceSegment> segments;
    segments.reserve(n * S);
    for (size_t i = 0; i < n; ++i) {
        const penumbra::DsmCoord c = penumbra::dsmCoord(params, receivers.points[i]);
        const uint32_t texel = texelOf(c.u, c.v, R);
        for (uint32_t j = 0; j < S; ++j) {
            const glm::vec2 w = penumbra::dsmSubSample(setup, texel % R, texel / R, j);
            const glm::dvec4 h = inverse * glm::dvec4(w.x * 2.0 / R - 1.0, w.y * 2.0 / R - 1.0, 0.0, 1.0);
            const glm::dvec3 on_ray = glm::dvec3(h) / h.w;
            const double t = (static_cast<double>(c.depth) - eye_depth) / (depthOf(on_ray) - eye_depth);
            segments.push_back({eye, eye + (on_ray - eye) * t});
        }
    }
    const auto batch = oracleOf(s).evaluate(segments);
    ref->transmittance.resize(n);
    for (size_t i = 0; i < n; ++i) {
        double sum = 0.0;
        bool tie = false;
        for (uint32_t j = 0; j < S; ++j) {
            sum += batch.results[i * S + j].transmittance;
            tie = tie || batch.results[i * S + j].tie;
        }
        ref->transmittance[i] = sum / S;
        ref->tie_receivers += tie;
    }
    return *ref;
}

/// Milliseconds. No MinTime / UseRealTime (they would append "/min_time:...", "/real_time" to the
/// names): every entry is single-threaded, so CPU time is its wall time; --benchmark_min_time applies.
benchmark::internal::Benchmark* configure(benchmark::internal::Benchmark* b) { return b->Unit(benchmark::kMillisecond); }

// ---- 1. compression table ----

/// The fragments and the uncompressed map of the table's current (scene, S), one at a time (the
/// entries run grouped by (scene, S); at S = 256 the pair holds ~1 GB).
struct TableData {
    Key key;
    std::unique_ptr<penumbra::DsmFragmentsCpu> fragments;
    std::unique_ptr<penumbra::DsmMapCpu> uncompressed;
};

const TableData& tableData(const std::string& scene, uint32_t R, uint32_t S) {
    static TableData data;
    const Key key{scene, R, S};
    if (!data.fragments || data.key != key) {
        data = TableData{};
        data.key = key;
        const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
        data.fragments = std::make_unique<penumbra::DsmFragmentsCpu>(buildFragments(dsmBenchScene(scene), setup));
        data.uncompressed =
            std::make_unique<penumbra::DsmMapCpu>(penumbra::buildDsmMapCpu(setup, *data.fragments, false));
    }
    return data;
}

/// `tag`: the entry's last name component (eps_div or "paper"), for the message below.
void compressionTable(benchmark::State& state, const std::string& scene, uint32_t S, float tolerance, const std::string& tag) {
    const uint32_t R = tableResolution();
    if (R == 0) {
        const std::string message =
            std::string("PENUMBRA_DSM_TABLE_RES must be an integer in [1, 4096], got '") + std::getenv("PENUMBRA_DSM_TABLE_RES") + "'";
        state.SkipWithError(message.c_str());
        return;
    }
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S, tolerance);
    const TableData& data = tableData(scene, R, S);
    const penumbra::DsmFragmentsCpu& frags = *data.fragments;
    const penumbra::DsmMapCpu& raw = *data.uncompressed;
    penumbra::DsmMapCpu map;
    for (auto _ : state) {
        map = penumbra::buildDsmMapCpu(setup, frags, true);
        benchmark::DoNotOptimize(map.vertices[0].data());
    }
    const uint32_t F = 1 + setup.channels;
    double worst = 0.0;
    uint32_t worst_texel = 0;
    for (uint32_t t = 0; t < R * R; ++t) {
        const uint32_t a0 = raw.offsets[0][t], a1 = raw.offsets[0][t + 1];
        const uint32_t b0 = map.offsets[0][t], b1 = map.offsets[0][t + 1];
        const double d = penumbra::dsmFunctionDistance(raw.vertices[0].data() + F * a0, a1 - a0,
                                                       map.vertices[0].data() + F * b0, b1 - b0, setup.channels);
        if (d > worst) worst = d, worst_texel = t;
    }
    const double eps = setup.tolerance;
    if (worst > eps)
        std::fprintf(stderr,
                     "BM_DsmCompressionTable/%s/%u/%s: texel (%u, %u) of R = %u: L-inf distance %.9g > eps %.9g "
                     "(uncompressed %u vertices, compressed %u)\n",
                     scene.c_str(), S, tag.c_str(), worst_texel % R, worst_texel / R, R, worst, eps,
                     raw.offsets[0][worst_texel + 1] - raw.offsets[0][worst_texel],
                     map.offsets[0][worst_texel + 1] - map.offsets[0][worst_texel]);
    const double bytes = static_cast<double>(levelBytes(map, 0));
    const double depth_map_bytes = 4.0 * R * R * S;
    // The fewest vertices any function within eps of each texel's could have
    // (dsmVerticesLowerBound), and what they would take in this storage (counts padded to even).
    uint64_t bound_vertices = 0, bound_stored = 0, bound_over = 0;
    for (uint32_t t = 0; t < R * R; ++t) {
        const uint32_t a0 = raw.offsets[0][t], a1 = raw.offsets[0][t + 1];
        const uint32_t b = penumbra::dsmVerticesLowerBound(raw.vertices[0].data() + F * a0, a1 - a0, setup.channels, 0, eps);
        bound_vertices += b;
        bound_stored += b + (b & 1u);
        bound_over += b > map.offsets[0][t + 1] - map.offsets[0][t];
    }
    const double bound_bytes = 4.0 * (double(R) * R + 1) + double(bound_stored) * (4.0 + 2.0 * setup.channels);
    state.counters["resolution"] = R;
    state.counters["eps"] = eps;
    state.counters["fragments"] = static_cast<double>(frags.fragments.size());
    state.counters["vertices_before"] = static_cast<double>(raw.vertexCount(0));
    state.counters["vertices_after"] = static_cast<double>(map.vertexCount(0));
    state.counters["bytes_level0"] = bytes;
    state.counters["depth_map_bytes"] = depth_map_bytes;
    state.counters["ratio"] = depth_map_bytes / bytes;
    state.counters["vertices_lower_bound"] = static_cast<double>(bound_vertices);
    state.counters["ratio_upper_bound"] = depth_map_bytes / bound_bytes;
    state.counters["bound_over_compressor"] = static_cast<double>(bound_over);
    state.counters["err_linf"] = worst;
    state.counters["err_linf_over_eps"] = worst / eps;
}

// ---- 2. stage times ----

void buildFragmentsEntry(benchmark::State& state, uint32_t R, uint32_t S) {
    const DsmBenchScene& s = dsmBenchScene("hairball");
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
    penumbra::DsmFragmentsCpu frags;
    for (auto _ : state) {
        frags = buildFragments(s, setup);
        benchmark::DoNotOptimize(frags.fragments.data());
    }
    const double fragments = static_cast<double>(frags.fragments.size());
    state.counters["fragments"] = fragments;
    state.counters["fragments_per_sub_sample"] = fragments / (static_cast<double>(R) * R * S);
    state.counters["bytes"] = 4.0 * (static_cast<double>(R) * R * S + 1) + 16.0 * fragments;
    dsmBenchFragments("hairball", R, S, &frags);  // the merge entries reuse them
}

void mergeCompressEntry(benchmark::State& state, uint32_t R, uint32_t S) {
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
    const penumbra::DsmFragmentsCpu& frags = dsmBenchFragments("hairball", R, S);
    penumbra::DsmMapCpu map;
    for (auto _ : state) {
        map = penumbra::buildDsmMapCpu(setup, frags, true);
        benchmark::DoNotOptimize(map.vertices[0].data());
    }
    state.counters["fragments"] = static_cast<double>(frags.fragments.size());
    state.counters["vertices"] = static_cast<double>(map.vertexCount(0));
    state.counters["bytes"] = static_cast<double>(map.bytes());
}

/// Levels 1 .. setup.levels - 1 of `map` from its level 0 (one channel): the CPU twin's own loop for
/// level > 0 (buildDsmMapCpu: detail::dsmAverageTexel into a detail::DsmCompressor at
/// dsmInnerTolerance of the level's tolerance), replayed on a prebuilt level 0 so that the mip
/// chain can be timed alone, as the GPU's mip pass is a separate kernel. mipsEntry checks it bit
/// for bit against buildDsmMapCpu.
void buildMipsCpu(const penumbra::DsmSetup& setup, penumbra::DsmMapCpu& map) {
    namespace detail = penumbra::detail;
    constexpr int F = 2;  // (z, V)
    map.levels = setup.levels;
    map.resolution_of = setup.level_resolution;
    map.offsets.resize(setup.levels);
    map.vertices.resize(setup.levels);
    for (uint32_t level = 1; level < setup.levels; ++level) {
        const uint32_t r = setup.level_resolution[level], rc = setup.level_resolution[level - 1];
        const float tol = setup.levelTolerance(level);
        const float eps_inner = penumbra::dsmInnerTolerance(tol);  // as buildDsmMapCpu (minus 1/64 and the 16-bit rounding)
        std::vector<uint32_t>& offsets = map.offsets[level];
        std::vector<float>& out = map.vertices[level];
        offsets.assign(static_cast<size_t>(r) * r + 1, 0);
        out.clear();
        const std::vector<uint32_t>& co = map.offsets[level - 1];
        const std::vector<float>& cv = map.vertices[level - 1];
        for (uint32_t y = 0; y < r; ++y)
            for (uint32_t x = 0; x < r; ++x) {
                detail::DsmCompressor<1> compressor(eps_inner, &out);
                detail::DsmSink<1> sink;
                sink.compressor = &compressor;
                const float* verts[4];
                uint32_t counts[4];
                for (int k = 0; k < 4; ++k) {
                    const uint32_t t = (2 * y + (k >> 1)) * rc + (2 * x + (k & 1));
                    verts[k] = cv.data() + static_cast<size_t>(F) * co[t];
                    counts[k] = co[t + 1] - co[t];
                }
                detail::dsmAverageTexel<1>(verts, counts, sink);
                compressor.finish();
                offsets[static_cast<size_t>(y) * r + x + 1] = static_cast<uint32_t>(out.size() / F);
            }
    }
}

void mipsEntry(benchmark::State& state, uint32_t R, uint32_t S) {
    const penumbra::DsmSetup chain = dsmBenchSetup(R, S, 0.0f, 0);
    const penumbra::DsmFragmentsCpu& frags = dsmBenchFragments("hairball", R, S);
    penumbra::DsmMapCpu map = dsmBenchMap("hairball", R, S);  // level 0 (same eps as the chain's level 0)
    for (auto _ : state) {
        buildMipsCpu(chain, map);  // overwrites levels >= 1; level 0 stays
        benchmark::DoNotOptimize(map.vertices.back().data());
    }
    // The replay must equal the twin's full build (one untimed buildDsmMapCpu of the whole chain).
    const penumbra::DsmMapCpu twin = penumbra::buildDsmMapCpu(chain, frags, true);
    bool identical = twin.levels == map.levels;
    for (uint32_t l = 0; identical && l < map.levels; ++l)
        identical = twin.offsets[l] == map.offsets[l] && twin.vertices[l] == map.vertices[l];
    if (!identical)
        std::fprintf(stderr, "BM_DsmMips/%u/%u: buildMipsCpu differs from buildDsmMapCpu (levels = 0)\n", R, S);
    uint64_t vertices = 0;
    for (uint32_t l = 0; l < map.levels; ++l) vertices += map.vertexCount(l);
    state.counters["levels"] = map.levels;
    state.counters["fragments"] = static_cast<double>(frags.fragments.size());
    state.counters["vertices"] = static_cast<double>(vertices);
    state.counters["vertices_mips"] = static_cast<double>(vertices - map.vertexCount(0));
    state.counters["bytes"] = static_cast<double>(map.bytes());
    state.counters["bytes_mips"] = static_cast<double>(map.bytes() - levelBytes(map, 0));
    state.counters["identical_to_twin"] = identical ? 1.0 : 0.0;
}

// ---- 3. lookups, 4. the PCF baseline ----

struct ErrorStats {
    double rmse = 0.0, max = 0.0, over_eps = 0.0;
};

ErrorStats errorsAgainst(const LookupReference& ref, const std::vector<float>& got, double eps) {
    ErrorStats e;
    const size_t n = ref.transmittance.size();
    for (size_t i = 0; i < n; ++i) {
        const double d = std::fabs(static_cast<double>(got[i]) - ref.transmittance[i]);
        e.rmse += d * d;
        e.max = std::max(e.max, d);
        e.over_eps += d > eps;
    }
    e.rmse = n ? std::sqrt(e.rmse / n) : 0.0;
    e.over_eps = n ? e.over_eps / n : 0.0;
    return e;
}

void lookupEntry(benchmark::State& state, const std::string& scene, uint32_t R, uint32_t S) {
    const DsmBenchScene& s = dsmBenchScene(scene);
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
    const penumbra::DsmParams params = penumbra::deepShadowMapParams(setup, s.light.light, s.opacity);
    const penumbra::DsmMapCpu& map = dsmBenchMap(scene, R, S);
    const Receivers& receivers = dsmBenchReceivers(scene);
    const LookupReference& ref = dsmBenchLookupReference(scene, R, S);
    auto lookup = [&](const glm::vec3& p) {
        const penumbra::DsmCoord c = penumbra::dsmCoord(params, p);
        return penumbra::dsmVisibility(map, 0, texelOf(c.u, c.v, R), c.depth);
    };
    for (auto _ : state) {
        float sum = 0.0f;
        for (const glm::vec3& p : receivers.points) sum += lookup(p);
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * receivers.points.size()));
    std::vector<float> got(ref.transmittance.size());
    for (size_t i = 0; i < got.size(); ++i) got[i] = lookup(receivers.points[i]);
    const ErrorStats e = errorsAgainst(ref, got, setup.tolerance);
    state.counters["err_rmse"] = e.rmse;
    state.counters["err_max"] = e.max;
    state.counters["err_over_eps"] = e.over_eps;
    state.counters["eps"] = setup.tolerance;
    state.counters["oracle_receivers"] = static_cast<double>(got.size());
    state.counters["oracle_tie_receivers"] = static_cast<double>(ref.tie_receivers);
    state.counters["bytes_level0"] = static_cast<double>(levelBytes(map, 0));
    state.counters["seed"] = static_cast<double>(kReceiverSeed);
}

/// A regular depth map: the nearest caster depth along each texel's centre ray (+inf: none).
struct DepthMap {
    uint32_t resolution = 0;
    std::vector<float> depth;
    penumbra::DsmParams params;
};

/// The DSM rasterizer's rule (detail::dsmTriangle, dsmEdge, dsmEdgeCovers, dsmInterpolate: what
/// buildDsmFragmentsCpu applies to its sub-samples) at the texel centres, keeping the nearest depth.
/// Instead of every texel of the triangle's bounding box (hundreds of thousands per hairball strand
/// at Rb ~ 1800) each row tests only the span where its centre line crosses the projected triangle,
/// widened by one texel: the same depths, tens of times faster.
DepthMap buildDepthMap(const DsmBenchScene& s, uint32_t Rb) {
    namespace detail = penumbra::detail;
    DepthMap m;
    m.resolution = Rb;
    m.params = penumbra::deepShadowMapParams(dsmBenchSetup(Rb, 1), s.light.light, s.opacity);
    m.depth.assign(static_cast<size_t>(Rb) * Rb, std::numeric_limits<float>::infinity());
    const float scale = m.params.numbers.x;  // 2 / Rb
    const float R = static_cast<float>(Rb);
    const std::vector<glm::vec3>& positions = s.casters.positions;
    const std::vector<uint32_t>& indices = s.casters.indices;
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        glm::vec4 clip[3];
        float depth[3];
        glm::vec2 w[3];
        bool in_front = true;
        for (int i = 0; i < 3; ++i) {
            const glm::vec3& p = positions[indices[t + i]];
            clip[i] = detail::transformPointDsm(m.params.light_view_projection, p);
            depth[i] = detail::dsmDepth(m.params.depth_row, p);
            in_front = in_front && clip[i].w > 0.0f;
            w[i] = (glm::vec2(clip[i]) / clip[i].w * 0.5f + 0.5f) * R;
        }
        const detail::DsmTriangle tri = detail::dsmTriangle(clip, depth);
        if (!tri.valid) continue;
        int y0 = 0, y1 = static_cast<int>(Rb) - 1;
        if (in_front) {
            const float lo = std::min({w[0].y, w[1].y, w[2].y}), hi = std::max({w[0].y, w[1].y, w[2].y});
            y0 = std::max(y0, static_cast<int>(std::floor(std::max(lo, -2.0f))) - 1);
            y1 = std::min(y1, static_cast<int>(std::floor(std::min(hi, R + 2.0f))) + 1);
        }
        for (int y = y0; y <= y1; ++y) {
            int x0 = 0, x1 = static_cast<int>(Rb) - 1;
            if (in_front) {  // the span of the line through the row's centres inside the triangle
                const float cy = static_cast<float>(y) + 0.5f;
                float lo = std::numeric_limits<float>::infinity(), hi = -lo;
                for (int i = 0; i < 3; ++i) {
                    const glm::vec2 a = w[i], b = w[(i + 1) % 3];
                    if (std::min(a.y, b.y) > cy + 1.0f || std::max(a.y, b.y) < cy - 1.0f) continue;
                    const float t_line = a.y == b.y ? 0.0f : std::clamp((cy - a.y) / (b.y - a.y), 0.0f, 1.0f);
                    const float x = a.x + (b.x - a.x) * t_line;
                    lo = std::min({lo, x, a.y == b.y ? b.x : x}), hi = std::max({hi, x, a.y == b.y ? b.x : x});
                }
                if (!(lo <= hi)) continue;
                x0 = std::max(x0, static_cast<int>(std::floor(std::max(lo, -2.0f) - 0.5f)) - 1);
                x1 = std::min(x1, static_cast<int>(std::floor(std::min(hi, R + 2.0f) - 0.5f)) + 1);
            }
            const float py = detail::dsmNdc(static_cast<float>(y) + 0.5f, scale);
            for (int x = x0; x <= x1; ++x) {
                const float px = detail::dsmNdc(static_cast<float>(x) + 0.5f, scale);
                const float e0 = detail::dsmEdge(tri.n[0], px, py), e1 = detail::dsmEdge(tri.n[1], px, py),
                            e2 = detail::dsmEdge(tri.n[2], px, py);
                if (!detail::dsmEdgeCovers(e0, tri.n[0]) || !detail::dsmEdgeCovers(e1, tri.n[1]) ||
                    !detail::dsmEdgeCovers(e2, tri.n[2]) || !((e0 + e1) + e2 > 0.0f))
                    continue;
                float& d = m.depth[static_cast<size_t>(y) * Rb + static_cast<size_t>(x)];
                d = std::min(d, detail::dsmInterpolate(e0, e1, e2, tri.d[0], tri.d[1], tri.d[2]));
            }
        }
    }
    return m;
}

/// 3x3 PCF: the share of taps around the receiver's texel whose depth is >= the receiver's.
float pcfLookup(const DepthMap& m, const glm::vec3& p) {
    const penumbra::DsmCoord c = penumbra::dsmCoord(m.params, p);
    const uint32_t t = texelOf(c.u, c.v, m.resolution);
    const int R = static_cast<int>(m.resolution);
    const int x = static_cast<int>(t % m.resolution), y = static_cast<int>(t / m.resolution);
    int lit = 0;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            const int tx = std::clamp(x + dx, 0, R - 1), ty = std::clamp(y + dy, 0, R - 1);
            lit += m.depth[static_cast<size_t>(ty) * R + tx] >= c.depth;
        }
    return static_cast<float>(lit) * (1.0f / 9.0f);
}

void pcfBaselineEntry(benchmark::State& state, const std::string& scene, uint32_t R, uint32_t S) {
    const DsmBenchScene& s = dsmBenchScene(scene);
    const uint64_t dsm_bytes = levelBytes(dsmBenchMap(scene, R, S), 0);
    const uint32_t Rb = std::min(penumbra::kDsmMaxResolution,
                                 static_cast<uint32_t>(std::floor(std::sqrt(static_cast<double>(dsm_bytes) / 4.0))));
    const auto start = std::chrono::steady_clock::now();
    const DepthMap m = buildDepthMap(s, Rb);
    const double build_ms = msSince(start);
    const Receivers& receivers = dsmBenchReceivers(scene);
    const LookupReference& ref = dsmBenchLookupReference(scene, R, S);
    for (auto _ : state) {
        float sum = 0.0f;
        for (const glm::vec3& p : receivers.points) sum += pcfLookup(m, p);
        benchmark::DoNotOptimize(sum);
    }
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * receivers.points.size()));
    std::vector<float> got(ref.transmittance.size());
    for (size_t i = 0; i < got.size(); ++i) got[i] = pcfLookup(m, receivers.points[i]);
    const ErrorStats e = errorsAgainst(ref, got, dsmBenchSetup(R, S).tolerance);
    state.counters["err_rmse"] = e.rmse;
    state.counters["err_max"] = e.max;
    state.counters["err_over_eps"] = e.over_eps;
    state.counters["resolution_b"] = Rb;
    state.counters["bytes"] = 4.0 * Rb * Rb;
    state.counters["dsm_bytes_level0"] = static_cast<double>(dsm_bytes);
    state.counters["build_ms"] = build_ms;
}

// ---- 6. the GPU build and GPU lookups (penumbra/gl/deep_shadow_map.hpp) ----
// The whole build timed with penumbra::bench::timeGpu (GL_TIME_ELAPSED where the driver's answers
// are durations, glFinish + the wall clock elsewhere: timer_gl_time_elapsed says which), the four
// stages with the builder's own queries (medians); identical_to_twin compares every level-0 offset
// and vertex with the CPU twin's map (1 = bit for bit; llvmpipe rounds like the twin).

struct GpuCasters {
    penumbra::gl::Buffer positions, indices;
    penumbra::gl::DsmCasterBuffers ranges;
};

GpuCasters gpuCasters(const DsmBenchScene& s) {
    GpuCasters g;
    g.positions = penumbra::gl::Buffer::fromVector(s.casters.positions);
    g.indices = penumbra::gl::Buffer::fromVector(s.casters.indices);
    g.ranges.positions = {g.positions.id(), 0, g.positions.size()};
    g.ranges.indices = {g.indices.id(), 0, g.indices.size()};
    g.ranges.index_count = static_cast<uint32_t>(s.casters.indices.size());
    return g;
}

void gpuBuildEntry(benchmark::State& state, uint32_t R, uint32_t S) {
    penumbra::bench::glContext();
    const DsmBenchScene& s = dsmBenchScene("hairball");
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
    const penumbra::DsmFragmentsCpu& frags = dsmBenchFragments("hairball", R, S);
    const penumbra::DsmMapCpu& cpu = dsmBenchMap("hairball", R, S);
    penumbra::gl::DsmCapacity capacity;
    capacity.fragments = frags.fragments.size() + 16;
    capacity.vertices = cpu.vertexCount(0) + 16;
    penumbra::gl::DeepShadowMapBuilder builder(setup, capacity);
    const GpuCasters casters = gpuCasters(s);
    auto run = [&] { builder.build(s.light.light, s.opacity, casters.ranges); };
    penumbra::bench::timeGpu(run);  // warm-up (llvmpipe compiles at the first draw)
    for (auto _ : state) state.SetIterationTime(penumbra::bench::timeGpu(run));
    // Stage split: one more build per iteration count with the stages bracketed (queries where
    // they measure durations, else glFinish + wall clock); not part of the timed builds above.
    builder.enableStageTimers(!penumbra::bench::timeElapsedMeasuresNow());
    std::vector<double> raster, sort, merge;
    for (int i = 0; i < 3; ++i) {
        run();
        const penumbra::gl::DsmStageTimes t = builder.stageTimes();
        raster.push_back(t.rasterize);
        sort.push_back(t.sort);
        merge.push_back(t.merge_compress);
    }
    const penumbra::DsmMapCpu gpu = builder.readMap();
    const penumbra::gl::DsmStatus status = builder.readStatus();
    const bool identical = gpu.offsets[0] == cpu.offsets[0] && gpu.vertices[0].size() == cpu.vertices[0].size() &&
                           std::equal(gpu.vertices[0].begin(), gpu.vertices[0].end(), cpu.vertices[0].begin(),
                                      [](float a, float b) { return penumbra::detail::floatBits(a) == penumbra::detail::floatBits(b); });
    state.counters["identical_to_twin"] = identical ? 1.0 : 0.0;
    state.counters["overflow"] = double(status.fragment_overflow + status.vertex_overflow);
    state.counters["fragments"] = double(status.fragments);
    state.counters["vertices"] = double(gpu.vertexCount(0));
    state.counters["bytes_level0"] = double(levelBytes(gpu, 0));
    state.counters["rasterize_ms"] = penumbra::bench::median(raster);
    state.counters["sort_ms"] = penumbra::bench::median(sort);
    state.counters["merge_compress_ms"] = penumbra::bench::median(merge);
    penumbra::bench::reportTimer(state);
}

void gpuLookupEntry(benchmark::State& state, uint32_t R, uint32_t S) {
    penumbra::bench::glContext();
    const DsmBenchScene& s = dsmBenchScene("hairball");
    const penumbra::DsmSetup setup = dsmBenchSetup(R, S);
    const penumbra::DsmFragmentsCpu& frags = dsmBenchFragments("hairball", R, S);
    const penumbra::DsmMapCpu& cpu = dsmBenchMap("hairball", R, S);
    penumbra::gl::DsmCapacity capacity;
    capacity.fragments = frags.fragments.size() + 16;
    capacity.vertices = cpu.vertexCount(0) + 16;
    penumbra::gl::DeepShadowMapBuilder builder(setup, capacity);
    const GpuCasters casters = gpuCasters(s);
    builder.build(s.light.light, s.opacity, casters.ranges);
    const Receivers& receivers = dsmBenchReceivers("hairball");
    std::vector<glm::vec4> queries;
    for (const glm::vec3& p : receivers.points) {
        const penumbra::DsmCoord c = penumbra::dsmCoord(builder.params(), p);
        queries.emplace_back(c.u, c.v, c.depth, 0.0f);
    }
    penumbra::gl::Buffer q = penumbra::gl::Buffer::fromVector(queries), r(queries.size() * 16);
    const uint32_t n = static_cast<uint32_t>(queries.size());
    auto run = [&] { builder.lookup({q.id(), 0, q.size()}, {r.id(), 0, r.size()}, n); };
    penumbra::bench::timeGpu(run);
    for (auto _ : state) state.SetIterationTime(penumbra::bench::timeGpu(run));
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
    std::vector<glm::vec4> got(queries.size());
    glGetNamedBufferSubData(r.id(), 0, static_cast<GLsizeiptr>(r.size()), got.data());
    double differ = 0.0;
    for (size_t i = 0; i < queries.size(); ++i)
        differ += penumbra::detail::floatBits(got[i].x) !=
                  penumbra::detail::floatBits(penumbra::dsmLookup(cpu, queries[i].x, queries[i].y, queries[i].z, 0.0f));
    state.counters["err_bits_vs_twin"] = differ;
    state.counters["lookups"] = double(n);
    penumbra::bench::reportTimer(state);
}

// ---- registration (in this order: the table's and the stage entries' caches feed the later ones) ----

const bool kDsmRegistered = [] {
    using Args = std::vector<uint32_t>;
    const std::vector<std::string> scenes = smoke() ? std::vector<std::string>{"hairball"}
                                                    : std::vector<std::string>{"hairball", "grass"};
    const Args table_samples = smoke() ? Args{4} : Args{16, 64, 256};
    const Args eps_divs = smoke() ? Args{2} : Args{1, 2, 4};
    for (const std::string& scene : scenes)
        for (uint32_t S : table_samples) {
            // Every tolerance of one (scene, S) in a row: they share tableData's cached fragments.
            std::vector<std::pair<std::string, float>> tolerances;
            for (uint32_t div : eps_divs) tolerances.emplace_back(std::to_string(div), 1.0f / static_cast<float>(div * S));
            tolerances.emplace_back("paper", 0.25f / std::sqrt(static_cast<float>(S)));  // in smoke runs too: CI runs it
            for (const auto& [tag, eps] : tolerances) {
                const std::string name = "BM_DsmCompressionTable/" + scene + "/" + std::to_string(S) + "/" + tag;
                configure(benchmark::RegisterBenchmark(name.c_str(), [scene, S, eps = eps, tag = tag](benchmark::State& st) {
                    compressionTable(st, scene, S, eps, tag);
                }));
            }
        }
    const Args resolutions = smoke() ? Args{32} : Args{64, 128, 256};
    const Args samples = smoke() ? Args{4} : Args{16, 64};
    auto each = [&](const char* base, void (*entry)(benchmark::State&, uint32_t, uint32_t), const Args& rs) {
        for (uint32_t R : rs)
            for (uint32_t S : samples) {
                const std::string name = std::string(base) + "/" + std::to_string(R) + "/" + std::to_string(S);
                configure(benchmark::RegisterBenchmark(
                    name.c_str(), [entry, R, S](benchmark::State& st) { entry(st, R, S); }));
            }
    };
    each("BM_DsmBuildFragments", buildFragmentsEntry, resolutions);
    each("BM_DsmMergeCompress", mergeCompressEntry, resolutions);
    each("BM_DsmMips", mipsEntry, resolutions);
    const Args lookup_resolutions = smoke() ? Args{32} : Args{128, 256};
    // Lookup error on both scenes: the deep shadow map and, at equal memory, a PCF shadow map.
    for (const std::string& scene : scenes)
        for (uint32_t R : lookup_resolutions)
            for (uint32_t S : samples) {
                const std::string tail = "/" + scene + "/" + std::to_string(R) + "/" + std::to_string(S);
                configure(benchmark::RegisterBenchmark(("BM_DsmLookup" + tail).c_str(),
                                                       [scene, R, S](benchmark::State& st) { lookupEntry(st, scene, R, S); }));
                configure(benchmark::RegisterBenchmark(("BM_DsmPcfBaseline" + tail).c_str(),
                                                       [scene, R, S](benchmark::State& st) { pcfBaselineEntry(st, scene, R, S); }));
            }
    const Args gpu_resolutions = smoke() ? Args{32} : Args{64, 128, 256};
    for (uint32_t R : gpu_resolutions)
        for (uint32_t S : samples) {
            const std::string b = "BM_DsmGpuBuild/" + std::to_string(R) + "/" + std::to_string(S);
            configure(benchmark::RegisterBenchmark(b.c_str(), [R, S](benchmark::State& st) { gpuBuildEntry(st, R, S); }))
                ->UseManualTime();
        }
    for (uint32_t R : lookup_resolutions)
        for (uint32_t S : samples) {
            const std::string b = "BM_DsmGpuLookup/" + std::to_string(R) + "/" + std::to_string(S);
            configure(benchmark::RegisterBenchmark(b.c_str(), [R, S](benchmark::State& st) { gpuLookupEntry(st, R, S); }))
                ->UseManualTime();
        }
    return true;
}();

}  // namespace
