// Hierarchical penumbra casting (penumbra/penumbra_casting.hpp, laine2005) against the shadow rays
// a user would trace instead: Embree 3 (Debian libembree-dev), same receivers, same light samples,
// all cores, in one run. The seed's protocol (laine2005 §4, Table 2): a rectangular light, 256
// samples at 640 x 480 and 1280 x 960, 1024 samples at 1280 x 960, and the light's area x 4 at
// 1280 x 960 with 256 samples; 32 samples per group, 16 receivers per leaf, 8 sample sets.
//
// Receivers: the camera's primary rays at W x H hit points (the oracle's closestHit, double),
// background pixels dropped; receiver (x, y) uses sample set lightSampleSet(x, y, 0, 8), on both
// sides. Blockers: every triangle of the scene, streamed to penumbraCast one at a time.
//
// Embree: one RTCScene of the same (float) triangles, RTC_SCENE_FLAG_ROBUST, build quality high;
// per receiver rtcOccluded16 packets of its N samples (origin the receiver, direction sample -
// receiver, t in [1e-4, 1]: Embree has no coplanar rule, so a receiver on a surface needs the
// usual offset), receivers spread over all cores (std::thread, dynamic chunks). Embree's build is
// timed separately: ray tracing needs it every frame for a dynamic scene, penumbra casting needs no
// scene hierarchy at all.
//
// Counters (per entry):
//   ours_ms, embree_ms                       wall clock, median of 3 warm rounds (each side
//                                            reusing its output storage of the round before)
//   ours_cold_ms, embree_cold_ms, ratio_cold the first round: outputs allocated and first-touched
//   embree_build_ms                          Embree's scene build, once
//   ratio_ours_over_embree                   ours_ms / embree_ms (< 1: penumbra casting wins)
//   ratio_ours_over_embree_with_build        ours_ms / (embree_ms + embree_build_ms)
//   ours_mask_bytes_peak, mask_bytes_full    on-demand masks vs R * N / 8
//   embree_bytes_peak                        Embree's allocations (its memory monitor callback)
//   err_ours_vs_embree_bits                  share of (receiver, sample) bits that differ
//   err_ours_vs_oracle                       non-tie bits that differ from the double oracle, on
//                                            every `kOracleStride`-th receiver (must be 0)
//   err_embree_vs_oracle                     share of those receivers' non-tie bits Embree gets
//                                            wrong (float, the offset)
//   oracle_ties, receivers, samples, triangles, blocked_fraction, pairs_classified (ours: pairs the
//   oracle's test decided), pairs_certified (ours: pairs the certified fast path decided)
// BM_PenumbraCastingOptimizations: each §3.3 optimization (and area sorting, and the certified fast
// path of per-pair verdicts) switched off alone at
// 640 x 480 x 256, `speedup` = time with it off / time with everything on (same run, interleaved),
// `identical` = 1 when its bits equal the all-on run's.
// Environment: PENUMBRA_HPC_SCENES (comma list of built-in scenes; default columns,grass),
// PENUMBRA_BENCH_SMOKE=1 (64 x 48 and 96 x 72 pixels, 32 and 64 samples: ctest's smoke run).
#include <penumbra/light_samples.hpp>
#include <penumbra/penumbra_casting.hpp>
#include <penumbra/reference/visibility.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

