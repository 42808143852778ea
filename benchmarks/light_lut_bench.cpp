// The light-sample LUT (sintorn2008 §4.2): generation on the CPU and the GPU, and per-(view
// sample, plane) lookups on the device against the exact test.
//
// BM_LutGenerateCpu/<R>/<N>, BM_LutGenerateGpu/<R>/<N>: one certified LUT (R^3 cells, N ball
// samples, one set: N / 128 tables). Cpu = generateLightLut on all cores; Gpu = LightLutGenerator::
// generate, timed with penumbra::bench::timeGpu. Counters: memory_bytes (the LUT), texels,
// err_words (Gpu: words that differ from the CPU table; must be 0), dispatches (Gpu).
//
// BM_LutLookup/<R>/<N>, BM_LutLookupCertified/<R>/<N>, BM_ExactBehind/<R>/<N>: M random planes
// (unit normal through a point within 1.5 of the light's centre, the light's normalised space)
// against every table: one compute invocation per (plane, table), tests/shaders/light_lut/
// lookup_test.comp.glsl modes 1 (penumbraLutBehind, seed-mode LUT), 2 (penumbraLutBehindCertified
// + penumbraLutResolve: exact answers, the uncertain samples tested against the plane) and 3
// (penumbraExactBehind, all 128 samples). Each entry also times the exact kernel on the same planes,
// interleaved: speedup_vs_exact = exact time / this entry's time. Counters: err_bits = fraction of
// the valid bits that differ from the fp64 oracle on the kernels' own inputs (exactBehindOracle: the
// float plane, the float samples; must be 0 for Certified and ExactBehind),
// uncertain_bits = fraction of uncertain bits (certified LUT; 0 for the others),
// memory_bytes = the LUT (the float samples for ExactBehind), tests = M x tables, ns_per_test.
// llvmpipe runs the kernels on the CPU cores: the ratios, not the times, carry over to GPUs.
// Example: penumbra_bench --benchmark_filter='BM_Lut|BM_Exact'
#include "bench_common.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/light_lut.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/light_lut.hpp>

#include <benchmark/benchmark.h>

#include <bitset>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <vector>

namespace {

using penumbra::bench::timeGpu;

penumbra::LightLutSetup benchSetup(uint32_t resolution, uint32_t n, bool certified) {
    penumbra::LightLutOptions options;
    options.resolution = resolution;
    options.certified = certified;
    return penumbra::lightLutSetup(penumbra::reference::sphereLightSamples(glm::dvec3(0.0), 0.999, n, 20261201u), n,
                                   options);
}

int popcount(const penumbra::LutMask& m) {
    int c = 0;
    for (uint32_t w : m) c += static_cast<int>(std::bitset<32>(w).count());
    return c;
}

void lookupArgs(benchmark::internal::Benchmark* b) {
    if (penumbra::bench::smokeRun()) {
        b->Args({16, 128});
        return;
    }
    for (const auto& a : std::vector<std::vector<int64_t>>{{32, 128}, {64, 128}, {128, 128}, {64, 512}}) b->Args(a);
}

void lutGenerateCpu(benchmark::State& state, int64_t resolution, int64_t n) {
    const penumbra::LightLutSetup setup = benchSetup(uint32_t(resolution), uint32_t(n), true);
    std::vector<uint32_t> words(setup.texelCount() * 4);
    for (auto _ : state) {
        penumbra::generateLightLut(setup, words.data(), words.size());
        benchmark::DoNotOptimize(words.data());
        benchmark::ClobberMemory();
    }
    state.counters["memory_bytes"] = double(setup.tableBytes());
    state.counters["texels"] = double(setup.texelCount());
    state.counters["threads"] = double(std::max(1u, std::thread::hardware_concurrency()));
}

void lutGenerateGpu(benchmark::State& state, int64_t resolution, int64_t n) {
    penumbra::bench::glContext();
    const penumbra::LightLutSetup setup = benchSetup(uint32_t(resolution), uint32_t(n), true);
    penumbra::LightLutGenerator generator;
    penumbra::gl::Buffer table(setup.tableBytes());
    const penumbra::BufferRange range{table.id(), 0, setup.tableBytes()};
    generator.reserve(setup);
    generator.validate(setup, range);
    auto run = [&] {
        if (generator.generate(setup, range) != penumbra::Status::Ok) state.SkipWithError("generate refused its input");
    };
    timeGpu(run);  // warm-up (llvmpipe compiles at the first dispatch)
    for (auto _ : state) state.SetIterationTime(timeGpu(run));
    const std::vector<uint32_t> gpu = penumbra::readLightLut(setup, range);
    const std::vector<uint32_t> cpu = penumbra::generateLightLut(setup);
    size_t wrong = 0;
    for (size_t i = 0; i < cpu.size(); ++i) wrong += gpu[i] != cpu[i];
    state.counters["err_words"] = double(wrong);
    state.counters["memory_bytes"] = double(setup.tableBytes());
    state.counters["texels"] = double(setup.texelCount());
    state.counters["dispatches"] = double(generator.dispatches().size());
    state.counters["timer_gl_time_elapsed"] = penumbra::bench::timerCounter();
}

// The names: BM_LutGenerate/<res>/<N>/cpu and BM_LutGenerate/<res>/<N>/gpu.
const bool kLutGenerateRegistered = [] {
    std::vector<std::vector<int64_t>> sizes;
    if (penumbra::bench::smokeRun()) {
        sizes = {{16, 128}};
    } else {
        sizes = {{32, 128}, {64, 128}, {32, 512}, {64, 512}, {128, 128}};
    }
    for (const std::vector<int64_t>& size : sizes) {
        const std::string name = "BM_LutGenerate/" + std::to_string(size[0]) + "/" + std::to_string(size[1]);
        const int64_t r = size[0], n = size[1];
        benchmark::RegisterBenchmark((name + "/cpu").c_str(), [r, n](benchmark::State& state) { lutGenerateCpu(state, r, n); })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark((name + "/gpu").c_str(), [r, n](benchmark::State& state) { lutGenerateGpu(state, r, n); })
            ->UseManualTime()
            ->Unit(benchmark::kMillisecond);
    }
    return true;
}();

// ---- lookups on the device ----

/// A LUT generated on the GPU, the planes, the float samples and the host-side references of one
/// (R, N, certified) configuration; built once per configuration.
struct LookupWorld {
    penumbra::LightLutSetup setup;
    penumbra::gl::Buffer lut, params, samples, planes, rotations, results, exact_results;
    std::vector<glm::vec4> plane_values;
    std::vector<penumbra::LutMask> reference;  ///< exactBehindOracle per (plane, table)
    uint64_t valid_bits = 0, uncertain_bits = 0;
    uint64_t entries = 0;

