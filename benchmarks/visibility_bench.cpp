// Throughput of the double-precision visibility oracle (reference/visibility.hpp), CPU only.
//
// Scenes (built once per size, outside the timed loop):
//   soup = random triangles of random size around [-1, 1]^3, receivers in space and on the mesh,
//          a ball light (the shape of the tests' brute-force comparisons);
//   city = a 64 x 64-quad ground plus tessellated boxes standing on it, receivers on the ground,
//          a ball light above: the shape of a soft-shadow workload.
// Counters:
//   segments_per_second        (receiver, sample) pairs per wall-clock second, all threads;
//   nodes_visited_per_segment  BVH node bounds tested per pair (device independent);
//   triangle_tests_per_segment triangle classifications per pair (device independent);
//   blocked_fraction, tie_fraction;
//   err_mismatches_vs_brute    pairs whose blocked or tie bit differs from evaluateBruteForce on a
//                              subset of receivers (checked once per scene; must be 0);
//   threads.
// PENUMBRA_BENCH_SMOKE=1 (ctest's smoke run) shrinks the receiver counts so everything runs fast.
// Example: penumbra_bench --benchmark_filter='BM_VisibilityEvaluate/city' --benchmark_repetitions=3
#include <penumbra/reference/light_samples.hpp>
#include <penumbra/reference/visibility.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <thread>
#include <utility>
#include <vector>