namespace {

using glm::dvec3;

constexpr uint32_t kSets = 8;
constexpr size_t kOracleStride = 61;  // receivers compared with the oracle: every 61st
constexpr float kEmbreeTNear = 1e-4f;

bool smokeRun() {
    const char* env = std::getenv("PENUMBRA_BENCH_SMOKE");
    return env && std::strcmp(env, "1") == 0;
}

std::vector<std::string> sceneNames() {
    const char* env = std::getenv("PENUMBRA_HPC_SCENES");
    std::string list = env && *env ? env : (smokeRun() ? "columns" : "columns,grass");
    std::vector<std::string> names;
    std::stringstream in(list);
    for (std::string name; std::getline(in, name, ',');) {
        if (!name.empty()) names.push_back(name);
    }
    return names;
}

unsigned threadCount() { return std::max(1u, std::thread::hardware_concurrency()); }

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// Runs f(begin, end) over [0, n) in dynamic chunks on every core.
template <typename F>
void parallelChunks(size_t n, size_t chunk, F&& f) {
    std::atomic<size_t> next{0};
    std::vector<std::thread> threads;
    for (unsigned t = 0; t < threadCount(); ++t) {
        threads.emplace_back([&] {
            for (size_t begin = next.fetch_add(chunk); begin < n; begin = next.fetch_add(chunk)) f(begin, std::min(n, begin + chunk));
        });
    }
    for (std::thread& t : threads) t.join();
}

// ---- the workload ---------------------------------------------------------------------------

struct Geometry {
    std::vector<dvec3> positions;
    std::vector<uint32_t> indices;
    std::unique_ptr<penumbra::reference::VisibilityOracle> oracle;
};

struct Receivers {
    std::vector<dvec3> points;
    std::vector<uint32_t> sets;  // lightSampleSet of the receiver's pixel
};

const penumbra::scene::Scene& sceneNamed(const std::string& name) {
    static std::map<std::string, penumbra::scene::Scene> scenes;
    auto it = scenes.find(name);
    if (it == scenes.end()) it = scenes.emplace(name, penumbra::scene::builtin(name)).first;
    return it->second;
}

const Geometry& geometry(const std::string& name) {
    static std::map<std::string, Geometry> cache;
    auto it = cache.find(name);
    if (it != cache.end()) return it->second;
    Geometry g;
    const penumbra::scene::Mesh mesh = sceneNamed(name).merged();
    for (const glm::vec3& p : mesh.positions) g.positions.emplace_back(p);
    g.indices = mesh.indices;
    g.oracle = std::make_unique<penumbra::reference::VisibilityOracle>(g.positions, g.indices);
    return cache.emplace(name, std::move(g)).first->second;
}

/// Primary-ray hit points at width x height (the demo's camera), in pixel order.
const Receivers& receivers(const std::string& name, uint32_t width, uint32_t height) {
    static std::map<std::tuple<std::string, uint32_t, uint32_t>, Receivers> cache;
    const auto key = std::make_tuple(name, width, height);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    const penumbra::scene::Scene& scene = sceneNamed(name);
    const Geometry& g = geometry(name);
    const glm::mat4 view_projection = scene.camera.projection(float(width) / float(height)) * scene.camera.view();
    const glm::dmat4 inverse = glm::inverse(glm::dmat4(view_projection));
    const dvec3 eye(scene.camera.eye);
    std::vector<dvec3> hit(size_t(width) * height);
    std::vector<uint8_t> valid(hit.size(), 0);
    parallelChunks(hit.size(), 1024, [&](size_t begin, size_t end) {
        for (size_t i = begin; i < end; ++i) {
            const uint32_t x = uint32_t(i % width), y = uint32_t(i / width);
            const glm::dvec4 ndc((x + 0.5) / width * 2 - 1, (y + 0.5) / height * 2 - 1, 1.0, 1.0);
            const glm::dvec4 far_point = inverse * ndc;
            const dvec3 dir = glm::normalize(dvec3(far_point) / far_point.w - eye);
            const penumbra::reference::Hit h = g.oracle->closestHit(eye, dir, 0.0, 1e30);
            if (h.hit) {
                hit[i] = eye + h.t * dir;
                valid[i] = 1;
            }
        }
    });
    Receivers r;
    for (size_t i = 0; i < hit.size(); ++i) {
        if (!valid[i]) continue;
        r.points.push_back(hit[i]);
        r.sets.push_back(penumbra::lightSampleSet(uint32_t(i % width), uint32_t(i / width), 0, kSets));
    }
    return cache.emplace(key, std::move(r)).first->second;
}

/// The seed's rectangular light: centred on the scene's light, facing the scene's centre, half
/// extents the scene light's radius (times sqrt(area_scale)).
penumbra::LightSampleSets lightSamples(const std::string& name, uint32_t samples, double area_scale) {
    const penumbra::scene::Scene& scene = sceneNamed(name);
    penumbra::Light light;
    light.shape = penumbra::LightShape::Rectangle;
    light.center = dvec3(scene.light.position);
    const penumbra::scene::Bounds box = scene.bounds();
    const dvec3 centre(box.center());
    light.axis_z = centre - light.center;
    light.axis_x = std::abs(light.axis_z.x) < 0.9 * glm::length(light.axis_z) ? dvec3(1, 0, 0) : dvec3(0, 0, 1);
    const double half = double(scene.light.radius) * std::sqrt(area_scale);
    light.size = dvec3(half, half, 0.0);
    penumbra::LightSampleOptions options;
    options.count = samples;
    options.sets = kSets;
    return penumbra::makeLightSampleSets(light, options);
}

// ---- penumbra casting -------------------------------------------------------------------------

/// Into `out`, whose storage a warm run reuses (PenumbraCaster::finish(result)).
void runOurs(penumbra::PenumbraCastingResult& out, const std::string& name, const Receivers& r,
             const penumbra::LightSampleSets& sets, const penumbra::PenumbraCastingOptions& options) {
    const Geometry& g = geometry(name);
    size_t next = 0;
    penumbra::penumbraCast(
        out, r.points, sets.light, sets,
        [&](dvec3& a, dvec3& b, dvec3& c) {
            if (next + 3 > g.indices.size()) return false;
            a = g.positions[g.indices[next]];
            b = g.positions[g.indices[next + 1]];
            c = g.positions[g.indices[next + 2]];
            next += 3;
            return true;
        },
        options, r.sets);
}

// ---- Embree -----------------------------------------------------------------------------------

struct EmbreeMemory {
    std::atomic<int64_t> now{0}, peak{0};
};

bool embreeMemoryMonitor(void* user, ssize_t bytes, bool /*post*/) {
    auto* m = static_cast<EmbreeMemory*>(user);
    const int64_t now = m->now.fetch_add(int64_t(bytes)) + int64_t(bytes);
    int64_t peak = m->peak.load();
    while (now > peak && !m->peak.compare_exchange_weak(peak, now)) {
    }
    return true;
}

struct EmbreeScene {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    EmbreeMemory memory;
    double build_seconds = 0.0;

