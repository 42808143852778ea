// pipelines/sample_based_soft.hpp's CPU twin against the oracle: on the built-in scenes, with the
// same light samples, Exact and Brute give the oracle's blocked bits on every pair it does not call
// a tie; Lut's error is reported. Receivers lie on the scenes' surfaces (as view samples do).
#include "penumbra/pipelines/sample_based_soft.hpp"
#include "penumbra/scene/scene.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <cmath>
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
            // Receiver r uses rotation step r % 4 of 4 (sintorn2008 §4.2's per-pixel jitter); the
            // oracle gets each receiver's rotated samples (sampleBasedSoftSampleTable).
            constexpr uint32_t kRotations = 4;
            std::vector<uint32_t> selection(points.size());
            for (size_t r = 0; r < points.size(); ++r) selection[r] = uint32_t(r % kRotations) << 8;
            const penumbra::SoftReceivers receivers{points.data(), points.size(), selection.data()};

            std::vector<dvec3> positions(mesh.positions.begin(), mesh.positions.end());
            const penumbra::reference::VisibilityOracle oracle(positions, mesh.indices);
            const std::vector<glm::dvec4> table = penumbra::sampleBasedSoftSampleTable(sets, kRotations);
            // The oracle per rotation step, scattered back into receiver order.
            penumbra::reference::VisibilityResult truth;
            truth.receivers = points.size();
            truth.samples = n;
            truth.words_per_receiver = (n + 31) / 32;
            truth.blocked.assign(points.size() * truth.words_per_receiver, 0u);
            truth.ties = truth.blocked;
            for (uint32_t step = 0; step < kRotations; ++step) {
                std::vector<dvec3> group, samples;
                for (size_t r = step; r < points.size(); r += kRotations) group.emplace_back(points[r]);
                for (uint32_t i = 0; i < n; ++i) samples.emplace_back(table[size_t(step) * n + i]);
                const penumbra::reference::VisibilityResult part = oracle.evaluate(group, samples);
                for (size_t g = 0; g < group.size(); ++g)
                    for (uint32_t w = 0; w < truth.words_per_receiver; ++w) {
                        const size_t r = step + g * kRotations;
                        truth.blocked[r * truth.words_per_receiver + w] = part.blocked[g * part.words_per_receiver + w];
                        truth.ties[r * truth.words_per_receiver + w] = part.ties[g * part.words_per_receiver + w];
                    }
            }

            penumbra::SampleBasedSoftOptions options;
            options.rotations = kRotations;
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
    const uint32_t bad_step = 1u << 8;  // rotation step 1 of 1
    const penumbra::SoftReceivers bad_rotation{points.data(), 1, &bad_step};
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(sets, &seed_lut, words.data(), casters, bad_rotation, options); }),
                   "rotation step 1 of 1"));
    options.rotations = 300;
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftCpu(sets, &seed_lut, words.data(), casters, receivers, options); }),
                   "rotations = 300"));
    options.rotations = 1;
    {
        penumbra::Light rectangle = light;  // not symmetric about local z: rotation steps refused
        rectangle.shape = penumbra::LightShape::Rectangle;
        rectangle.size = dvec3(0.4, 0.2, 0.0);
        const penumbra::LightSampleSets rect_sets = penumbra::makeLightSampleSets(rectangle, sample_options);
        CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftSampleTable(rect_sets, 4); }), "symmetric"));
        CHECK(penumbra::sampleBasedSoftSampleTable(rect_sets, 1).size() == size_t(2) * 64 + 1);
        // Step 0 is the sets' world samples bit for bit; other steps rotate them about local z.
        const std::vector<glm::dvec4> t = penumbra::sampleBasedSoftSampleTable(sets, 4);
        CHECK(glm::dvec3(t[5]) == sets.worldSet(0)[5]);
        CHECK(glm::dvec3(t[64 + 5]) != sets.worldSet(0)[5]);
        CHECK(std::abs(glm::length(glm::dvec3(t[64 + 5]) - light.center) - glm::length(sets.worldSet(0)[5] - light.center)) < 1e-12);
        CHECK(t[size_t(2) * 4 * 64 + 1].x == doctest::Approx(0.0).epsilon(1e-15));  // cos(1/4 turn)
    }
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

