// Shared helpers for penumbra_bench: one GL context for every GL benchmark (created on first use,
// backend from PENUMBRA_GL), and the smoke flag ctest sets (PENUMBRA_BENCH_SMOKE=1) so each
// benchmark can shrink its sizes to run once in seconds.
#ifndef PENUMBRA_BENCHMARKS_BENCH_COMMON_HPP
#define PENUMBRA_BENCHMARKS_BENCH_COMMON_HPP

#include <penumbra/gl/headless.hpp>

#include <chrono>
#include <cstdlib>
#include <cstring>

namespace penumbra::bench {

inline gl::HeadlessContext& glContext() {
    static gl::HeadlessContext context;
    return context;
}

/// True under ctest's smoke run: benchmarks should use their smallest sizes.
inline bool smokeRun() {
    const char* env = std::getenv("PENUMBRA_BENCH_SMOKE");
    return env && std::strcmp(env, "1") == 0;
}

/// Seconds between a glFinish before and after `f`: wall-clock GPU time. llvmpipe answers
/// GL_TIME_ELAPSED queries with 1 ns, so benchmarks that must run there time this way.
template <typename F>
double timeGpu(F&& f) {
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    f();
    glFinish();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace penumbra::bench

#endif