    explicit EmbreeScene(const Geometry& g) {
        device = rtcNewDevice(nullptr);
        if (!device) throw std::runtime_error("rtcNewDevice failed");
        rtcSetDeviceMemoryMonitorFunction(device, embreeMemoryMonitor, &memory);
        const auto start = std::chrono::steady_clock::now();
        scene = rtcNewScene(device);
        rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
        rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
        RTCGeometry mesh = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                     3 * sizeof(float), g.positions.size()));
        for (size_t i = 0; i < g.positions.size(); ++i) {
            vertices[3 * i] = float(g.positions[i].x);
            vertices[3 * i + 1] = float(g.positions[i].y);
            vertices[3 * i + 2] = float(g.positions[i].z);
        }
        auto* triangles = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                         3 * sizeof(uint32_t), g.indices.size() / 3));
        std::memcpy(triangles, g.indices.data(), g.indices.size() * sizeof(uint32_t));
        rtcSetGeometryBuildQuality(mesh, RTC_BUILD_QUALITY_HIGH);
        rtcCommitGeometry(mesh);
        rtcAttachGeometry(scene, mesh);
        rtcReleaseGeometry(mesh);
        rtcCommitScene(scene);
        build_seconds = secondsSince(start);
    }
    ~EmbreeScene() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
    EmbreeScene(const EmbreeScene&) = delete;
    EmbreeScene& operator=(const EmbreeScene&) = delete;

    /// Blocked bits in the oracle's layout: bit s of receiver r's words = sample s occluded.
    /// Into `bits`, whose storage a warm run reuses.
    void occluded(const Receivers& r, const penumbra::LightSampleSets& sets, std::vector<uint32_t>& bits) const {
        const uint32_t n = sets.count(), words = n / 32;
        bits.assign(r.points.size() * words, 0u);
        parallelChunks(r.points.size(), 64, [&](size_t begin, size_t end) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // one origin, directions to one light
            alignas(64) RTCRay16 rays;
            alignas(64) int valid[16];
            for (int& v : valid) v = -1;
            for (size_t i = begin; i < end; ++i) {
                const dvec3 p = r.points[i];
                const dvec3* samples = sets.worldSet(r.sets[i]);
                for (uint32_t s0 = 0; s0 < n; s0 += 16) {
                    for (int k = 0; k < 16; ++k) {
                        const dvec3 d = samples[s0 + k] - p;
                        rays.org_x[k] = float(p.x);
                        rays.org_y[k] = float(p.y);
                        rays.org_z[k] = float(p.z);
                        rays.dir_x[k] = float(d.x);
                        rays.dir_y[k] = float(d.y);
                        rays.dir_z[k] = float(d.z);
                        rays.tnear[k] = kEmbreeTNear;
                        rays.tfar[k] = 1.0f;
                        rays.time[k] = 0.0f;
                        rays.mask[k] = 0xFFFFFFFFu;
                        rays.id[k] = unsigned(k);
                        rays.flags[k] = 0;
                    }
                    rtcOccluded16(valid, scene, &context, &rays);
                    uint32_t word = 0;
                    for (int k = 0; k < 16; ++k) word |= uint32_t(rays.tfar[k] < 0.0f) << k;
                    bits[i * words + s0 / 32] |= word << (s0 % 32);
                }
            }
        });
    }
};

