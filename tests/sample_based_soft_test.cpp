// pipelines/sample_based_soft.hpp's CPU twin against the oracle: on the built-in scenes, with the
// same light samples, Exact and Brute give the oracle's blocked bits on every pair it does not call
// a tie; Lut's error is reported. Receivers lie on the scenes' surfaces (as view samples do).
#include "penumbra/pipelines/sample_based_soft.hpp"
#include "penumbra/scene/scene.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <random>

using glm::dvec3;
using penumbra::test::contains;
using penumbra::test::errorOf;

namespace {

struct Case {
    std::string name;
    penumbra::scene::Scene scene;
};

/// `count` points on random triangles of the merged mesh (area-weighted by the triangle index
/// draw being uniform per triangle of the ground's subdivided grid and the object).
std::vector<glm::vec3> surfacePoints(const penumbra::scene::Mesh& mesh, size_t count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<size_t> pick(0, mesh.triangleCount() - 1);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<glm::vec3> points;
    while (points.size() < count) {
        const size_t t = pick(rng);
        const glm::vec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
                        c = mesh.positions[mesh.indices[3 * t + 2]];
        float u = unit(rng), v = unit(rng);
        if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
        points.push_back(a + u * (b - a) + v * (c - a));
    }
    return points;
}

struct Tally {
    uint64_t bits = 0, ties = 0, mismatched = 0;
};

Tally compare(const penumbra::SampleBasedSoftCpuResult& result, const penumbra::reference::VisibilityResult& oracle) {
    Tally t;
    for (size_t r = 0; r < oracle.receivers; ++r)
        for (uint32_t s = 0; s < oracle.samples; ++s) {
            ++t.bits;
            if (oracle.isTie(r, s)) {
                ++t.ties;
                continue;
            }
            t.mismatched += result.blocked(r, s) != oracle.isBlocked(r, s);
        }
    return t;
}

}  // namespace

namespace {

void equalsOracle(bool stress) {
    const uint32_t seed = penumbra::test::testSeed();
    std::vector<Case> cases;
    cases.push_back({"torus_knot", penumbra::scene::torusKnot(24)});
    cases.push_back({"columns", penumbra::scene::columns(4)});
    cases.push_back({"hairball", penumbra::scene::hairball(600, 3)});
    cases.push_back({"grass", penumbra::scene::grass(150, 3)});
    const size_t receiver_count = stress ? 2000 : 200;
    for (const Case& c : cases) {
        // N = 128 everywhere, N = 1024 on the torus knot (every scene in the stress suite).
        std::vector<uint32_t> counts = {128u};
        if (stress || c.name == "torus_knot") counts.push_back(1024u);
        for (const uint32_t n : counts) {
            INFO(c.name << " N=" << n);
            const penumbra::scene::Mesh mesh = c.scene.merged();
            penumbra::Light light;
            light.center = dvec3(c.scene.light.position);
            light.size = dvec3(double(c.scene.light.radius));
            penumbra::LightSampleOptions sample_options;
            sample_options.count = n;
            sample_options.sets = 1;
            sample_options.seed = 11;
            const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
            penumbra::LightLutOptions lut_options;
            lut_options.resolution = 64;
            lut_options.certified = true;
            const penumbra::LightLutSetup lut = penumbra::lightLutSetup(sets, lut_options);
            const std::vector<uint32_t> words = penumbra::generateLightLut(lut);

            const std::vector<glm::vec3> points = surfacePoints(mesh, receiver_count, seed + n);
            const penumbra::SoftCasters casters{mesh.positions.data(), mesh.positions.size(), mesh.indices.data(),
                                                mesh.triangleCount()};
            const penumbra::SoftReceivers receivers{points.data(), points.size(), nullptr};

            std::vector<dvec3> positions(mesh.positions.begin(), mesh.positions.end());
            const penumbra::reference::VisibilityOracle oracle(positions, mesh.indices);
            const std::vector<dvec3> receivers_d(points.begin(), points.end());
            const std::vector<dvec3> samples(sets.worldSet(0), sets.worldSet(0) + n);
            const penumbra::reference::VisibilityResult truth = oracle.evaluate(receivers_d, samples);

            penumbra::SampleBasedSoftOptions options;
            options.mode = penumbra::SoftMode::Exact;
            const penumbra::SampleBasedSoftCpuResult exact = penumbra::sampleBasedSoftCpu(sets, &lut, words.data(), casters,
                                                                                          receivers, options);
            // Brute (every pair, every sample) only at N = 128: the oracle is the brute reference.
            options.mode = penumbra::SoftMode::Brute;
            const penumbra::SampleBasedSoftCpuResult brute =
                n == 128 ? penumbra::sampleBasedSoftCpu(sets, nullptr, nullptr, casters, receivers, options) : exact;
            options.mode = penumbra::SoftMode::Lut;
            const penumbra::SampleBasedSoftCpuResult approx = penumbra::sampleBasedSoftCpu(sets, &lut, words.data(), casters,
                                                                                           receivers, options);
            const Tally e = compare(exact, truth), b = compare(brute, truth), l = compare(approx, truth);
            uint64_t blocked = 0;
            for (size_t r = 0; r < points.size(); ++r) blocked += truth.blockedCount(r);
            MESSAGE(c.name << " N=" << n << ": " << e.bits << " bits, " << blocked << " blocked, " << e.ties
                           << " ties; exact mismatched " << e.mismatched << " (uncertain "
                           << double(exact.uncertain_bits) / double(std::max<uint64_t>(exact.bits, 1))
                           << " of pair bits, unproven pairs " << exact.pairs_unproven << ", ignored " << exact.pairs_ignored
                           << ", unproven planes " << exact.planes_unproven << " of " << exact.planes
                           << "), brute mismatched " << b.mismatched << ", lut mismatched "
                           << double(l.mismatched) / double(l.bits));
            CHECK(blocked > 0);  // the case has shadows to get right
            CHECK(e.mismatched == 0);
            CHECK(b.mismatched == 0);
            CHECK(l.mismatched < l.bits / 20);  // the seed mode is close, not exact (reported above)
            CHECK(exact.uncertain_bits < exact.bits / 10);  // the LUT decides most bits
        }
    }
}

}  // namespace

