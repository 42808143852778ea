// The exact blocker test, filtered (float with a proven error bound, double only where the sign is
// uncertain; PENUMBRA_AFH_FILTERED 1) against fp64-only (PENUMBRA_AFH_FILTERED 0), in one entry
// over the same (triangle, sample) pairs, in a compute shader that walks them the way the light
// pass does (one invocation per triangle and list: tests/shaders/alias_free_hard/
// blocker_filter_test.comp.glsl, penumbraAfhBlocksLight).
//
// Pairs: view samples drawn uniformly on the surfaces of a built-in scene (float points), the
// scene's point light, and for every sample the triangles whose bounding sphere its light ray
// passes (about the light pass's conservative coverage; the sample's own triangle among them).
//
// Counters: ms_filtered, ms_fp64 (per run, glFinish + wall clock), speedup = ms_fp64 /
// ms_filtered (measured in this entry), ms_deferred / speedup_deferred: the filter with its
// fallbacks deferred to the end of each window of 32 slots (mode 2 of the kernel: a SIMD group
// then runs its double tests together instead of at every iteration where one lane falls back),
// fallback = fraction of pairs the filter left to double,
// simd32_fallback = share of lock-step iterations of 32 invocations in which at least one lane
// takes the double path (what a 32-wide GPU pays for the inline fallback),
// pairs, err_mismatch = pairs where a filtered variant's verdict differs from fp64-only (must be 0).
// llvmpipe runs fp64 at nearly float speed (CPU SIMD: half the lanes), so the speed-up measured
// there understates GPUs whose fp64 rate is 1/32-1/64 of float.
#include "bench_common.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/scene/scene.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace {

struct BlockerPairs {
    std::vector<glm::vec4> triangles;   // 3 per triangle
    std::vector<glm::uvec4> fragments;  // triangle, first slot, count
    std::vector<glm::vec4> samples;     // per slot
    glm::vec4 light;
};

BlockerPairs blockerPairs(const std::string& name, size_t max_pairs) {
    const penumbra::scene::Scene scene = penumbra::scene::builtin(name);
    const penumbra::scene::Mesh mesh = scene.merged();
    BlockerPairs out;
    out.light = glm::vec4(scene.light.position, 1.0f);
    const size_t n = mesh.triangleCount();
    std::vector<glm::vec3> centers(n);
    std::vector<float> radii(n), areas(n);
    for (size_t t = 0; t < n; ++t) {
        const glm::vec3 v[3] = {mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                                mesh.positions[mesh.indices[3 * t + 2]]};
        for (const auto& x : v) out.triangles.push_back(glm::vec4(x, 1.0f));
        centers[t] = (v[0] + v[1] + v[2]) / 3.0f;
        radii[t] = std::max(glm::length(v[0] - centers[t]), std::max(glm::length(v[1] - centers[t]), glm::length(v[2] - centers[t])));
        areas[t] = glm::length(glm::cross(v[1] - v[0], v[2] - v[0])) + (t ? areas[t - 1] : 0.0f);
    }
    std::mt19937 rng(20261201u);
    const glm::vec3 light(out.light);
    std::vector<std::vector<glm::vec3>> lists(n);
    size_t pairs = 0;
    while (pairs < max_pairs) {
        const float pick = std::uniform_real_distribution<float>(0.0f, areas.back())(rng);
        const size_t t = std::min(size_t(std::lower_bound(areas.begin(), areas.end(), pick) - areas.begin()), n - 1);
        float u = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng), v = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
        if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
        const glm::vec3 a(out.triangles[3 * t]), b(out.triangles[3 * t + 1]), c(out.triangles[3 * t + 2]);
        const glm::vec3 p = a + u * (b - a) + v * (c - a);
        const glm::vec3 d = glm::normalize(p - light);
        const float reach = glm::length(p - light);
        for (size_t k = 0; k < n; ++k) {
            const glm::vec3 w = centers[k] - light;
            const float along = glm::dot(w, d);
            if (along < -radii[k] || along > reach + radii[k]) continue;
            if (glm::length(w - along * d) > radii[k] * 1.05f + 1e-3f * along) continue;
            lists[k].push_back(p);
            ++pairs;
        }
    }
    for (size_t k = 0; k < n; ++k) {
        for (size_t first = 0; first < lists[k].size(); first += 2048) {
            const size_t count = std::min<size_t>(2048, lists[k].size() - first);
            out.fragments.push_back(glm::uvec4(uint32_t(k), uint32_t(out.samples.size()), uint32_t(count), 0u));
            for (size_t i = first; i < first + count; ++i) out.samples.push_back(glm::vec4(lists[k][i], 1.0f));
        }
    }
    return out;
}

const char* const kBlockerScenes[] = {"hairball", "columns", "torus_knot"};

