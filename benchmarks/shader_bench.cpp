// Shader system costs an engine pays at load time: assembling a key from the embedded table, and
// compiling + linking it on the driver.
#include "bench_common.hpp"

#include <penumbra/gl/shader.hpp>

#include <benchmark/benchmark.h>

namespace {

void BM_AssembleShader(benchmark::State& state) {
    size_t bytes = 0;
    for (auto _ : state) {
        auto assembly = penumbra::assembleShader("penumbra/common/copy.comp.glsl", {{"PENUMBRA_COPY_GROUP_SIZE", "128"}});
        bytes += assembly.text.size();
        benchmark::DoNotOptimize(assembly.text.data());
    }
    state.counters["bytes_per_second"] = benchmark::Counter(static_cast<double>(bytes), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AssembleShader);

void BM_CompileComputeProgram(benchmark::State& state) {
    penumbra::bench::glContext();
    for (auto _ : state) {
        auto program = penumbra::gl::buildComputeProgram("penumbra/common/copy.comp.glsl");
        glFinish();
        benchmark::DoNotOptimize(program.id());
    }
}
BENCHMARK(BM_CompileComputeProgram)->Unit(benchmark::kMillisecond);

}  // namespace
