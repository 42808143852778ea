// light_lut.hpp on the CPU: setup validation, the generator against the texel function, the
// certified mode's zero wrong certain bits on random planes (double and float lookups), the seed
// mode's error, symmetry, trivial and bad planes, the combine rule, progress and cancellation.
// The GPU generator and GLSL lookups are compared with these in light_lut_gl_test.cpp.
#include "penumbra/light_lut.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <random>

using glm::dvec3;
using glm::dvec4;
using penumbra::test::contains;
using penumbra::test::errorOf;

namespace {

/// N samples per set, `sets` sets: the oracle's ball samples at radius 0.999 (inside |q| < 1 - 2^-20).
std::vector<dvec3> ballSets(uint32_t n, uint32_t sets) {
    std::vector<dvec3> all;
    for (uint32_t s = 0; s < sets; ++s) {
        const std::vector<dvec3> one = penumbra::reference::sphereLightSamples(dvec3(0.0), 0.999, n, 100 + s);
        all.insert(all.end(), one.begin(), one.end());
    }
    return all;
}

std::vector<dvec3> diskSet(uint32_t n) {
    return penumbra::reference::diskLightSamples(dvec3(0.0), dvec3(0, 0, 1), 0.999, n, 3);
}

int popcount(const penumbra::LutMask& m) {
    int c = 0;
    for (uint32_t w : m) c += static_cast<int>(std::bitset<32>(w).count());
    return c;
}

penumbra::LutMask andNot(const penumbra::LutMask& a, const penumbra::LutMask& b) {
    return {a[0] & ~b[0], a[1] & ~b[1], a[2] & ~b[2], a[3] & ~b[3]};
}

penumbra::LutMask xorMask(const penumbra::LutMask& a, const penumbra::LutMask& b) {
    return {a[0] ^ b[0], a[1] ^ b[1], a[2] ^ b[2], a[3] ^ b[3]};
}

/// A random plane through a random point within 1.5 of the centre, as (unit n, d).
dvec4 randomPlane(std::mt19937_64& rng) {
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> uniform(-1.5, 1.5);
    dvec3 n;
    do n = dvec3(normal(rng), normal(rng), normal(rng)); while (glm::dot(n, n) < 1e-12);
    n = glm::normalize(n);
    const dvec3 p(uniform(rng), uniform(rng), uniform(rng));
    return dvec4(n, -glm::dot(n, p));
}

struct Tally {
    uint64_t bits = 0, wrong_seed = 0, wrong_certain = 0, uncertain = 0;
};

/// Looks `planes` random planes up in every table and counts against exactBehind (double).
template <typename Real>
Tally tally(const penumbra::LightLutSetup& setup, const std::vector<uint32_t>& lut, uint64_t planes, uint32_t seed) {
    std::mt19937_64 rng(seed);
    Tally t;
    for (uint64_t k = 0; k < planes; ++k) {
        const dvec4 plane = randomPlane(rng);
        const glm::vec<4, Real> looked(plane);
        for (uint32_t table = 0; table < setup.params.tables; ++table) {
            const penumbra::LutMask exact = penumbra::exactBehind(setup, table, plane);
            const penumbra::LutAnswer answer = penumbra::lightLutLookup(setup.params, lut.data(), table, looked);
            const penumbra::LutCertain certain = penumbra::lutCertain(answer);
            t.bits += static_cast<uint64_t>(popcount(penumbra::lightLutValidMask(setup.params, table)));
            t.wrong_seed += static_cast<uint64_t>(popcount(xorMask(answer.centre, exact)));
            t.wrong_certain += static_cast<uint64_t>(popcount(andNot(xorMask(certain.behind, exact), certain.uncertain)));
            t.uncertain += static_cast<uint64_t>(popcount(answer.uncertain));
            // Resolving the uncertain bits gives the exact mask.
            if (setup.options.certified) REQUIRE(penumbra::lutResolve(setup, table, certain, plane) == exact);
        }
    }
    return t;
}

}  // namespace