TEST_CASE("sample-based soft (CPU twin): exact and brute equal the oracle, lut reports its error") { equalsOracle(false); }

TEST_SUITE("stress") {
TEST_CASE("sample-based soft (CPU twin): the same with 2000 receivers and N = 1024 everywhere") { equalsOracle(true); }
}

TEST_CASE("sample-based soft (CPU twin): bad input") {
    penumbra::Light light;
    light.center = dvec3(0, 4, 0);
    light.size = dvec3(0.3);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 64;
    sample_options.sets = 2;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
    penumbra::LightLutOptions lut_options;
    lut_options.resolution = 16;
    const penumbra::LightLutSetup seed_lut = penumbra::lightLutSetup(sets, lut_options);
    const std::vector<uint32_t> words = penumbra::generateLightLut(seed_lut);
    const std::vector<glm::vec3> positions = {{0, 1, 0}, {1, 1, 0}, {0, 1, 1}};
    const std::vector<uint32_t> indices = {0, 1, 2}, bad_indices = {0, 1, 3};
    const std::vector<glm::vec3> points = {{-0.05f, 0, 0.2f}};  // in the penumbra of edge x = 0
    const uint32_t bad_set = 2;
    const penumbra::SoftCasters casters{positions.data(), 3, indices.data(), 1};
    const penumbra::SoftReceivers receivers{points.data(), 1, nullptr};
    penumbra::SampleBasedSoftOptions options;
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(sets, &seed_lut, words.data(), casters, receivers, options); }),
                   "certified"));
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(sets, nullptr, nullptr, casters, receivers, options); }),
                   "needs a LUT"));
    options.mode = penumbra::SoftMode::Lut;
    const penumbra::SoftCasters bad{positions.data(), 3, bad_indices.data(), 1};
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(sets, &seed_lut, words.data(), bad, receivers, options); }),
                   "beyond the 3"));
    const penumbra::SoftReceivers bad_receivers{points.data(), 1, &bad_set};
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(sets, &seed_lut, words.data(), casters, bad_receivers, options); }),
                   "uses set 2 of 2"));
    sample_options.count = 128;
    const penumbra::LightSampleSets other = penumbra::makeLightSampleSets(light, sample_options);
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(other, &seed_lut, words.data(), casters, receivers, options); }),
                   "built for 2 sets of 64"));
    // A blocker straight above: Lut and Brute agree on a clear case.
    const penumbra::SampleBasedSoftCpuResult lut_result =
        penumbra::sampleBasedSoftCpu(sets, &seed_lut, words.data(), casters, receivers, options);
    options.mode = penumbra::SoftMode::Brute;
    const penumbra::SampleBasedSoftCpuResult brute = penumbra::sampleBasedSoftCpu(sets, nullptr, nullptr, casters, receivers, options);
    CHECK(brute.blockedCount(0) > 0);
    CHECK(brute.blockedCount(0) < 64);
    CHECK(std::abs(int(lut_result.blockedCount(0)) - int(brute.blockedCount(0))) <= 4);
}
