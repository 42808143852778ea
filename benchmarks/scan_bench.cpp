// Scan throughput against the compute copy of the same bytes (shaders/penumbra/common/copy.comp.glsl),
// in the same context, and the CPU twin.
//
// bytes_per_second counts n * 4 bytes read + n * 4 bytes written for BM_Scan and BM_ComputeCopy
// alike (what a scan must move at least; reduce-then-scan really reads the input twice, so its
// ceiling is 2/3 of the copy's rate), so BM_Scan / BM_ComputeCopy is the device-independent ratio.
// GPU time: glFinish before and after the region, wall clock, manual time, after one warm-up run.
// Counters: err_mismatches = output elements that differ from the CPU twin (copy: from the
// source) after the timed runs; dispatches = compute dispatches per scan; elements = n. The label
// names the top pass's workgroup-scan mode; BM_ScanPortable forces the shared-memory one.
// Example: penumbra_bench --benchmark_filter='BM_(Scan|ComputeCopy)/16777216' --benchmark_repetitions=5
//          --benchmark_report_aggregates_only=true
#include "bench_common.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/scan.hpp>

#include <benchmark/benchmark.h>

#include <chrono>
#include <random>
#include <vector>

namespace {

std::vector<uint32_t> benchValues(size_t n) {
    std::mt19937 rng(12345);
    std::vector<uint32_t> v(n);
    for (auto& x : v) x = rng();
    return v;
}

using penumbra::bench::timeGpu;

void setRates(benchmark::State& state, uint64_t n) {
    state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * n * 8));  // -> bytes_per_second
    state.counters["elements"] = static_cast<double>(n);
}

void runScan(benchmark::State& state, penumbra::Scanner& scanner) {
    const uint64_t n = static_cast<uint64_t>(state.range(0));
    const std::vector<uint32_t> values = benchValues(n);
    penumbra::gl::Buffer input = penumbra::gl::Buffer::fromVector(values);
    penumbra::gl::Buffer output(n * 4);
    scanner.reserve(n);
    scanner.exclusive(input.id(), 0, output.id(), 0, n);  // warm-up
    for (auto _ : state) {
        state.SetIterationTime(timeGpu([&] { scanner.exclusive(input.id(), 0, output.id(), 0, n); }));
    }
    setRates(state, n);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<uint32_t> want(n);
    penumbra::scanCpu(values.data(), want.data(), n, penumbra::ScanKind::Exclusive);
    const std::vector<uint32_t> got = output.download<uint32_t>();
    size_t mismatches = 0;
    for (size_t i = 0; i < n; ++i) mismatches += got[i] != want[i];
    state.counters["err_mismatches"] = static_cast<double>(mismatches);
    state.counters["dispatches"] = static_cast<double>(scanner.plan(n).dispatches);
    state.SetLabel(penumbra::scanSubgroupsName(scanner.subgroupMode()));
}

// The default scanner (the top pass on subgroup operations where the driver has them).
void BM_Scan(benchmark::State& state) {
    penumbra::bench::glContext();
    static penumbra::Scanner scanner;
    runScan(state, scanner);
}

// ScanOptions::allow_subgroups = false: the shared-memory workgroup scan everywhere.
void BM_ScanPortable(benchmark::State& state) {
    penumbra::bench::glContext();
    static penumbra::Scanner scanner([] {
        penumbra::ScanOptions options;
        options.allow_subgroups = false;
        return options;
    }());
    runScan(state, scanner);
}

void BM_ComputeCopy(benchmark::State& state) {
    penumbra::bench::glContext();
    static penumbra::gl::Program copy = penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl");
    const uint64_t n = static_cast<uint64_t>(state.range(0));  // uints; a multiple of 4 (uvec4 copy)
    const std::vector<uint32_t> values = benchValues(n);
    penumbra::gl::Buffer source = penumbra::gl::Buffer::fromVector(values);
    penumbra::gl::Buffer destination(n * 4);
    const uint64_t quads = n / 4;
    const penumbra::detail::DispatchGrid grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(quads, 256));
    auto run = [&] {
        copy.use();
        glUniform1ui(copy.uniform("penumbraCopyCount"), static_cast<GLuint>(quads));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, source.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, destination.id());
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glDispatchCompute(grid.x, grid.y, 1);
    };
    run();  // warm-up
    for (auto _ : state) state.SetIterationTime(timeGpu(run));
    setRates(state, n);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const std::vector<uint32_t> got = destination.download<uint32_t>();
    size_t mismatches = 0;
    for (size_t i = 0; i < n; ++i) mismatches += got[i] != values[i];
    state.counters["err_mismatches"] = static_cast<double>(mismatches);
    state.counters["dispatches"] = 1;
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, 0);
    glUseProgram(0);
}

void BM_CpuScan(benchmark::State& state) {
    const size_t n = static_cast<size_t>(state.range(0));
    const std::vector<uint32_t> values = benchValues(n);
    std::vector<uint32_t> output(n);
    for (auto _ : state) {
        penumbra::scanCpu(values.data(), output.data(), n, penumbra::ScanKind::Exclusive);
        benchmark::DoNotOptimize(output.data());
        benchmark::ClobberMemory();
    }
    setRates(state, n);
}

void scanSizes(benchmark::internal::Benchmark* b) {
    if (penumbra::bench::smokeRun()) {
        b->Arg(1 << 10);
        return;
    }
    for (int64_t n : {int64_t(1) << 16, int64_t(1) << 20, int64_t(1) << 24}) b->Arg(n);
}

BENCHMARK(BM_Scan)->Apply(scanSizes)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScanPortable)->Apply(scanSizes)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ComputeCopy)->Apply(scanSizes)->UseManualTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CpuScan)->Apply(scanSizes)->Unit(benchmark::kMillisecond);

}  // namespace