TEST_CASE("sample-based soft (CPU twin): depth-input epsilon, receivers in a tessellated floor's plane") {
    // A floor of 8 x 8 quads (128 coplanar triangles) under a tilted triangle, receivers on the floor
    // nudged off it by up to ~1e-6 (as positions rebuilt from a depth buffer are), and the coplanar
    // epsilon the demo uses for depth input (2e-5) on both sides. Every floor triangle is a caster
    // of every floor receiver here (the twin has no influence regions): with p in their plane
    // (det ~ 0) those pairs were decided sample by sample; the light lies above the floor, so they
    // are now proven to block nothing. Exact must still equal the oracle bit for bit.
    const uint32_t seed = penumbra::test::testSeed();
    penumbra::scene::Mesh floor = penumbra::scene::groundPlane(2.0f, 0.0f, 8);
    penumbra::scene::Mesh mesh = floor;
    const uint32_t base = uint32_t(mesh.positions.size());
    mesh.positions.insert(mesh.positions.end(), {{-0.4f, 0.6f, -0.3f}, {0.5f, 0.8f, -0.2f}, {0.0f, 0.7f, 0.6f}});
    mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2});
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    std::vector<glm::vec3> points;
    for (int i = 0; i < 300; ++i) points.emplace_back(1.5f * unit(rng), (i % 3 == 0 ? 1e-6f : 0.0f) * unit(rng), 1.5f * unit(rng));

    penumbra::Light light;
    light.center = dvec3(0.3, 3.0, 0.2);
    light.size = dvec3(0.4);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 128;
    sample_options.sets = 1;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);

    penumbra::SampleBasedSoftGpuOptions gpu_options;
    gpu_options.grid_width = gpu_options.grid_height = 64;
    gpu_options.oracle.coplanar_epsilon = 2e-5;
    penumbra::LightLutOptions lut_options;
    lut_options.resolution = 32;
    lut_options.certified = true;
    lut_options.tolerance = penumbra::sampleBasedSoftLutTolerance(gpu_options, sets.frame, dvec3(-2, 0, -2), dvec3(2, 0.8, 2));
    CHECK(lut_options.tolerance == 1e-6);  // the oracle's tie epsilon (1e-9) needs no more at this scale
    const penumbra::LightLutSetup lut = penumbra::lightLutSetup(sets, lut_options);
    const std::vector<uint32_t> words = penumbra::generateLightLut(lut);

    penumbra::SampleBasedSoftOptions options;
    options.mode = penumbra::SoftMode::Exact;
    options.oracle.coplanar_epsilon = 2e-5;
    const penumbra::SoftCasters casters{mesh.positions.data(), mesh.positions.size(), mesh.indices.data(), mesh.triangleCount()};
    const penumbra::SoftReceivers receivers{points.data(), points.size(), nullptr};
    const penumbra::SampleBasedSoftCpuResult exact = penumbra::sampleBasedSoftCpu(sets, &lut, words.data(), casters, receivers, options);

    std::vector<dvec3> positions(mesh.positions.begin(), mesh.positions.end());
    const penumbra::reference::VisibilityOracle oracle(positions, mesh.indices);
    penumbra::reference::VisibilityOptions oracle_options;
    oracle_options.coplanar_epsilon = 2e-5;
    const penumbra::reference::VisibilityResult truth = oracle.evaluate(
        std::vector<dvec3>(points.begin(), points.end()), std::vector<dvec3>(sets.worldSet(0), sets.worldSet(0) + 128), oracle_options);
    const Tally e = compare(exact, truth);
    uint64_t blocked = 0;
    for (size_t r = 0; r < points.size(); ++r) blocked += truth.blockedCount(r);
    MESSAGE("floor: " << e.bits << " bits, " << blocked << " blocked, " << e.ties << " ties, exact mismatched " << e.mismatched
                      << "; pairs " << exact.pairs << ", ignored " << exact.pairs_ignored << ", unproven " << exact.pairs_unproven
                      << ", exact tests " << exact.exact_tests);
    CHECK(blocked > 0);
    CHECK(e.mismatched == 0);
    // The 200 receivers exactly in the floor's plane: every floor triangle is ignored (its own by
    // the coplanar rule, the others proven to block nothing); the 100 nudged ones (det above its
    // rounding bound) go through the LUT. Nothing is left to per-sample tests but the few pairs
    // within the coplanar reach.
    CHECK(exact.pairs_ignored >= 200 * 128);
    CHECK(exact.pairs_unproven < points.size() * 4);
}

TEST_CASE("sample-based soft: sampleBasedSoftLutTolerance") {
    penumbra::Light light;
    light.center = dvec3(0, 4, 0);
    light.size = dvec3(0.25);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 32;
    sample_options.sets = 1;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
    penumbra::SampleBasedSoftGpuOptions o;
    o.grid_width = o.grid_height = 16;
    CHECK(penumbra::sampleBasedSoftLutTolerance(o, sets.frame, dvec3(-1), dvec3(1)) == 1e-6);  // default floor
    // A large tie epsilon needs a proportionally larger margin: 1.25 * 2 * tie * s / (budget * r),
    // s = max(box extent 2, farthest corner from the centre 5 + reach 0.25 sqrt 3).
    o.oracle.tie_epsilon = 1e-6;
    const double s = 5.0 + 0.25 * std::sqrt(3.0);
    const double want = 1.25 * 2.0 * 1e-6 * s / (0.25 * 0.25);
    CHECK(penumbra::sampleBasedSoftLutTolerance(o, sets.frame, dvec3(-1), dvec3(1)) == doctest::Approx(want).epsilon(1e-12));
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftLutTolerance(o, sets.frame, dvec3(1), dvec3(-1)); }), "ordered"));
    CHECK(contains(errorOf([&] { penumbra::sampleBasedSoftLutTolerance(o, sets.frame, dvec3(std::nan("")), dvec3(1)); }),
                   "finite"));
}