// ---- comparisons ------------------------------------------------------------------------------

struct OracleComparison {
    uint64_t bits = 0, ties = 0, ours_wrong = 0, embree_wrong = 0;
};

/// Every kOracleStride-th receiver against the oracle, per sample set (the oracle takes one list).
OracleComparison compareWithOracle(const std::string& name, const Receivers& r, const penumbra::LightSampleSets& sets,
                                   const std::vector<uint32_t>& ours, const std::vector<uint32_t>& embree) {
    OracleComparison c;
    const Geometry& g = geometry(name);
    const uint32_t n = sets.count(), words = n / 32;
    for (uint32_t set = 0; set < sets.sets(); ++set) {
        std::vector<size_t> ids;
        std::vector<dvec3> points;
        for (size_t i = 0; i < r.points.size(); i += kOracleStride) {
            if (r.sets[i] != set) continue;
            ids.push_back(i);
            points.push_back(r.points[i]);
        }
        if (ids.empty()) continue;
        const std::vector<dvec3> samples(sets.worldSet(set), sets.worldSet(set) + n);
        const penumbra::reference::VisibilityResult expected = g.oracle->evaluate(points, samples);
        for (size_t k = 0; k < ids.size(); ++k) {
            for (uint32_t w = 0; w < words; ++w) {
                const uint32_t want = expected.blocked[k * words + w], tie = expected.ties[k * words + w];
                c.ties += uint64_t(__builtin_popcount(tie));
                c.bits += 32;
                c.ours_wrong += uint64_t(__builtin_popcount((ours[ids[k] * words + w] ^ want) & ~tie));
                c.embree_wrong += uint64_t(__builtin_popcount((embree[ids[k] * words + w] ^ want) & ~tie));
            }
        }
    }
    return c;
}

uint64_t differingBits(const std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    uint64_t count = 0;
    for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) count += uint64_t(__builtin_popcount(a[i] ^ b[i]));
    return count + 32 * (std::max(a.size(), b.size()) - std::min(a.size(), b.size()));
}

// ---- entries ----------------------------------------------------------------------------------

struct Config {
    uint32_t width, height, samples;
    double area_scale;
};