void BM_BlockerTestFilteredVsFp64(benchmark::State& state) {
    penumbra::bench::glContext();
    const std::string scene = kBlockerScenes[state.range(0)];
    const BlockerPairs pairs = blockerPairs(scene, penumbra::bench::smokeRun() ? 20000 : 1000000);
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.addDirectory(penumbra::test::testShaderDir());
    const std::string key = "alias_free_hard/blocker_filter_test.comp.glsl";
    penumbra::gl::Program check = penumbra::gl::buildComputeProgram(key, {{"PENUMBRA_AFH_FILTER_TEST_MODE", "0"}}, lib);
    penumbra::gl::Program filtered =
        penumbra::gl::buildComputeProgram(key, {{"PENUMBRA_AFH_FILTER_TEST_MODE", "1"}, {"PENUMBRA_AFH_FILTERED", "1"}}, lib);
    penumbra::gl::Program fp64 =
        penumbra::gl::buildComputeProgram(key, {{"PENUMBRA_AFH_FILTER_TEST_MODE", "1"}, {"PENUMBRA_AFH_FILTERED", "0"}}, lib);
    penumbra::gl::Program deferred = penumbra::gl::buildComputeProgram(key, {{"PENUMBRA_AFH_FILTER_TEST_MODE", "2"}}, lib);
    const auto triangles = penumbra::gl::Buffer::fromVector(pairs.triangles);
    const auto fragments = penumbra::gl::Buffer::fromVector(pairs.fragments);
    const auto samples = penumbra::gl::Buffer::fromVector(pairs.samples);
    const size_t slots = pairs.samples.size();
    penumbra::gl::Buffer results(slots * 4), results_fp64(slots * 4), results_check(slots * 4), results_deferred(slots * 4);
    const uint32_t fragment_count = uint32_t(pairs.fragments.size());
    const auto dispatch = [&](const penumbra::gl::Program& program, const penumbra::gl::Buffer& out) {
        glUseProgram(program.id());
        glUniform4fv(0, 1, &pairs.light.x);
        glUniform1f(1, 0.0f);
        glUniform1d(2, 1e-7);
        glUniform1d(3, 0.0);
        glUniform1ui(4, fragment_count);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, triangles.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragments.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, samples.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, out.id());
        glDispatchCompute((fragment_count + 63) / 64, 1, 1);
    };
    // Warm-up: llvmpipe compiles a shader variant at its first dispatch.
    penumbra::bench::timeGpu([&] {
        dispatch(filtered, results);
        dispatch(fp64, results_fp64);
        dispatch(deferred, results_deferred);
    });
    double filtered_s = 0, fp64_s = 0, deferred_s = 0;
    int runs = 0;
    for (auto _ : state) {
        const double f = penumbra::bench::timeGpu([&] { dispatch(filtered, results); });
        const double d = penumbra::bench::timeGpu([&] { dispatch(fp64, results_fp64); });
        const double q = penumbra::bench::timeGpu([&] { dispatch(deferred, results_deferred); });
        filtered_s += f;
        fp64_s += d;
        deferred_s += q;
        ++runs;
        state.SetIterationTime(f + d + q);
    }
    // Outside the timed region: the verdicts of both variants and the filter's states.
    dispatch(check, results_check);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const std::vector<uint32_t> a = results.download<uint32_t>(), b = results_fp64.download<uint32_t>();
    const std::vector<uint32_t> c = results_check.download<uint32_t>(), q = results_deferred.download<uint32_t>();
    uint64_t mismatch = 0, uncertain = 0;
    for (size_t i = 0; i < slots; ++i) {
        mismatch += a[i] != b[i] || q[i] != b[i] || ((c[i] >> 2) & 1u) != ((c[i] >> 3) & 1u) || ((c[i] >> 3) & 1u) != b[i];
        uncertain += (c[i] & 3u) == 2u;
    }
    // SIMD divergence (device-independent): 32 consecutive invocations walk their lists in lock
    // step; with the inline fallback a group runs the double test at every step where any lane
    // is uncertain. simd32_fallback = those steps / all steps (what a 32-wide GPU pays in fp64).
    uint64_t steps = 0, double_steps = 0;
    for (size_t g = 0; g < pairs.fragments.size(); g += 32) {
        const size_t end = std::min(pairs.fragments.size(), g + 32);
        uint32_t longest = 0;
        for (size_t f = g; f < end; ++f) longest = std::max(longest, pairs.fragments[f].z);
        for (uint32_t k = 0; k < longest; ++k) {
            bool any = false;
            for (size_t f = g; f < end && !any; ++f) {
                any = k < pairs.fragments[f].z && (c[pairs.fragments[f].y + k] & 3u) == 2u;
            }
            ++steps;
            double_steps += any;
        }
    }
    state.counters["simd32_fallback"] = steps ? double(double_steps) / double(steps) : 0.0;
    state.SetLabel(scene);
    penumbra::bench::reportTimer(state);  // which clock timed this entry
    state.counters["pairs"] = double(slots);
    state.counters["ms_filtered"] = 1e3 * filtered_s / std::max(runs, 1);
    state.counters["ms_fp64"] = 1e3 * fp64_s / std::max(runs, 1);
    state.counters["ms_deferred"] = 1e3 * deferred_s / std::max(runs, 1);
    state.counters["speedup"] = filtered_s > 0 ? fp64_s / filtered_s : 0.0;
    state.counters["speedup_deferred"] = deferred_s > 0 ? fp64_s / deferred_s : 0.0;
    state.counters["fallback"] = slots ? double(uncertain) / double(slots) : 0.0;
    state.counters["err_mismatch"] = double(mismatch);
}

}  // namespace

BENCHMARK(BM_BlockerTestFilteredVsFp64)->DenseRange(0, 2)->UseManualTime()->Unit(benchmark::kMillisecond);
