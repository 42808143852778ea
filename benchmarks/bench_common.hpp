// Shared helpers for penumbra_bench: one GL context for every GL benchmark (created on first use,
// backend from PENUMBRA_GL), and the smoke flag ctest sets (PENUMBRA_BENCH_SMOKE=1) so each
// benchmark can shrink its sizes to run once in seconds.
#ifndef PENUMBRA_BENCHMARKS_BENCH_COMMON_HPP
#define PENUMBRA_BENCHMARKS_BENCH_COMMON_HPP

#include <penumbra/gl/headless.hpp>

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

}  // namespace penumbra::bench

#endif