TEST_CASE("light lut: setup sizes and parameters") {
    const std::vector<dvec3> samples = ballSets(160, 2);
    penumbra::LightLutOptions options;
    options.resolution = 32;
    options.certified = true;
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, 160, options);
    CHECK(setup.params.tables_per_set == 2);
    CHECK(setup.params.tables == 4);
    CHECK(setup.params.texels_per_table == 32u * 32u * 32u);
    CHECK(setup.params.uncertain_offset == 4u * 32u * 32u * 32u);
    CHECK(setup.tableBytes() == 2ull * 4 * 32 * 32 * 32 * 16);
    CHECK(setup.samples.size() == 4u * 128u);
    // Set 1's sample 130 is table 3's bit 2; padding past N is zero.
    CHECK(glm::dvec3(setup.samples[3 * 128 + 2]) == samples[160 + 130]);
    CHECK(setup.samples[1 * 128 + 40] == dvec4(0.0));
    CHECK(penumbra::lightLutValidMask(setup.params, 1) == penumbra::LutMask{0xFFFFFFFFu, 0, 0, 0});
    CHECK(penumbra::lightLutValidMask(setup.params, 2) == penumbra::LutMask{~0u, ~0u, ~0u, ~0u});
    // Octahedral cells: rho is a chord bound at least the largest corner chord.
    for (const dvec4& cell : setup.normal_cells) {
        CHECK(glm::length(dvec3(cell)) == doctest::Approx(1.0).epsilon(1e-15));
        CHECK(cell.w > 0.0);
        CHECK(cell.w < 0.2);
    }
}

TEST_CASE("light lut: bad input is a clear error") {
    const std::vector<dvec3> samples = ballSets(128, 1);
    penumbra::LightLutOptions options;
    options.resolution = 16;
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples.data(), 100, 1, options); }), "multiple of 32"));
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples.data(), 1056, 1, options); }), "(got 1056)"));
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples.data(), 0, 1, options); }), "(got 0)"));
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples.data(), 128, 0, options); }), "sets"));
    for (uint32_t r : {8u, 15u, 17u, 258u, 512u}) {
        options.resolution = r;
        CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples, 128, options); }), "resolution"));
    }
    options.resolution = 16;
    options.tolerance = -1.0;
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples, 128, options); }), "tolerance"));
    options.tolerance = std::nan("");
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples, 128, options); }), "tolerance"));
    options.tolerance = 1.5e-2;  // above the documented 1e-2
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples, 128, options); }), "1e-2"));
    options.tolerance = 1e-6;
    std::vector<dvec3> bad = samples;
    bad[7] = dvec3(0.0, std::nan(""), 0.0);
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(bad, 128, options); }), "sample 7 of set 0 is not finite"));
    bad[7] = dvec3(1.0, 0.0, 0.0);  // on the bounding sphere: outside the margin
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(bad, 128, options); }), "|q| = 1"));
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(samples, 96, options); }), "whole sets"));
    // 256^3 x 2 x 2 tables x 8 sets certified: beyond 2^32 texels.
    const std::vector<dvec3> big = ballSets(256, 1);
    std::vector<dvec3> many;
    for (int s = 0; s < 70; ++s) many.insert(many.end(), big.begin(), big.end());
    options.resolution = 256;
    options.certified = true;
    CHECK(contains(errorOf([&] { penumbra::lightLutSetup(many, 256, options); }), "exceed 2^32"));
}

