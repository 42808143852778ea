// Shared helpers for penumbra_bench: one GL context for every GL benchmark (created on first use,
// backend from PENUMBRA_GL), the smoke flag ctest sets (PENUMBRA_BENCH_SMOKE=1) so each
// benchmark can shrink its sizes to run once in seconds, the one GPU timing method, and the
// interleaved timing of several methods inside one entry.
#ifndef PENUMBRA_BENCHMARKS_BENCH_COMMON_HPP
#define PENUMBRA_BENCHMARKS_BENCH_COMMON_HPP

#include <penumbra/gl/headless.hpp>

#include "../tests/support/source_paths.hpp"  // testShaderDir(), sharedScenesDir(): env-overridable (tools/gpu_bundle.sh)

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

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

namespace detail {
inline bool& timeElapsedMeasures() {
    static bool measures = false;
    return measures;
}
struct TimerUse {
    uint64_t query = 0, wall = 0;  ///< timeGpu calls timed by GL_TIME_ELAPSED / by glFinish + wall clock
};
inline TimerUse& timerUse() {
    static TimerUse use;
    return use;
}
struct LastTiming {
    double wall = 0.0, query = 0.0;  ///< seconds
};
inline LastTiming& lastTiming() {
    static LastTiming last;
    return last;
}
}  // namespace detail

/// Whether the benchmarks' context runs on the CPU (HeadlessContext::cpuRenderer(): llvmpipe).
inline bool cpuRenderer() {
    static const bool cpu = glContext().cpuRenderer();
    return cpu;
}

/// GPU seconds of `f`, the one timing method of every GL benchmark: a GL_TIME_ELAPSED query
/// around it where the driver really measures the region (a GPU renderer, and the query reports
/// between 5% and 100% of the wall time between the glFinish()es around it: GPU time lies inside
/// that window), else that wall time. CPU renderers (cpuRenderer(): llvmpipe) always use the wall
/// time: it is their execution time, and their queries miss work (HeadlessContext::cpuRenderer()).
/// timerCounter() says which method the last call used.
template <typename F>
double timeGpu(F&& f) {
    static const GLuint query = [] {
        GLuint q = 0;
        glCreateQueries(GL_TIME_ELAPSED, 1, &q);
        return q;
    }();
    const bool use_query = !cpuRenderer();
    glFinish();
    const auto start = std::chrono::steady_clock::now();
    if (use_query) glBeginQuery(GL_TIME_ELAPSED, query);
    f();
    if (use_query) glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    GLuint64 ns = 0;
    if (use_query) glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
    const double measured = double(ns) * 1e-9;
    detail::timeElapsedMeasures() = use_query && measured >= 0.05 * wall && measured <= 1.02 * wall;
    detail::lastTiming() = {wall, measured};
    ++(detail::timeElapsedMeasures() ? detail::timerUse().query : detail::timerUse().wall);
    return detail::timeElapsedMeasures() ? measured : wall;
}

/// Counter value for "timer_gl_time_elapsed": 1 when timeGpu used the GL query, 0 for glFinish + wall clock.
inline double timerCounter() { return detail::timeElapsedMeasures() ? 1.0 : 0.0; }

/// Whether the last timeGpu call found GL_TIME_ELAPSED measuring durations.
inline bool timeElapsedMeasuresNow() { return detail::timeElapsedMeasures(); }

/// Sets the entry's "timer_gl_time_elapsed" counter to the share of its timeGpu calls (since the
/// last report) that the GL_TIME_ELAPSED query timed: 1 every call, 0 none (glFinish + wall clock,
/// e.g. llvmpipe), in between a mix that the entry's times should not be compared across.
inline void reportTimer(benchmark::State& state) {
    detail::TimerUse& use = detail::timerUse();
    const uint64_t calls = use.query + use.wall;
    state.counters["timer_gl_time_elapsed"] = calls ? double(use.query) / double(calls) : 0.0;
    use = {};
}

/// Both readings of the last timeGpu call (seconds): the glFinish-to-glFinish wall time and what
/// the GL_TIME_ELAPSED query answered (whether or not timeGpu used it). For entries that must time
/// several methods the same way: when one call's query does not measure, use lastWallSeconds()
/// for every method of the entry.
inline double lastWallSeconds() { return detail::lastTiming().wall; }
inline double lastQuerySeconds() { return detail::lastTiming().query; }

inline double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// One timed method of an entry.
struct TimedMethod {
    std::string name;  ///< counter suffix
    std::function<void()> run;
    std::vector<double> wall{}, query{};  ///< per iteration: both readings of timeGpu
    double ms(bool use_query) const { return 1e3 * median(use_query ? query : wall); }
};

/// One warm-up call of every method, then per benchmark iteration one timed call of every method,
/// interleaved (the first rotates with the iteration, so none always runs after the others). The
/// entry's manual time is methods[0]'s. Sets timer_gl_time_elapsed and returns whether the
/// GL_TIME_ELAPSED query measured every call (then every method's ms() should use it, else every
/// method's wall clock: one timing method for the whole entry).
inline bool timeInterleaved(benchmark::State& state, std::vector<TimedMethod>& methods) {
    for (TimedMethod& m : methods) timeGpu(m.run);
    bool query_measures = true;
    size_t iteration = 0;
    for (auto _ : state) {
        double first = 0.0;
        for (size_t k = 0; k < methods.size(); ++k) {
            const size_t which = (k + iteration) % methods.size();
            const double seconds = timeGpu(methods[which].run);
            methods[which].wall.push_back(lastWallSeconds());
            methods[which].query.push_back(lastQuerySeconds());
            query_measures &= timerCounter() > 0.5;
            if (which == 0) first = seconds;
        }
        state.SetIterationTime(first);
        ++iteration;
    }
    state.counters["timer_gl_time_elapsed"] = query_measures ? 1.0 : 0.0;
    detail::timerUse() = {};
    return query_measures;
}

}  // namespace penumbra::bench

#endif
