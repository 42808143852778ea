// Helpers every penumbra test shares (one copy; tests include this instead of redefining them).
//
//   testSeed():  the seed random tests draw from. Fixed by default (kDefaultTestSeed) so a run is
//                repeatable; PENUMBRA_SEED=<n> picks n, PENUMBRA_SEED=random draws a fresh one.
//                Every call prints the seed it returns, so a failure can be replayed.
//   errorOf(f):  the message of the penumbra::Error f throws, or a marker when it throws none.
//   contains():  substring test for error messages.
//   envCount():  a case count from an environment variable (stress runs set it), else the default.
//   kSanitized:  true in the ASan/UBSan build (tools/test.sh's second tree), where a run is ~4-10x
//                slower and what is checked is the host code: sweeps over data may run fewer cases
//                there (saying so), never fewer code paths; the Release run keeps every case.
#ifndef PENUMBRA_TESTS_SUPPORT_TEST_SUPPORT_HPP
#define PENUMBRA_TESTS_SUPPORT_TEST_SUPPORT_HPP

#include "penumbra/error.hpp"
#include "support/source_paths.hpp"

#include <doctest/doctest.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace penumbra::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

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

inline long envCount(const char* name, long fallback) {
    const char* env = std::getenv(name);
    return env && *env ? std::strtol(env, nullptr, 10) : fallback;
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

/// "" when equal, else the first differing word (index and values) and how many differ from there
/// on; `per_item` > 1 also names the item (e.g. 4 words per uvec4 texel).
inline std::string firstMismatch(const std::vector<uint32_t>& got, const std::vector<uint32_t>& want,
                                 size_t per_item = 1, const char* item = "element") {
    if (got.size() != want.size()) return "size " + std::to_string(got.size()) + " != " + std::to_string(want.size());
    for (size_t i = 0; i < got.size(); ++i) {
        if (got[i] == want[i]) continue;
        size_t wrong = 0;
        for (size_t j = i; j < got.size(); ++j) wrong += got[j] != want[j];
        std::string where = "word " + std::to_string(i);
        if (per_item > 1) where += " (" + std::string(item) + " " + std::to_string(i / per_item) + ")";
        return where + ": got " + std::to_string(got[i]) + ", want " + std::to_string(want[i]) + " (" +
               std::to_string(wrong) + " wrong)";
    }
    return "";
}

}  // namespace penumbra::test

#endif