TEST_CASE("light lut: the generator writes the texel function, on any thread count") {
    for (const auto mapping : {penumbra::LutNormalMapping::Octahedral, penumbra::LutNormalMapping::Spherical}) {
        for (const bool symmetric : {true, false}) {
            penumbra::LightLutOptions options;
            options.resolution = 16;
            options.mapping = mapping;
            options.symmetric = symmetric;
            options.certified = true;
            const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(160, 1), 160, options);
            const std::vector<uint32_t> one = penumbra::generateLightLut(setup, penumbra::LutProgress{}, 1);
            const std::vector<uint32_t> three = penumbra::generateLightLut(setup, penumbra::LutProgress{}, 3);
            CHECK(one == three);
            for (uint32_t table = 0; table < setup.params.tables; ++table)
                for (uint32_t texel = 0; texel < setup.params.texels_per_table; texel += 7) {
                    const penumbra::LutAnswer a = penumbra::lightLutTexel(setup, table, texel);
                    const uint64_t c = (uint64_t(table) * setup.params.texels_per_table + texel) * 4;
                    const uint64_t u = c + uint64_t(setup.params.uncertain_offset) * 4;
                    REQUIRE(penumbra::LutMask{one[c], one[c + 1], one[c + 2], one[c + 3]} == a.centre);
                    REQUIRE(penumbra::LutMask{one[u], one[u + 1], one[u + 2], one[u + 3]} == a.uncertain);
                    // Certain bits are consistent with the centre: certain behind => centre behind.
                    REQUIRE(andNot(a.uncertain, penumbra::lightLutValidMask(setup.params, table)) == penumbra::LutMask{});
                }
            // The seed-mode table is the certified one's first half.
            options.certified = false;
            const penumbra::LightLutSetup seed = penumbra::lightLutSetup(ballSets(160, 1), 160, options);
            const std::vector<uint32_t> seed_words = penumbra::generateLightLut(seed);
            CHECK(std::equal(seed_words.begin(), seed_words.end(), one.begin()));
        }
    }
}

namespace {

void certifiedNeverWrong(uint64_t planes) {
    const uint32_t seed = penumbra::test::testSeed();
    struct Case {
        const char* name;
        std::vector<dvec3> samples;
        uint32_t n;
        penumbra::LutNormalMapping mapping;
        bool symmetric;
        uint32_t resolution;
    };
    const std::vector<Case> cases = {
        {"ball 128 oct sym 32", ballSets(128, 1), 128, penumbra::LutNormalMapping::Octahedral, true, 32},
        {"ball 256 oct asym 16", ballSets(256, 1), 256, penumbra::LutNormalMapping::Octahedral, false, 16},
        {"disk 128 oct sym 64", diskSet(128), 128, penumbra::LutNormalMapping::Octahedral, true, 64},
        {"ball 128 two angles sym 32", ballSets(128, 1), 128, penumbra::LutNormalMapping::Spherical, true, 32},
    };
    for (const Case& c : cases) {
        INFO(c.name);
        penumbra::LightLutOptions options;
        options.resolution = c.resolution;
        options.mapping = c.mapping;
        options.symmetric = c.symmetric;
        options.certified = true;
        const penumbra::LightLutSetup setup = penumbra::lightLutSetup(c.samples, c.n, options);
        const std::vector<uint32_t> lut = penumbra::generateLightLut(setup);
        const Tally d = tally<double>(setup, lut, planes, seed);
        MESSAGE(c.name << ": " << d.bits << " bits, seed-mode wrong " << double(d.wrong_seed) / double(d.bits)
                       << ", uncertain " << double(d.uncertain) / double(d.bits));
        CHECK(d.wrong_certain == 0);
        CHECK(d.uncertain >= d.wrong_seed);  // every wrong centre bit is an uncertain one
        CHECK(d.wrong_seed > 0);             // the seed mode is an approximation: the test can see errors
        if (c.mapping == penumbra::LutNormalMapping::Octahedral) {
            // The tolerance covers float lookups (float plane, float cell location).
            const Tally f = tally<float>(setup, lut, planes / 4, seed + 1);
            CHECK(f.wrong_certain == 0);
        }
    }
}

}  // namespace

TEST_CASE("light lut: certified mode has no wrong certain bit (double and float lookups)") { certifiedNeverWrong(20000); }

TEST_SUITE("stress") {
TEST_CASE("light lut: certified mode has no wrong certain bit, 10^6 planes per case") { certifiedNeverWrong(1000000); }
}

TEST_CASE("light lut: seed-mode error shrinks with resolution; symmetric halves the memory") {
    const std::vector<dvec3> samples = ballSets(128, 1);
    double previous = 1.0;
    for (uint32_t r : {16u, 32u, 64u}) {
        penumbra::LightLutOptions options;
        options.resolution = r;
        options.certified = true;
        const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, 128, options);
        const Tally t = tally<double>(setup, penumbra::generateLightLut(setup), 5000, penumbra::test::testSeed(r));
        const double wrong = double(t.wrong_seed) / double(t.bits);
        MESSAGE("R " << r << ": wrong " << wrong << ", uncertain " << double(t.uncertain) / double(t.bits));
        CHECK(wrong < previous);
        previous = wrong;
    }
    CHECK(previous < 0.01);
}

