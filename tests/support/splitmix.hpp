// splitmix64 random numbers for tests: the same stream on every platform and standard library
// (unlike std:: distributions), so golden values and case lists are reproducible everywhere.
#ifndef PENUMBRA_TESTS_SUPPORT_SPLITMIX_HPP
#define PENUMBRA_TESTS_SUPPORT_SPLITMIX_HPP

#include <glm/vec3.hpp>

#include <cstdint>

namespace penumbra::test {

struct SplitMix64 {
    uint64_t state;
    explicit SplitMix64(uint64_t seed) : state(seed) {}
    uint64_t next() {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    /// [0, 1) from the top 53 bits.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
    uint32_t below(uint32_t n) { return static_cast<uint32_t>(next() % n); }
    glm::dvec3 point(double lo, double hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
};

}  // namespace penumbra::test

#endif