Config config(int index) {
    if (smokeRun()) {  // distinct names, seconds in all
        static const Config smoke[] = {{64, 48, 32, 1.0}, {96, 72, 32, 1.0}, {96, 72, 64, 1.0}, {96, 72, 32, 4.0}};
        return smoke[index];
    }
    static const Config configs[] = {{640, 480, 256, 1.0}, {1280, 960, 256, 1.0}, {1280, 960, 1024, 1.0}, {1280, 960, 256, 4.0}};
    return configs[index];
}

/// Rounds per VsEmbree entry: 1 cold + 3 warm (the counters take the warm ones' medians).
constexpr int kRounds = 4;

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

void BM_PenumbraCastingVsEmbree(benchmark::State& state, const std::string& name, int config_index) {
    const Config c = config(config_index);
    const Receivers& r = receivers(name, c.width, c.height);
    const penumbra::LightSampleSets sets = lightSamples(name, c.samples, c.area_scale);
    const EmbreeScene embree(geometry(name));
    penumbra::PenumbraCastingResult ours;
    std::vector<uint32_t> embree_bits;
    // Round 0 is cold: both sides allocate (and first-touch) their R N / 8 output bytes, ours its
    // R N / 16 of tie bits too. The later rounds reuse last round's output storage on both sides,
    // as a renderer casting every frame would; ours still builds its receiver hierarchy and
    // volumes from scratch each round. Interleaved: ours then Embree, in every round.
    const int rounds = smokeRun() ? 2 : kRounds;
    std::vector<double> ours_warm, embree_warm;
    double ours_cold = 0.0, embree_cold = 0.0;
    for (auto _ : state) {
        for (int round = 0; round < rounds; ++round) {
            auto start = std::chrono::steady_clock::now();
            runOurs(ours, name, r, sets, {});
            const double ours_s = secondsSince(start);
            start = std::chrono::steady_clock::now();
            embree.occluded(r, sets, embree_bits);
            const double embree_s = secondsSince(start);
            if (round == 0) {
                ours_cold = ours_s;
                embree_cold = embree_s;
            } else {
                ours_warm.push_back(ours_s);
                embree_warm.push_back(embree_s);
            }
        }
        state.SetIterationTime(median(ours_warm));
    }
    const double ours_s = median(ours_warm), embree_s = median(embree_warm);
    const OracleComparison o = compareWithOracle(name, r, sets, ours.blocked, embree_bits);
    uint64_t blocked = 0;
    for (uint32_t w : ours.blocked) blocked += uint64_t(__builtin_popcount(w));
    const double total_bits = double(r.points.size()) * c.samples;
    state.counters["ours_ms"] = 1e3 * ours_s;
    state.counters["embree_ms"] = 1e3 * embree_s;
    state.counters["ours_cold_ms"] = 1e3 * ours_cold;
    state.counters["embree_cold_ms"] = 1e3 * embree_cold;
    state.counters["embree_build_ms"] = 1e3 * embree.build_seconds;
    state.counters["ratio_ours_over_embree"] = embree_s > 0 ? ours_s / embree_s : 0.0;
    state.counters["ratio_cold"] = embree_cold > 0 ? ours_cold / embree_cold : 0.0;
    state.counters["ratio_ours_over_embree_with_build"] = ours_s / std::max(1e-12, embree_s + embree.build_seconds);
    state.counters["ours_mask_bytes_peak"] = double(ours.stats.mask_bytes_peak);
    state.counters["mask_bytes_full"] = total_bits / 8;
    state.counters["embree_bytes_peak"] = double(embree.memory.peak.load());
    state.counters["err_ours_vs_embree_bits"] = total_bits > 0 ? double(differingBits(ours.blocked, embree_bits)) / total_bits : 0.0;
    state.counters["err_ours_vs_oracle"] = double(o.ours_wrong);
    state.counters["err_embree_vs_oracle"] = o.bits ? double(o.embree_wrong) / double(o.bits) : 0.0;
    state.counters["oracle_ties"] = double(o.ties);
    state.counters["oracle_bits_compared"] = double(o.bits);
    state.counters["receivers"] = double(r.points.size());
    state.counters["samples"] = c.samples;
    state.counters["light_area_scale"] = c.area_scale;
    state.counters["triangles"] = double(geometry(name).indices.size() / 3);
    state.counters["blocked_fraction"] = total_bits > 0 ? double(blocked) / total_bits : 0.0;
    state.counters["pairs_classified"] = double(ours.stats.pairs_classified);  // by the oracle's own test
    state.counters["pairs_certified"] = double(ours.stats.pairs_certified);    // by the certified fast path
    state.counters["threads"] = threadCount();
    state.SetLabel(name + " " + std::to_string(c.width) + "x" + std::to_string(c.height) + " N=" + std::to_string(c.samples) +
                   (c.area_scale != 1.0 ? " light area x" + std::to_string(int(c.area_scale)) : ""));
}