TEST_CASE("light lut: trivial planes, symmetry and bad planes") {
    penumbra::LightLutOptions options;
    options.resolution = 16;
    options.certified = true;
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(64, 1), 64, options);
    const std::vector<uint32_t> lut = penumbra::generateLightLut(setup);
    const penumbra::LutMask all{~0u, ~0u, 0, 0}, none{};
    auto lookup = [&](const dvec4& plane) { return penumbra::lightLutLookup(setup.params, lut.data(), 0, plane); };
    // |d| >= 1 misses the bounding sphere: answered without the table, certain.
    CHECK(lookup(dvec4(0, 0, 1, 1.0)).centre == none);
    CHECK(lookup(dvec4(0, 0, 1, -1.0)).centre == all);
    CHECK(lookup(dvec4(0, 0, 1, -1.0)).uncertain == none);
    CHECK(lookup(dvec4(0, 0, 2, 2.5)).centre == none);     // n need not be unit: d = 1.25
    CHECK(penumbra::lightLutLocate(setup.params, dvec4(0, 0, -3, -2.0)).trivial == 0);
    // Bad planes: the documented empty mask.
    const double nan = std::nan("");
    for (const dvec4& bad : {dvec4(nan, 0, 1, 0), dvec4(0, 0, 1, nan), dvec4(0, 0, 0, -0.5), dvec4(INFINITY, 0, 0, 0)}) {
        CHECK(penumbra::lightLutLocate(setup.params, bad).trivial == -1);
        CHECK(lookup(bad).centre == none);
        CHECK(lookup(bad).uncertain == none);
    }
    // (n, d) and (-n, -d): complementary centre masks, the same uncertain bits.
    std::mt19937_64 rng(penumbra::test::testSeed());
    for (int k = 0; k < 2000; ++k) {
        const dvec4 plane = randomPlane(rng);
        const penumbra::LutAnswer a = lookup(plane), b = lookup(-plane);
        if (penumbra::lightLutLocate(setup.params, plane).trivial != 0 || plane.w == 0.0) continue;
        REQUIRE(a.uncertain == b.uncertain);
        REQUIRE(xorMask(a.centre, b.centre) == all);
    }
}

TEST_CASE("light lut: combining planes keeps certainty sound") {
    penumbra::LightLutOptions options;
    options.resolution = 16;
    options.certified = true;
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(128, 1), 128, options);
    const std::vector<uint32_t> lut = penumbra::generateLightLut(setup);
    std::mt19937_64 rng(penumbra::test::testSeed());
    uint64_t uncertain = 0, total = 0;
    for (int k = 0; k < 20000; ++k) {
        const dvec4 planes[3] = {randomPlane(rng), randomPlane(rng), randomPlane(rng)};
        penumbra::LutCertain c = penumbra::lutCertain(penumbra::lightLutLookup(setup.params, lut.data(), 0, planes[0]));
        penumbra::LutMask exact = penumbra::exactBehind(setup, 0, planes[0]);
        for (int p = 1; p < 3; ++p) {
            c = penumbra::lutCombine(c, penumbra::lutCertain(penumbra::lightLutLookup(setup.params, lut.data(), 0, planes[p])));
            const penumbra::LutMask e = penumbra::exactBehind(setup, 0, planes[p]);
            for (int w = 0; w < 4; ++w) exact[w] &= e[w];
        }
        // Certain bits are right; behind and uncertain never overlap.
        REQUIRE(andNot(xorMask(c.behind, exact), c.uncertain) == penumbra::LutMask{});
        for (int w = 0; w < 4; ++w) REQUIRE((c.behind[w] & c.uncertain[w]) == 0u);
        uncertain += static_cast<uint64_t>(popcount(c.uncertain));
        total += 128;
    }
    MESSAGE("uncertain after combining 3 planes: " << double(uncertain) / double(total));
    CHECK(uncertain > 0);
}

