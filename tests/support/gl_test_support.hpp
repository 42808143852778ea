// The one headless context a GL test executable uses (created on first use, on the backend
// PENUMBRA_GL names; see penumbra/gl/headless.hpp), and the two tiers of GL assertions.
//
// Tiers (docs/portable_tier.md lists every assertion of the second tier and why it is there):
//   portable  holds on any conformant driver: exact modes against the fp64 oracle, conservativeness,
//             structure invariants, integer results, GPU-vs-twin differences within a stated bound.
//   bitwise   holds only where the driver's float operations are correctly rounded and never fused
//             (GPU == CPU twin bit for bit). Mesa's llvmpipe and softpipe are such drivers; NVIDIA,
//             AMD and Intel hardware contract a*b+c into FMAs, approximate division, sqrt and
//             transcendental functions within GLSL's stated precision, and so are not.
// bitwiseTier(what) says whether the running driver is checked for the bitwise tier. Where it is
// not, the check is reported as skipped (a MESSAGE naming it and a summary line on stderr at exit:
// "penumbra-tier: N bitwise check(s) skipped on <renderer>"), never passed silently.
// PENUMBRA_TIER=portable skips the bitwise tier on any driver (the GPU bundle's run.sh uses it, so
// the portable tier alone is exercised on llvmpipe too); PENUMBRA_TIER=bitwise forces it anywhere.
#ifndef PENUMBRA_TESTS_SUPPORT_GL_TEST_SUPPORT_HPP
#define PENUMBRA_TESTS_SUPPORT_GL_TEST_SUPPORT_HPP

#include "penumbra/gl/headless.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>

namespace penumbra::test {

inline penumbra::gl::HeadlessContext& context() {
    static penumbra::gl::HeadlessContext ctx;
    return ctx;
}

/// Whether `renderer` (GL_RENDERER) is a driver whose float operations are correctly rounded and
/// unfused: Mesa's software rasterizers.
inline bool rendererRoundsCorrectly(const std::string& renderer) {
    return renderer.find("llvmpipe") != std::string::npos || renderer.find("softpipe") != std::string::npos;
}

namespace detail {

struct TierState {
    bool decided = false;
    bool bitwise = false;
    std::string reason;
    std::map<std::string, size_t> skipped;  // check name -> times skipped
    ~TierState() {
        if (skipped.empty()) return;
        size_t total = 0;
        for (const auto& entry : skipped) total += entry.second;
        std::fprintf(stderr, "penumbra-tier: %zu bitwise check(s) skipped (%zu distinct) on %s\n", total, skipped.size(),
                     reason.c_str());
        for (const auto& entry : skipped) std::fprintf(stderr, "penumbra-tier:   skipped %zux: %s\n", entry.second, entry.first.c_str());
    }
};

inline TierState& tierState() {
    static TierState state;
    if (!state.decided) {
        state.decided = true;
        const char* env = std::getenv("PENUMBRA_TIER");
        const std::string tier = env ? env : "";
        const std::string& renderer = context().renderer();
        if (tier == "portable") {
            state.bitwise = false;
            state.reason = "\"" + renderer + "\" (PENUMBRA_TIER=portable)";
        } else if (tier == "bitwise") {
            state.bitwise = true;
            state.reason = "\"" + renderer + "\" (PENUMBRA_TIER=bitwise)";
        } else {
            PENUMBRA_CHECK(tier.empty(), "penumbra tests: PENUMBRA_TIER=", tier, " (expected portable or bitwise)");
            state.bitwise = rendererRoundsCorrectly(renderer);
            state.reason = "\"" + renderer + "\" (not a correctly rounded software driver)";
        }
    }
    return state;
}

}  // namespace detail

/// True when this run checks the bitwise tier; otherwise reports `what` as skipped and returns false.
inline bool bitwiseTier(const char* what) {
    detail::TierState& state = detail::tierState();
    if (state.bitwise) return true;
    if (state.skipped[what]++ == 0) MESSAGE("skipped (bitwise tier, ", state.reason, "): ", std::string(what));
    return false;
}

/// Whether the bitwise tier runs, without recording a skip (for choosing what to compute).
inline bool bitwiseTierEnabled() { return detail::tierState().bitwise; }

}  // namespace penumbra::test

/// CHECK(...) in the bitwise tier (see above); `what` names the check in the skip report.
#define PENUMBRA_CHECK_BITWISE(what, ...)                      \
    do {                                                       \
        if (::penumbra::test::bitwiseTier(what)) CHECK(__VA_ARGS__); \
    } while (0)

#endif