    LookupWorld(uint32_t resolution, uint32_t n, bool certified, size_t plane_count)
        : setup(benchSetup(resolution, n, certified)) {
        penumbra::LightLutGenerator generator;
        lut = penumbra::gl::Buffer(setup.tableBytes());
        generator.reserve(setup);
        generator.generate(setup, {lut.id(), 0, setup.tableBytes()});
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        const std::vector<uint32_t> words = penumbra::readLightLut(setup, {lut.id(), 0, setup.tableBytes()});
        params = penumbra::gl::Buffer(sizeof setup.params, &setup.params);
        std::vector<glm::vec4> float_samples(setup.samples.size());
        for (size_t i = 0; i < float_samples.size(); ++i) float_samples[i] = glm::vec4(glm::vec3(setup.samples[i]), 0.0f);
        samples = penumbra::gl::Buffer::fromVector(float_samples);
        std::mt19937_64 rng(20261201u);
        std::normal_distribution<double> normal;
        std::uniform_real_distribution<double> uniform(-1.5, 1.5);
        plane_values.resize(plane_count);
        for (glm::vec4& p : plane_values) {
            glm::dvec3 nrm;
            do nrm = glm::dvec3(normal(rng), normal(rng), normal(rng)); while (glm::dot(nrm, nrm) < 1e-12);
            nrm = glm::normalize(nrm);
            const glm::dvec3 q(uniform(rng), uniform(rng), uniform(rng));
            p = glm::vec4(glm::dvec4(nrm, -glm::dot(nrm, q)));
        }
        planes = penumbra::gl::Buffer::fromVector(plane_values);
        rotations = penumbra::gl::Buffer(16);
        entries = uint64_t(plane_count) * setup.params.tables;
        results = penumbra::gl::Buffer(entries * 16);
        exact_results = penumbra::gl::Buffer(entries * 16);
        reference.resize(entries);
        for (size_t k = 0; k < plane_count; ++k)
            for (uint32_t t = 0; t < setup.params.tables; ++t) {
                // The samples buffer is setup.samples rounded to float, as exactBehindOracle rounds them.
                reference[k * setup.params.tables + t] = penumbra::exactBehindOracle(setup, t, plane_values[k]);
                valid_bits += uint64_t(popcount(penumbra::lightLutValidMask(setup.params, t)));
                if (certified) {
                    uncertain_bits += uint64_t(popcount(
                        penumbra::lightLutLookup(setup.params, words.data(), t, plane_values[k]).uncertain));
                }
            }
    }
};

LookupWorld& lookupWorld(uint32_t resolution, uint32_t n, bool certified) {
    static std::map<std::tuple<uint32_t, uint32_t, bool>, std::unique_ptr<LookupWorld>> worlds;
    auto& w = worlds[{resolution, n, certified}];
    if (!w) w = std::make_unique<LookupWorld>(resolution, n, certified, penumbra::bench::smokeRun() ? 4096 : 65536);
    return *w;
}

const penumbra::gl::Program& lookupKernel(int mode) {
    static std::map<int, penumbra::gl::Program> programs;
    auto it = programs.find(mode);
    if (it == programs.end()) {
        penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
        lib.addDirectory(penumbra::test::testShaderDir());
        it = programs.emplace(mode, penumbra::gl::buildComputeProgram("light_lut/lookup_test.comp.glsl",
                                                                      {{"PENUMBRA_LUT_TEST_MODE", std::to_string(mode)}}, lib))
                 .first;
    }
    return it->second;
}

void dispatchLookups(const LookupWorld& w, int mode, const penumbra::gl::Buffer& out) {
    const penumbra::gl::Program& program = lookupKernel(mode);
    program.use();
    glUniform1ui(0, static_cast<GLuint>(w.plane_values.size()));
    glUniform1ui(1, w.setup.params.tables);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, w.params.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, w.lut.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, w.samples.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, w.planes.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, w.rotations.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, out.id());
    const penumbra::detail::DispatchGrid grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(w.entries, 64));
    glDispatchCompute(grid.x, grid.y, 1);
}