TEST_CASE("light lut: progress reaches 1 and cancellation stops") {
    penumbra::LightLutOptions options;
    options.resolution = 32;
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(128, 2), 128, options);
    std::vector<double> seen;
    const std::vector<uint32_t> words = penumbra::generateLightLut(setup, [&](double f) {
        seen.push_back(f);
        return true;
    });
    REQUIRE(!seen.empty());
    CHECK(seen.back() == 1.0);
    CHECK(std::is_sorted(seen.begin(), seen.end()));
    int calls = 0;
    std::vector<uint32_t> out(setup.texelCount() * 4);
    CHECK_FALSE(penumbra::generateLightLut(setup, out.data(), out.size(), [&](double) { return ++calls < 3; }));
    CHECK(contains(errorOf([&] { penumbra::generateLightLut(setup, [](double) { return false; }); }), "cancelled"));
    CHECK(contains(errorOf([&] { penumbra::generateLightLut(setup, out.data(), 5); }), "needs"));
}

TEST_CASE("light lut: a rotated plane answers for rotated samples") {
    penumbra::LightLutOptions options;
    options.resolution = 32;
    options.certified = true;
    const std::vector<dvec3> samples = diskSet(128);
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(samples, 128, options);
    const std::vector<uint32_t> lut = penumbra::generateLightLut(setup);
    std::mt19937_64 rng(penumbra::test::testSeed());
    std::uniform_real_distribution<double> angle(0.0, 6.283185307179586);
    for (int k = 0; k < 24; ++k) {  // a setup per angle: a few dozen angles
        const double a = angle(rng), c = std::cos(a), s = std::sin(a);
        // The samples rotated by a about z, and the exact mask of a random plane on them.
        std::vector<dvec3> rotated(samples.size());
        for (size_t i = 0; i < samples.size(); ++i)
            rotated[i] = dvec3(c * samples[i].x - s * samples[i].y, s * samples[i].x + c * samples[i].y, samples[i].z);
        const penumbra::LightLutSetup rotated_setup = penumbra::lightLutSetup(rotated, 128, options);
        const dvec4 plane = randomPlane(rng);
        const penumbra::LutMask exact = penumbra::exactBehind(rotated_setup, 0, plane);
        const dvec4 turned = penumbra::lightLutRotate(plane, c, s);
        const penumbra::LutCertain certain = penumbra::lutCertain(penumbra::lightLutLookup(setup.params, lut.data(), 0, turned));
        // Certain bits of the unrotated table are right for the rotated samples (up to the
        // rotation's rounding, far below the tolerance).
        REQUIRE(andNot(xorMask(certain.behind, exact), certain.uncertain) == penumbra::LutMask{});
    }
}

namespace {

// Issue 41 item 10: BM_LutLookupCertified/64/512 had one wrong bit, plane 56000 (of its 65 536),
// table 3, bit 31 (sample 415). Exact value on these float inputs (Python fractions):
// dot(n, q) + w = -2.4893796357616793e-08 < 0, behind; the float evaluation rounds it to 0.
const glm::vec4 kIssuePlane(-0x1.b5fd3p-1f, -0x1.d51bp-2f, -0x1.eeaf9ep-3f, 0x1.d44ce4p-2f);
const glm::vec3 kIssueSample(0x1.6f1ad4p-2f, 0x1.44ee3p-1f, -0x1.28ef46p-1f);

bool bit(const penumbra::LutMask& m, uint32_t b) { return (m[b >> 5] >> (b & 31)) & 1u; }

}  // namespace