namespace {

using glm::dvec3;
using penumbra::reference::VisibilityOptions;
using penumbra::reference::VisibilityOracle;
using penumbra::reference::VisibilityResult;

bool smokeRun() {
    const char* env = std::getenv("PENUMBRA_BENCH_SMOKE");
    return env && std::strcmp(env, "1") == 0;
}

struct Rng {
    uint64_t state;
    explicit Rng(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    double uniform(double lo = 0.0, double hi = 1.0) {
        return lo + (hi - lo) * (static_cast<double>(next() >> 11) * 0x1.0p-53);
    }
    dvec3 point(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
};

enum SceneKind : int { kSoup = 0, kCity = 1 };

struct Scene {
    std::vector<dvec3> positions;
    std::vector<uint32_t> indices;
    std::vector<dvec3> receivers;
    std::vector<dvec3> samples;
    std::unique_ptr<VisibilityOracle> oracle;
    uint64_t err_mismatches = 0;

    void triangle(const dvec3& a, const dvec3& b, const dvec3& c) {
        for (const dvec3& p : {a, b, c}) {
            indices.push_back(static_cast<uint32_t>(positions.size()));
            positions.push_back(p);
        }
    }
    void quad(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& d) {
        triangle(a, b, c);
        triangle(a, c, d);
    }
};

void buildSoup(Scene& scene, Rng& rng, size_t triangles, size_t receivers) {
    const double size_max = 0.6 * std::min(1.0, std::sqrt(200.0 / static_cast<double>(triangles)));
    for (size_t i = 0; i < triangles; ++i) {
        const dvec3 centre = rng.point(-1, 1);
        const double size = size_max * std::exp(rng.uniform(std::log(1.0 / 30.0), 0.0));
        scene.triangle(centre + size * rng.point(-1, 1), centre + size * rng.point(-1, 1),
                       centre + size * rng.point(-1, 1));
    }
    for (size_t i = 0; i < receivers; ++i) scene.receivers.push_back(rng.point(-1.3, 1.3));
    scene.samples = penumbra::reference::sphereLightSamples(dvec3(0.3, 2.0, 0.1), 0.4, 64, 1);
}

void buildCity(Scene& scene, Rng& rng, size_t triangles, size_t receivers) {
    const int grid = 64;
    const double half = 32.0;
    for (int j = 0; j < grid; ++j)
        for (int i = 0; i < grid; ++i) {
            const double x0 = -half + 2 * half * i / grid, x1 = -half + 2 * half * (i + 1) / grid;
            const double y0 = -half + 2 * half * j / grid, y1 = -half + 2 * half * (j + 1) / grid;
            scene.quad({x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0});
        }
    // Open-bottom boxes, 10 triangles each, sized so they cover ~30% of the ground at any count.
    const size_t boxes = triangles > scene.indices.size() / 3 ? (triangles - scene.indices.size() / 3) / 10 : 0;
    const double s0 = std::min(1.2, std::sqrt(0.3 * 56.0 * 56.0 / (4.0 * static_cast<double>(std::max<size_t>(boxes, 1)))));
    for (size_t box = 0; box < boxes; ++box) {
        const double x = rng.uniform(-28, 28), y = rng.uniform(-28, 28);
        const double sx = s0 * rng.uniform(0.5, 1.5), sy = s0 * rng.uniform(0.5, 1.5), h = s0 * rng.uniform(1.0, 8.0);
        const dvec3 a(x - sx, y - sy, 0), b(x + sx, y - sy, 0), c(x + sx, y + sy, 0), d(x - sx, y + sy, 0);
        const dvec3 up(0, 0, h);
        scene.quad(a, b, b + up, a + up);
        scene.quad(b, c, c + up, b + up);
        scene.quad(c, d, d + up, c + up);
        scene.quad(d, a, a + up, d + up);
        scene.quad(a + up, b + up, c + up, d + up);
    }
    for (size_t i = 0; i < receivers; ++i) scene.receivers.push_back({rng.uniform(-30, 30), rng.uniform(-30, 30), 0.0});
    scene.samples = penumbra::reference::sphereLightSamples(dvec3(10, 20, 40), 2.0, 64, 1);
}

/// Built once per (kind, triangles); also checks the BVH against brute force on a few receivers.
Scene& scene(int kind, size_t triangles) {
    static std::map<std::pair<int, size_t>, std::unique_ptr<Scene>> cache;
    std::unique_ptr<Scene>& slot = cache[{kind, triangles}];
    if (!slot) {
        slot = std::make_unique<Scene>();
        Rng rng(0x5eed0000u + triangles * 2 + static_cast<uint64_t>(kind));
        const size_t receivers = smokeRun() ? 8 : 256;
        if (kind == kSoup)
            buildSoup(*slot, rng, triangles, receivers);
        else
            buildCity(*slot, rng, triangles, receivers);
        slot->oracle = std::make_unique<VisibilityOracle>(slot->positions, slot->indices);
        const size_t check = std::min<size_t>(receivers, triangles > 50000 ? 2 : 8);
        const std::vector<dvec3> subset(slot->receivers.begin(), slot->receivers.begin() + check);
        const VisibilityResult bvh = slot->oracle->evaluate(subset, slot->samples);
        const VisibilityResult brute = slot->oracle->evaluateBruteForce(subset, slot->samples);
        for (size_t r = 0; r < subset.size(); ++r)
            for (size_t s = 0; s < slot->samples.size(); ++s)
                slot->err_mismatches +=
                    bvh.isBlocked(r, s) != brute.isBlocked(r, s) || bvh.isTie(r, s) != brute.isTie(r, s);
    }
    return *slot;
}

void reportEvaluate(benchmark::State& state, const Scene& scene, const VisibilityResult& last, uint64_t segments) {
    state.counters["segments_per_second"] =
        benchmark::Counter(static_cast<double>(segments) * static_cast<double>(state.iterations()),
                           benchmark::Counter::kIsRate);
    const double per = 1.0 / static_cast<double>(segments);
    state.counters["nodes_visited_per_segment"] = static_cast<double>(last.nodes_visited) * per;
    state.counters["triangle_tests_per_segment"] = static_cast<double>(last.triangle_tests) * per;
    uint64_t blocked = 0;
    for (size_t r = 0; r < last.receivers; ++r) blocked += last.blockedCount(r);
    state.counters["blocked_fraction"] = static_cast<double>(blocked) * per;
    state.counters["tie_fraction"] = static_cast<double>(last.tie_count) * per;
    state.counters["err_mismatches_vs_brute"] = static_cast<double>(scene.err_mismatches);
    state.counters["triangles"] = static_cast<double>(scene.oracle->triangleCount());
}

/// Args: scene kind, triangles, threads (0 = hardware concurrency).
void BM_VisibilityEvaluate(benchmark::State& state) {
    const Scene& s = scene(static_cast<int>(state.range(0)), static_cast<size_t>(state.range(1)));
    VisibilityOptions options;
    options.threads = static_cast<unsigned>(state.range(2));
    VisibilityResult last;
    for (auto _ : state) {
        last = s.oracle->evaluate(s.receivers, s.samples, options);
        benchmark::DoNotOptimize(last.blocked.data());
    }
    reportEvaluate(state, s, last, static_cast<uint64_t>(s.receivers.size() * s.samples.size()));
    state.counters["threads"] = options.threads != 0 ? options.threads : std::thread::hardware_concurrency();
}

/// The same predicate without the BVH, on a few receivers (its cost is segments x triangles).
void BM_VisibilityBruteForce(benchmark::State& state) {
    const Scene& s = scene(static_cast<int>(state.range(0)), static_cast<size_t>(state.range(1)));
    const std::vector<dvec3> receivers(s.receivers.begin(), s.receivers.begin() + std::min<size_t>(s.receivers.size(), 8));
    VisibilityOptions options;
    options.threads = 1;
    VisibilityResult last;
    for (auto _ : state) {
        last = s.oracle->evaluateBruteForce(receivers, s.samples, options);
        benchmark::DoNotOptimize(last.blocked.data());
    }
    reportEvaluate(state, s, last, static_cast<uint64_t>(receivers.size() * s.samples.size()));
}

/// One segmentBlocked call per pair (the per-query API, no result packing, one thread).
void BM_VisibilitySegmentBlocked(benchmark::State& state) {
    const Scene& s = scene(static_cast<int>(state.range(0)), static_cast<size_t>(state.range(1)));
    size_t r = 0, k = 0;
    uint64_t blocked = 0;
    for (auto _ : state) {
        blocked += s.oracle->segmentBlocked(s.receivers[r], s.samples[k]);
        if (++k == s.samples.size()) {
            k = 0;
            r = (r + 1) % s.receivers.size();
        }
    }
    benchmark::DoNotOptimize(blocked);
    state.counters["segments_per_second"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

/// Constructor cost: validation, degenerate filtering, binned-SAH build.
void BM_VisibilityBuild(benchmark::State& state) {
    const Scene& s = scene(static_cast<int>(state.range(0)), static_cast<size_t>(state.range(1)));
    size_t nodes = 0;
    int depth = 0;
    for (auto _ : state) {
        VisibilityOracle oracle(s.positions, s.indices);
        nodes = oracle.bvhNodeCount();
        depth = oracle.bvhDepth();
        benchmark::DoNotOptimize(nodes);
    }
    const double triangles = static_cast<double>(s.indices.size() / 3);
    state.counters["triangles_per_second"] =
        benchmark::Counter(triangles * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["bvh_nodes"] = static_cast<double>(nodes);
    state.counters["bvh_depth"] = depth;
}

/// Primary rays of the demo renderer: closest hit from a camera above the scene.
void BM_VisibilityClosestHit(benchmark::State& state) {
    const Scene& s = scene(static_cast<int>(state.range(0)), static_cast<size_t>(state.range(1)));
    const bool city = state.range(0) == kCity;
    const dvec3 eye = city ? dvec3(-40, -40, 30) : dvec3(-3, -3, 2);
    uint64_t hits = 0, rays = 0;
    size_t r = 0;
    for (auto _ : state) {
        const dvec3 target = s.receivers[r];
        r = (r + 1) % s.receivers.size();
        hits += s.oracle->closestHit(eye, target - eye, 0.0, INFINITY).hit;
        ++rays;
    }
    state.counters["rays_per_second"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
    state.counters["hit_fraction"] = rays ? static_cast<double>(hits) / static_cast<double>(rays) : 0.0;
}

/// Light-sample generation (kind 0 ball, 1 disk, 2 rect), count samples.
void BM_LightSamples(benchmark::State& state) {
    const int kind = static_cast<int>(state.range(0));
    const uint32_t count = static_cast<uint32_t>(state.range(1));
    const uint32_t side = static_cast<uint32_t>(std::sqrt(static_cast<double>(count)));
    for (auto _ : state) {
        std::vector<dvec3> samples;
        if (kind == 0) samples = penumbra::reference::sphereLightSamples(dvec3(1, 2, 3), 0.5, count, 7);
        if (kind == 1) samples = penumbra::reference::diskLightSamples(dvec3(1, 2, 3), dvec3(0, 0, 1), 0.5, count, 7);
        if (kind == 2) samples = penumbra::reference::rectLightSamples(dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0), side, side);
        benchmark::DoNotOptimize(samples.data());
    }
    const double produced = kind == 2 ? static_cast<double>(side) * side : count;
    state.counters["samples_per_second"] =
        benchmark::Counter(produced * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void evaluateArgs(benchmark::internal::Benchmark* b) {
    b->ArgNames({"scene", "triangles", "threads"});
    for (int64_t triangles : {1000, 20000, 200000}) {
        b->Args({kSoup, triangles, 1});
        b->Args({kSoup, triangles, 0});
    }
    for (int64_t triangles : {10000, 50000, 200000}) {
        b->Args({kCity, triangles, 1});
        b->Args({kCity, triangles, 0});
    }
}

}  // namespace

BENCHMARK(BM_VisibilityEvaluate)->Apply(evaluateArgs)->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VisibilityBruteForce)
    ->ArgNames({"scene", "triangles"})
    ->Args({kSoup, 1000})
    ->Args({kCity, 10000})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VisibilitySegmentBlocked)->ArgNames({"scene", "triangles"})->Args({kSoup, 20000})->Args({kCity, 50000});
BENCHMARK(BM_VisibilityBuild)
    ->ArgNames({"scene", "triangles"})
    ->Args({kSoup, 20000})
    ->Args({kCity, 200000})
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_VisibilityClosestHit)->ArgNames({"scene", "triangles"})->Args({kSoup, 20000})->Args({kCity, 200000});
BENCHMARK(BM_LightSamples)->ArgNames({"kind", "count"})->Args({0, 1024})->Args({1, 1024})->Args({2, 1024});