const char* const kOptimizationNames[] = {"umbra_bits",      "active_planes", "lazy_volumes",
                                          "on_demand_masks", "area_sort",     "certified_fast_path"};
constexpr int kOptimizations = 6;

void BM_PenumbraCastingOptimizations(benchmark::State& state, const std::string& name, int which) {
    const Config c = config(0);
    const Receivers& r = receivers(name, c.width, c.height);
    const penumbra::LightSampleSets sets = lightSamples(name, c.samples, 1.0);
    penumbra::PenumbraCastingOptions off;
    bool* switches[] = {&off.umbra_bits,      &off.active_planes, &off.lazy_volumes,
                        &off.on_demand_masks, &off.area_sort,     &off.certified_fast_path};
    static_assert(sizeof(switches) / sizeof(switches[0]) == kOptimizations, "one switch per name");
    *switches[which] = false;
    penumbra::PenumbraCastingResult all_on, one_off;
    std::vector<double> on_s, off_s;
    size_t iteration = 0;
    for (auto _ : state) {
        for (int k = 0; k < 2; ++k) {  // interleaved, alternating which runs first
            const bool run_off = (k + iteration) % 2 == 1;
            const auto start = std::chrono::steady_clock::now();
            if (run_off) runOurs(one_off, name, r, sets, off);
            else runOurs(all_on, name, r, sets, {});
            (run_off ? off_s : on_s).push_back(secondsSince(start));
        }
        state.SetIterationTime(off_s.back());
        ++iteration;
    }
    state.counters["all_on_ms"] = 1e3 * median(on_s);
    state.counters["off_ms"] = 1e3 * median(off_s);
    state.counters["speedup"] = median(on_s) > 0 ? median(off_s) / median(on_s) : 0.0;
    state.counters["identical"] = all_on.blocked == one_off.blocked && all_on.ties == one_off.ties ? 1.0 : 0.0;
    state.counters["mask_bytes_peak_off"] = double(one_off.stats.mask_bytes_peak);
    state.counters["mask_bytes_peak_on"] = double(all_on.stats.mask_bytes_peak);
    state.SetLabel(name + " " + kOptimizationNames[which] + " off");
}

const bool kRegistered = [] {
    for (const std::string& name : sceneNames()) {
        for (int k = 0; k < 4; ++k) {
            const Config c = config(k);
            std::string entry = "BM_PenumbraCastingVsEmbree/" + name + "/" + std::to_string(c.width) + "x" +
                                std::to_string(c.height) + "/N" + std::to_string(c.samples);
            if (c.area_scale != 1.0) entry += "/area4";
            benchmark::RegisterBenchmark(entry.c_str(), BM_PenumbraCastingVsEmbree, name, k)
                ->UseManualTime()
                ->Iterations(1)
                ->Unit(benchmark::kMillisecond);
        }
        for (int which = 0; which < kOptimizations; ++which) {
            const std::string entry = "BM_PenumbraCastingOptimizations/" + name + "/" + kOptimizationNames[which];
            benchmark::RegisterBenchmark(entry.c_str(), BM_PenumbraCastingOptimizations, name, which)
                ->UseManualTime()
                ->Iterations(smokeRun() ? 1 : 3)
                ->Unit(benchmark::kMillisecond);
        }
    }
    return true;
}();

}  // namespace