TEST_CASE("light lut: the float exact test is fp64's on the float inputs (issue 41 item 10's plane and sample)") {
    using penumbra::detail::dotRounded;
    // The trap: the float evaluation is exactly 0, so "strictly behind" says no.
    CHECK(dotRounded(glm::vec3(kIssuePlane), kIssueSample) + kIssuePlane.w == 0.0f);
    // Hand case: sample 0 is the issue's sample, the others the centre (0 + w > 0: in front).
    std::vector<dvec3> samples(32, dvec3(0.0));
    samples[0] = dvec3(kIssueSample);
    penumbra::LightLutOptions options;
    options.resolution = 16;
    options.certified = true;
    const penumbra::LightLutSetup hand = penumbra::lightLutSetup(samples, 32, options);
    const penumbra::LutMask want{1u, 0u, 0u, 0u};
    CHECK(penumbra::exactBehindOracle(hand, 0, kIssuePlane) == want);
    CHECK(penumbra::exactBehind(hand, 0, kIssuePlane) == want);
    CHECK(penumbra::exactBehind(hand, 0, -kIssuePlane) == penumbra::LutMask{~1u, 0u, 0u, 0u});  // w < 0: the centre is behind
    penumbra::LutCertain all_uncertain;
    all_uncertain.uncertain = {~0u, 0u, 0u, 0u};
    CHECK(penumbra::lutResolve(hand, 0, all_uncertain, kIssuePlane) == want);

    // The benchmark's own LUT (BM_LutLookupCertified/64/512): the sample is bit 31 of table 3, the
    // lookup leaves it uncertain, and resolving it gives the oracle's mask.
    options.resolution = 64;
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(
        penumbra::reference::sphereLightSamples(dvec3(0.0), 0.999, 512, 20261201u), 512, options);
    REQUIRE(glm::vec3(setup.samples[3 * 128 + 31]) == kIssueSample);
    const penumbra::LutCell cell = penumbra::lightLutLocate(setup.params, kIssuePlane);
    REQUIRE(cell.trivial == 0);
    std::vector<uint32_t> words(setup.texelCount() * 4, 0u);  // only the texel the lookup reads
    const penumbra::LutAnswer texel = penumbra::lightLutTexel(setup, 3, cell.texel);
    std::copy(texel.centre.begin(), texel.centre.end(), words.begin() + (3ull * setup.params.texels_per_table + cell.texel) * 4);
    std::copy(texel.uncertain.begin(), texel.uncertain.end(),
              words.begin() + (uint64_t(setup.params.uncertain_offset) + 3ull * setup.params.texels_per_table + cell.texel) * 4);
    const penumbra::LutCertain c = penumbra::lutCertain(penumbra::lightLutLookup(setup.params, words.data(), 3, kIssuePlane));
    CHECK(bit(c.uncertain, 31));
    const penumbra::LutMask oracle = penumbra::exactBehindOracle(setup, 3, kIssuePlane);
    CHECK(bit(oracle, 31));
    CHECK(penumbra::lutResolve(setup, 3, c, kIssuePlane) == oracle);
    CHECK(penumbra::exactBehind(setup, 3, kIssuePlane) == oracle);
}

TEST_CASE("light lut: the float exact test equals the oracle on planes within float noise of a sample") {
    // Planes through a sample, moved by a few float ulps: the float evaluation alone is wrong on
    // a good share of them; the filtered test never is.
    std::mt19937_64 rng(penumbra::test::testSeed());
    penumbra::LightLutOptions options;
    options.resolution = 16;
    const penumbra::LightLutSetup setup = penumbra::lightLutSetup(ballSets(128, 1), 128, options);
    std::uniform_int_distribution<int> sample(0, 127), ulps(-8, 8);
    std::uniform_real_distribution<double> scale(0.01, 100.0);
    uint64_t naive_wrong = 0, planes = 0;
    for (int k = 0; k < 50000; ++k) {
        const int b = sample(rng);
        const glm::vec3 q(setup.samples[size_t(b)]);
        const dvec3 n = glm::normalize(dvec3(randomPlane(rng))) * scale(rng);
        float w = float(-glm::dot(n, dvec3(q)));
        for (int u = ulps(rng); u != 0; u += u > 0 ? -1 : 1) w = std::nextafter(w, u > 0 ? INFINITY : -INFINITY);
        const glm::vec4 plane(glm::vec3(n), w);
        const penumbra::LutMask oracle = penumbra::exactBehindOracle(setup, 0, plane);
        const bool naive = penumbra::detail::dotRounded(glm::vec3(plane), q) + plane.w < 0.0f;
        naive_wrong += naive != bit(oracle, uint32_t(b));
        ++planes;
        REQUIRE(penumbra::exactBehind(setup, 0, plane) == oracle);
    }
    MESSAGE(planes << " planes: the float evaluation alone misjudges " << naive_wrong << " of their samples");
    CHECK(naive_wrong > 0);  // the planes do reach the float noise
}
