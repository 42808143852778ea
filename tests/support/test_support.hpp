// Helpers every penumbra test shares (one copy; tests include this instead of redefining them).
//
//   testSeed():  the seed random tests draw from. Fixed by default (kDefaultTestSeed) so a run is
//                repeatable; PENUMBRA_SEED=<n> picks n, PENUMBRA_SEED=random draws a fresh one.
//                Every call prints the seed it returns, so a failure can be replayed.
//   errorOf(f):  the message of the penumbra::Error f throws, or a marker when it throws none.
//   contains():  substring test for error messages.
#ifndef PENUMBRA_TESTS_SUPPORT_TEST_SUPPORT_HPP
#define PENUMBRA_TESTS_SUPPORT_TEST_SUPPORT_HPP

#include "penumbra/error.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>

namespace penumbra::test {

inline constexpr uint32_t kDefaultTestSeed = 20261201u;

/// `offset` separates the streams of several random cases in one test case.
inline uint32_t testSeed(uint32_t offset = 0) {
    uint32_t seed = kDefaultTestSeed;
    const char* env = std::getenv("PENUMBRA_SEED");
    if (env && *env) {
        seed = std::strcmp(env, "random") == 0 ? std::random_device{}()
                                                : static_cast<uint32_t>(std::strtoul(env, nullptr, 10));
    }
    seed += offset;
    MESSAGE("seed " << seed << " (replay: PENUMBRA_SEED=" << seed - offset << ")");
    return seed;
}

template <typename F>
std::string errorOf(F&& f) {
    try {
        f();
    } catch (const penumbra::Error& e) {
        return e.what();
    }
    return "(no penumbra::Error thrown)";
}

inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace penumbra::test

#endif
