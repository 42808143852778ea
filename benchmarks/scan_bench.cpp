// Scan throughput against the compute copy of the same bytes (shaders/penumbra/common/copy.comp.glsl),
// measured in the same benchmark entry, and the CPU twin.
//
// BM_Scan / BM_ScanPortable: every iteration times one scan and one compute copy of the same n
// uints (glFinish + wall clock, penumbra::bench::timeGpu; llvmpipe has no usable GL_TIME_ELAPSED),
// interleaved so both see the same machine state; the iteration time reported is the scan's.
// Counters:
//   scan_copy_ratio      bandwidth of the scan / bandwidth of the copy = median copy time / median
//                        scan time (both move n * 4 bytes in and n * 4 out at least): the
//                        device-independent figure. Reduce-then-scan reads the input twice, so
//                        its ceiling is about 2/3.
//   scan_ms, copy_ms     the two medians.
//   err_mismatches       scan output elements that differ from scanCpu; err_copy_mismatches the
//                        copy's against its source (both read back after the timed loop).
//   dispatches           compute dispatches per scan; bytes_moved: bytes the plan's dispatches
//                        read and write (tile sums included); elements = n.
// bytes_per_second counts n * 8 bytes per scan. The label names the top pass's workgroup-scan mode;
// BM_ScanPortable forces the shared-memory one.
// Example: penumbra_bench --benchmark_filter='BM_Scan/16777216' --benchmark_repetitions=3
#include "bench_common.hpp"

#include <penumbra/detail/dispatch.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/scan.hpp>
#include <penumbra/gl/shader.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
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

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    const size_t h = v.size() / 2;
    return v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
}

void setRates(benchmark::State& state, uint64_t n) {
    state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * n * 8));  // -> bytes_per_second
    state.counters["elements"] = static_cast<double>(n);
}

size_t mismatches(const std::vector<uint32_t>& got, const std::vector<uint32_t>& want) {
    size_t wrong = got.size() == want.size() ? 0 : want.size();
    for (size_t i = 0; i < std::min(got.size(), want.size()); ++i) wrong += got[i] != want[i];
    return wrong;
}

// Bytes the plan's dispatches read and write: reduce reads its level and writes one sum per tile;
// the top pass reads and writes its level; the scan pass reads its level and the tile offsets and
// writes its level.
double planBytes(const penumbra::ScanPlan& plan) {
    double bytes = 0;
    for (size_t i = 0; i < plan.dispatch_list.size(); ++i) {
        const double count = plan.constants[i].count;
        const double tiles = static_cast<double>(penumbra::detail::divUp(plan.constants[i].count, plan.items_per_thread));
        switch (plan.dispatch_list[i].pass) {
            case penumbra::ScanPass::Reduce: bytes += 4 * count + 4 * tiles; break;
            case penumbra::ScanPass::Top: bytes += 8 * count; break;
            case penumbra::ScanPass::Scan: bytes += 8 * count + 4 * tiles; break;
        }
    }
    return bytes;
}

// The baseline: a uvec4 compute copy of n uints (n a multiple of 4), same dispatch folding.
class ComputeCopy {
public:
    ComputeCopy() : program_(penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl")) {}
    void run(GLuint source, GLuint destination, uint64_t n) const {
        const uint64_t quads = n / 4;
        const penumbra::detail::DispatchGrid grid = penumbra::detail::foldDispatch(penumbra::detail::divUp(quads, 256));
        program_.use();
        glUniform1ui(0, static_cast<GLuint>(quads));
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, source);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, destination);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
        glDispatchCompute(grid.x, grid.y, 1);
    }

private:
    penumbra::gl::Program program_;
};

void runScan(benchmark::State& state, penumbra::Scanner& scanner) {
    static const ComputeCopy copy;
    const uint64_t n = static_cast<uint64_t>(state.range(0));  // a multiple of 4 (uvec4 copy)
    const std::vector<uint32_t> values = benchValues(n);
    penumbra::gl::Buffer input = penumbra::gl::Buffer::fromVector(values);
    penumbra::gl::Buffer output(n * 4), copied(n * 4);
    const penumbra::BufferRange in{input.id(), 0, n * 4}, out{output.id(), 0, n * 4};
    // Load time: size and check everything once.
    scanner.reserve(n);
    scanner.validate(in, out, n);
    auto scan = [&] {
        if (scanner.exclusive(in, out, n) != penumbra::Status::Ok) state.SkipWithError("scan refused its input");
    };
    auto run_copy = [&] { copy.run(input.id(), copied.id(), n); };
    scan();  // warm-up
    run_copy();
    std::vector<double> scan_times, copy_times;
    for (auto _ : state) {
        const double t_scan = timeGpu(scan);
        copy_times.push_back(timeGpu(run_copy));  // not part of the reported iteration time
        scan_times.push_back(t_scan);
        state.SetIterationTime(t_scan);
    }
    setRates(state, n);
    // Read-backs and host checks outside the timed region.
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<uint32_t> want(n);
    penumbra::scanCpu(values.data(), want.data(), n, penumbra::ScanKind::Exclusive);
    penumbra::bench::reportTimer(state);  // which clock timed this entry
    state.counters["err_mismatches"] = static_cast<double>(mismatches(output.download<uint32_t>(), want));
    state.counters["err_copy_mismatches"] = static_cast<double>(mismatches(copied.download<uint32_t>(), values));
    const double scan_s = median(scan_times), copy_s = median(copy_times);
    state.counters["scan_ms"] = scan_s * 1e3;
    state.counters["copy_ms"] = copy_s * 1e3;
    state.counters["scan_copy_ratio"] = scan_s > 0 ? copy_s / scan_s : 0;
    const penumbra::ScanPlan plan = scanner.plan(n);
    state.counters["dispatches"] = static_cast<double>(plan.dispatches);
    state.counters["bytes_moved"] = planBytes(plan);
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
BENCHMARK(BM_CpuScan)->Apply(scanSizes)->Unit(benchmark::kMillisecond);

}  // namespace