// mode 1 seed lookup, 2 certified + resolve, 3 exact.
void runLookup(benchmark::State& state, int mode) {
    penumbra::bench::glContext();
    const bool certified = mode == 2;
    LookupWorld& w = lookupWorld(uint32_t(state.range(0)), uint32_t(state.range(1)), certified);
    auto run = [&] { dispatchLookups(w, mode, w.results); };
    auto exact = [&] { dispatchLookups(w, 3, w.exact_results); };
    timeGpu(run);  // warm-up
    timeGpu(exact);
    double self_s = 0, exact_s = 0;
    for (auto _ : state) {
        const double t = timeGpu(run);
        exact_s += timeGpu(exact);
        self_s += t;
        state.SetIterationTime(t);
    }
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const std::vector<glm::uvec4> got = w.results.download<glm::uvec4>();
    uint64_t wrong = 0;
    for (size_t e = 0; e < w.entries; ++e) {
        const penumbra::LutMask m{got[e].x, got[e].y, got[e].z, got[e].w};
        const penumbra::LutMask& r = w.reference[e];
        wrong += uint64_t(popcount({m[0] ^ r[0], m[1] ^ r[1], m[2] ^ r[2], m[3] ^ r[3]}));
    }
    state.counters["err_bits"] = double(wrong) / double(w.valid_bits);
    state.counters["uncertain_bits"] = double(w.uncertain_bits) / double(w.valid_bits);
    state.counters["memory_bytes"] =
        mode == 3 ? double(w.setup.samples.size() * sizeof(glm::vec4)) : double(w.setup.tableBytes());
    state.counters["tests"] = double(w.entries);
    const double runs = double(state.iterations());
    state.counters["ns_per_test"] = runs > 0 ? self_s / runs / double(w.entries) * 1e9 : 0.0;
    state.counters["speedup_vs_exact"] = self_s > 0 ? exact_s / self_s : 0.0;
    state.counters["timer_gl_time_elapsed"] = penumbra::bench::timerCounter();
}

void BM_LutLookup(benchmark::State& state) { runLookup(state, 1); }
void BM_LutLookupCertified(benchmark::State& state) { runLookup(state, 2); }
void BM_ExactBehind(benchmark::State& state) { runLookup(state, 3); }

BENCHMARK(BM_LutLookup)->Apply(lookupArgs)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LutLookupCertified)->Apply(lookupArgs)->UseManualTime()->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ExactBehind)->Apply(lookupArgs)->UseManualTime()->Unit(benchmark::kMicrosecond);

}  // namespace
