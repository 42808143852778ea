// The GPU sample-based soft-shadow pipeline (penumbra/gl/pipelines/sample_based_soft.hpp) against
// the oracle and its CPU twin (penumbra/pipelines/sample_based_soft.hpp), on the built-in scenes:
// receivers are points on the surfaces (as view samples are), the light samples the same world
// samples the oracle tests. Exact and Brute: 0 mismatched non-tie bits vs
// reference::VisibilityOracle::evaluate (any conformant fp64 driver). Lut: its mismatch fraction
// vs the oracle is reported, and its bits are compared with the CPU twin's Lut mode: the GPU looks
// the fp64 planes up after rounding them to float, the twin in double, so bits may differ where a
// plane lies within float rounding of a LUT cell border (tolerance: 1e-3 of the bits).
#include "support/per_frame_contract.hpp"

#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/pipelines/sample_based_soft.hpp>
#include <penumbra/adjacency.hpp>
#include <penumbra/pipelines/alias_free_hard.hpp>
#include <penumbra/pipelines/silhouette_marks.hpp>
#include <penumbra/scene/gl_scene.hpp>
#include <penumbra/scene/obj.hpp>
#include <penumbra/scene/scene.hpp>

#include "support/gl_test_support.hpp"
#include "support/gl_world.hpp"
#include "support/source_paths.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

using glm::dvec3;
using penumbra::Status;

namespace {

/// The scenes a sweep over scenes runs: all of them, or in the sanitizer build (penumbra::test::
/// kSanitized: every path of the host code runs on the first scene) the first only.
std::vector<std::string> sweptScenes(std::vector<std::string> names) {
    if (penumbra::test::kSanitized && names.size() > 1) {
        MESSAGE("sanitizer build: ", names.front(), " only (the Release run sweeps every scene)");
        names.resize(1);
    }
    return names;
}

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

/// Casters as a VAO (attribute 0 = vec3 position) + index buffer.
struct GpuMesh {
    penumbra::gl::Buffer vbo, ibo;
    penumbra::gl::VertexArray vao;
    GLsizei index_count = 0;
    explicit GpuMesh(const penumbra::scene::Mesh& mesh)
        : vbo(penumbra::gl::Buffer::fromVector(mesh.positions)), ibo(penumbra::gl::Buffer::fromVector(mesh.indices)),
          vao(penumbra::gl::VertexArray::create()), index_count(static_cast<GLsizei>(mesh.indices.size())) {
        glVertexArrayVertexBuffer(vao.id(), 0, vbo.id(), 0, sizeof(glm::vec3));
        glVertexArrayAttribFormat(vao.id(), 0, 3, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao.id(), 0, 0);
        glEnableVertexArrayAttrib(vao.id(), 0);
        glVertexArrayElementBuffer(vao.id(), ibo.id());
    }
    void draw() const {
        glBindVertexArray(vao.id());
        glDrawElements(GL_TRIANGLES, index_count, GL_UNSIGNED_INT, nullptr);
    }
};

struct Tally {
    uint64_t bits = 0, ties = 0, mismatched = 0, untested = 0;
};

bool bitOf(const std::vector<uint32_t>& masks, uint32_t words, size_t r, uint32_t s) {
    return (masks[r * words + s / 32] >> (s % 32)) & 1u;
}

Tally compareOracle(const std::vector<uint32_t>& masks, uint32_t words, const std::vector<float>& visibility,
                    const penumbra::reference::VisibilityResult& oracle) {
    Tally t;
    for (size_t r = 0; r < oracle.receivers; ++r) {
        if (visibility[r] < 0.0f) {
            ++t.untested;
            continue;
        }
        for (uint32_t s = 0; s < oracle.samples; ++s) {
            ++t.bits;
            if (oracle.isTie(r, s)) {
                ++t.ties;
                continue;
            }
            t.mismatched += bitOf(masks, words, r, s) != oracle.isBlocked(r, s);
        }
    }
    return t;
}

/// Rotation steps about the light's local z in the scene checks (sintorn2008 §4.2's jitter).
constexpr uint32_t kRotations = 4;

/// A spherical light's stratified sample sets (makeLightSampleSets).
penumbra::LightSampleSets sphereSets(const dvec3& centre, double radius, uint32_t n, uint32_t sets, uint32_t seed) {
    penumbra::Light light;
    light.center = centre;
    light.size = dvec3(radius);
    penumbra::LightSampleOptions options;
    options.count = n;
    options.sets = sets;
    options.seed = seed;
    return penumbra::makeLightSampleSets(light, options);
}

/// A certified LUT of `sets` at `resolution` (generated on the CPU) and its GL buffer.
struct CertifiedLut {
    penumbra::LightLutSetup lut;
    std::vector<uint32_t> words;
    penumbra::gl::Buffer buffer;

    CertifiedLut(const penumbra::LightSampleSets& sets, uint32_t resolution) {
        penumbra::LightLutOptions options;
        options.resolution = resolution;
        options.certified = true;
        lut = penumbra::lightLutSetup(sets, options);
        words = penumbra::generateLightLut(lut);
        buffer = penumbra::gl::Buffer::fromVector(words);
    }
    penumbra::BufferRange table() const { return {buffer.id(), 0, buffer.size()}; }
};

struct Case {
    std::string name;
    penumbra::scene::Scene scene;
};

}  // namespace

namespace {

/// Every mode on every case: N = 128, and 1024 on the torus knot (on every case when `all_1024`).
/// A light grid over the receivers' box grown by `pad` (the casters need not lie inside its
/// frustum), grid x grid texels, its far plane just beyond every receiver.
struct ReceiverGrid {
    glm::mat4 vp;
    penumbra::InfluenceRegionSetup influence;
};
ReceiverGrid receiverGrid(const std::vector<glm::vec3>& points, const penumbra::Light& light, uint32_t grid, float pad) {
    glm::vec3 lo(1e30f), hi(-1e30f);
    for (const auto& p : points) lo = glm::min(lo, p - pad), hi = glm::max(hi, p + pad);
    ReceiverGrid g;
    g.vp = penumbra::lightViewProjectionForBounds(glm::vec4(glm::vec3(light.center), 1.0f), lo, hi);
    double far_depth = 0.0;
    for (const auto& p : points) far_depth = std::max(far_depth, double((g.vp * glm::vec4(p, 1.0f)).w));
    penumbra::InfluenceRegionOptions io;
    io.grid_width = io.grid_height = grid;
    io.far_plane = penumbra::influenceFarPlaneAtDepth(g.vp, far_depth * 1.01 + 1e-3);
    g.influence = penumbra::influenceRegionSetup(light, g.vp, io);
    return g;
}

void checkScenes(const std::vector<Case>& cases, size_t receiver_count, bool all_1024) {
    penumbra::test::context();
    const uint32_t seed = penumbra::test::testSeed();
    for (const Case& c : cases) {
        std::vector<uint32_t> counts = {128u};
        if (all_1024 || c.name == "torus_knot") counts.push_back(1024u);
        for (const uint32_t n : counts) {
            INFO(c.name << " N=" << n);
            const penumbra::scene::Mesh mesh = c.scene.merged();
            penumbra::Light light;
            light.center = dvec3(c.scene.light.position);
            light.size = dvec3(double(c.scene.light.radius));
            const penumbra::LightSampleSets sets = sphereSets(light.center, double(c.scene.light.radius), n, 2, 11);
            const CertifiedLut certified(sets, 64);
            const penumbra::LightLutSetup& lut = certified.lut;
            const std::vector<uint32_t>& lut_words = certified.words;
            const penumbra::BufferRange lut_table = certified.table();

            // Receivers on the surfaces; half of them use set 1 and each one of 4 rotation steps (the
            // per-pixel choice of sampleBasedSoftSelection): selection word set | step << 8.
            const std::vector<glm::vec3> points = surfacePoints(mesh, receiver_count, seed + n);
            std::vector<uint32_t> receiver_sets(points.size());
            for (size_t r = 0; r < points.size(); ++r) receiver_sets[r] = uint32_t(r & 1u) | uint32_t((r >> 1) & 3u) << 8;
            const std::vector<glm::dvec4> table = penumbra::sampleBasedSoftSampleTable(sets, kRotations);
            std::vector<glm::vec4> positions4;
            for (const auto& p : points) positions4.emplace_back(p, 1.0f);
            const penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(positions4);
            const penumbra::gl::Buffer sets_buffer = penumbra::gl::Buffer::fromVector(receiver_sets);
            const penumbra::SampleBufferInput input{{positions.id(), 0, positions.size()}, {}};

            // The light grid from the light centre over the receivers; far plane beyond every one.
            const ReceiverGrid receiver_grid = receiverGrid(points, light, 64, 0.0f);
            const glm::mat4& vp = receiver_grid.vp;
            const penumbra::InfluenceRegionSetup& influence = receiver_grid.influence;

            // The oracle on the same float receivers and the same world samples (per set).
            std::vector<dvec3> mesh_d(mesh.positions.begin(), mesh.positions.end());
            const penumbra::reference::VisibilityOracle oracle(mesh_d, mesh.indices);
            penumbra::reference::VisibilityOptions oracle_options;
            // The oracle's defaults (tie and coplanar 1e-9), on both sides. (With the hard pipeline's
            // 1e-7 the oracle's coplanar reach exceeds the LUT's margin at tolerance 1e-6: every pair
            // is then decided sample by sample; still exact, as fast as brute.)
            // Group g = set * R + step: receivers r with (r & 1, (r >> 1) & 3) = (set, step).
            const uint32_t groups = 2 * kRotations;
            auto groupOf = [&](size_t r) { return uint32_t(r & 1u) * kRotations + uint32_t((r >> 1) & 3u); };
            std::vector<std::vector<dvec3>> receivers_by_group(groups);
            for (size_t r = 0; r < points.size(); ++r) receivers_by_group[groupOf(r)].push_back(dvec3(points[r]));
            std::vector<penumbra::reference::VisibilityResult> truth_by_group(groups);
            for (uint32_t g = 0; g < groups; ++g) {
                std::vector<dvec3> samples;
                for (uint32_t i = 0; i < n; ++i) samples.emplace_back(table[size_t(g) * n + i]);
                truth_by_group[g] = oracle.evaluate(receivers_by_group[g], samples, oracle_options);
            }
            const uint32_t words = (n + 31) / 32;

            // CPU twin (Lut) for the bit comparison.
            penumbra::SampleBasedSoftOptions twin_options;
            twin_options.mode = penumbra::SoftMode::Lut;
            twin_options.oracle = oracle_options;
            twin_options.rotations = kRotations;
            const penumbra::SoftCasters casters{mesh.positions.data(), mesh.positions.size(), mesh.indices.data(),
                                                mesh.triangleCount()};
            const penumbra::SoftReceivers receivers{points.data(), points.size(), receiver_sets.data()};
            const penumbra::SampleBasedSoftCpuResult twin_lut =
                penumbra::sampleBasedSoftCpu(sets, &lut, lut_words.data(), casters, receivers, twin_options);

            const GpuMesh gpu_mesh(mesh);
            for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Lut, penumbra::SoftMode::Brute}) {
                if (mode == penumbra::SoftMode::Brute && n > 128) continue;
                INFO("mode " << std::string(penumbra::softModeName(mode)));
                penumbra::SampleBasedSoftGpuOptions options;
                options.mode = mode;
                options.grid_width = options.grid_height = 64;
                options.oracle = oracle_options;
                options.rotations = kRotations;
                penumbra::SampleBasedSoftShadows pipeline(options, sets, mode == penumbra::SoftMode::Brute ? nullptr : &lut,
                                                          influence, vp);
                pipeline.reserve(uint32_t(points.size()));
                const penumbra::SbsFrameBuffers frame{{sets_buffer.id(), 0, sets_buffer.size()}, {}, {}};
                pipeline.validate(input, uint32_t(points.size()), lut_table, frame);
                REQUIRE(pipeline.run(input, uint32_t(points.size()), mode == penumbra::SoftMode::Brute ? penumbra::BufferRange{} : lut_table,
                                     [&](penumbra::CasterClass c) {
                                         if (c == penumbra::CasterClass::Open) gpu_mesh.draw();
                                     }, frame) == Status::Ok);
                const std::vector<uint32_t> masks = pipeline.readMasks();
                const std::vector<float> visibility = pipeline.readVisibility();
                const penumbra::SampleBasedSoftFrame f = pipeline.readFrame();
                penumbra::gl::checkErrors("sample_based_soft_gl_test");
                // Per set: the oracle's receivers are the GPU's ids r with r & 1 == set.
                Tally total;
                uint64_t blocked = 0, visibility_errors = 0;
                for (uint32_t g = 0; g < groups; ++g) {
                    std::vector<uint32_t> sub_masks;
                    std::vector<float> sub_visibility;
                    for (size_t r = 0; r < points.size(); ++r) {
                        if (groupOf(r) != g) continue;
                        sub_masks.insert(sub_masks.end(), masks.begin() + r * words, masks.begin() + (r + 1) * words);
                        sub_visibility.push_back(visibility[r]);
                    }
                    const Tally t = compareOracle(sub_masks, words, sub_visibility, truth_by_group[g]);
                    total.bits += t.bits;
                    total.ties += t.ties;
                    total.mismatched += t.mismatched;
                    total.untested += t.untested;
                    for (size_t i = 0; i < truth_by_group[g].receivers; ++i) blocked += truth_by_group[g].blockedCount(i);
                }
                for (size_t r = 0; r < points.size(); ++r) {
                    uint32_t pop = 0;
                    for (uint32_t w = 0; w < words; ++w) pop += uint32_t(__builtin_popcount(masks[r * words + w]));
                    if (visibility[r] >= 0.0f && std::abs(visibility[r] - (1.0f - float(pop) / float(n))) > 1e-6f) ++visibility_errors;
                }
                uint64_t twin_diff = 0;
                if (mode == penumbra::SoftMode::Lut)
                    for (size_t i = 0; i < masks.size(); ++i)
                        twin_diff += uint64_t(__builtin_popcount(masks[i] ^ twin_lut.masks[i]));
                MESSAGE(c.name << " N=" << n << " " << std::string(penumbra::softModeName(mode)) << ": " << total.bits << " bits, " << blocked
                               << " blocked (oracle), " << total.ties << " ties, mismatched " << total.mismatched << " ("
                               << double(total.mismatched) / double(std::max<uint64_t>(total.bits, 1)) << "), untested "
                               << total.untested << "; passes " << f.passes << ", max list " << f.statistics.max_list_length
                               << ", fragments " << f.fragments << ", pairs " << f.pairs << " (ignored " << f.pairs_ignored
                               << ", unproven " << f.pairs_unproven << "), uncertain bits "
                               << double(f.uncertain_bits) / double(std::max<uint64_t>(f.pairs * n, 1)) << " of pair bits, exact tests "
                               << f.exact_tests << ", unproven planes " << f.planes_unproven << ", overflow " << f.overflow
                               << (mode == penumbra::SoftMode::Lut ? ", bits != CPU twin lut: " + std::to_string(twin_diff) : std::string()));
                CHECK(blocked > 0);
                CHECK(total.untested == 0);
                CHECK(f.overflow == 0);
                CHECK(visibility_errors == 0);
                CHECK(f.pairs > 0);
                if (mode == penumbra::SoftMode::Lut) {
                    CHECK(total.mismatched < total.bits / 20);
                    CHECK(twin_diff <= uint64_t(masks.size()) * 32 / 1000);
                } else {
                    CHECK(total.mismatched == 0);
                }
                // The LUT decides most bits (measured 1-10 %: pairs within the oracle's reach of their caster,
                // e.g. columns' ground samples next to a column, are decided sample by sample).
                if (mode == penumbra::SoftMode::Exact) CHECK(f.uncertain_bits < f.pairs * n / 5);
            }
        }
    }
}

}  // namespace

TEST_CASE("GPU sample-based soft: exact and brute equal the oracle, lut reported and close to the CPU twin") {
    std::vector<Case> cases;
    cases.push_back({"torus_knot", penumbra::scene::torusKnot(24)});
    cases.push_back({"columns", penumbra::scene::columns(4)});
    cases.push_back({"hairball", penumbra::scene::hairball(600, 3)});
    checkScenes(cases, 400, false);
}

TEST_SUITE("stress") {
    TEST_CASE("GPU sample-based soft (stress): 2000 receivers, N = 128 and 1024 on every scene, grass too") {
        std::vector<Case> cases;
        cases.push_back({"torus_knot", penumbra::scene::torusKnot(24)});
        cases.push_back({"columns", penumbra::scene::columns(4)});
        cases.push_back({"hairball", penumbra::scene::hairball(600, 3)});
        cases.push_back({"grass", penumbra::scene::grass(150, 3)});
        checkScenes(cases, 2000, true);
    }
}

// Issue 41: a light 1e3 and 1e6 scene sizes away (radius 1 % of its distance) along a fixed
// direction, coplanar epsilon 2e-5 (the demo's for depth-rebuilt samples; uncapped, its reach at
// 1e6 is 20: every caster ignored, no shadows). With scene_extent = the oracle's sceneExtent(),
// Exact and Brute equal VisibilityOracle::evaluate (which passes E) on every non-tie bit, through
// the fragment stage (deferred_pairs = 0) and the deferred compute and exact-test passes, and the
// light casts shadows.
TEST_CASE("GPU sample-based soft: far lights with scene_extent = the oracle's E equal the oracle (issue 41)") {
    penumbra::test::context();
    const penumbra::scene::Scene scene = penumbra::scene::torusKnot(24);
    const penumbra::scene::Mesh mesh = scene.merged();
    const std::vector<dvec3> mesh_d(mesh.positions.begin(), mesh.positions.end());
    const penumbra::reference::VisibilityOracle oracle(mesh_d, mesh.indices);
    penumbra::reference::VisibilityOptions oracle_options;
    oracle_options.coplanar_epsilon = 2e-5;
    const dvec3 direction = glm::normalize(dvec3(scene.light.position));
    const std::vector<glm::vec3> points = surfacePoints(mesh, 400, penumbra::test::testSeed());
    std::vector<glm::vec4> positions4;
    for (const auto& p : points) positions4.emplace_back(p, 1.0f);
    const penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(positions4);
    const penumbra::SampleBufferInput input{{positions.id(), 0, positions.size()}, {}};
    const GpuMesh gpu_mesh(mesh);
    const uint32_t n = 128, words = n / 32;
    for (const double distance : {1e3, 1e6}) {
        INFO("distance " << distance);
        penumbra::Light light;
        light.center = direction * distance;
        light.size = dvec3(distance * 1e-2);
        const penumbra::LightSampleSets sets = sphereSets(light.center, distance * 1e-2, n, 1, 11);
        const CertifiedLut certified(sets, 64);
        // The demo's grid: the §4.3 fit of the view samples, its far plane 1 % beyond the farthest.
        penumbra::SampleListsLight fit_light;
        fit_light.light = glm::vec4(glm::vec3(light.center), 1.0f);
        fit_light.view_projection = receiverGrid(points, light, 64, 0.0f).vp;
        penumbra::SampleListsOptions fit_options;
        fit_options.cull_back_facing = false;
        fit_options.depth_range = penumbra::LightDepthRange::Unclipped;
        const penumbra::LightFrustumFit fit = penumbra::fitLightFrustumCpu(penumbra::sampleListsSetup(64, 64, uint32_t(points.size())),
                                                                           fit_light, positions4.data(), nullptr, fit_options);
        REQUIRE(fit.valid);
        ReceiverGrid grid;
        grid.vp = fit.view_projection;
        double far_depth = 0.0;
        for (const glm::vec4& q : positions4) far_depth = std::max(far_depth, double((grid.vp * q).w));
        penumbra::InfluenceRegionOptions io;
        io.grid_width = io.grid_height = 64;
        io.far_plane = penumbra::influenceFarPlaneAtDepth(grid.vp, far_depth * 1.01 + 1e-3);
        grid.influence = penumbra::influenceRegionSetup(light, grid.vp, io);
        const penumbra::reference::VisibilityResult truth = oracle.evaluate(
            std::vector<dvec3>(points.begin(), points.end()), std::vector<dvec3>(sets.worldSet(0), sets.worldSet(0) + n),
            oracle_options);
        uint64_t blocked = 0;
        for (size_t r = 0; r < points.size(); ++r) blocked += truth.blockedCount(r);
        CHECK(blocked > points.size() * n / 50);  // the light casts shadows at every distance
        for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Brute}) {
            for (const uint32_t deferred : {0u, 1u << 20}) {
                const bool brute = mode == penumbra::SoftMode::Brute;
                INFO("mode " << std::string(penumbra::softModeName(mode)) << ", deferred_pairs " << deferred);
                penumbra::SampleBasedSoftGpuOptions options;
                options.mode = mode;
                options.grid_width = options.grid_height = 64;
                options.oracle = oracle_options;
                options.scene_extent = oracle.sceneExtent();
                options.deferred_pairs = deferred;
                penumbra::SampleBasedSoftShadows pipeline(options, sets, brute ? nullptr : &certified.lut, grid.influence, grid.vp);
                pipeline.reserve(uint32_t(points.size()));
                const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : certified.table();
                REQUIRE(pipeline.run(input, uint32_t(points.size()), table, [&](penumbra::CasterClass c) {
                    if (c == penumbra::CasterClass::Open) gpu_mesh.draw();
                }) == Status::Ok);
                const std::vector<uint32_t> masks = pipeline.readMasks();
                const std::vector<float> visibility = pipeline.readVisibility();
                const penumbra::SampleBasedSoftFrame f = pipeline.readFrame();
                penumbra::gl::checkErrors("sample_based_soft_gl_test far lights");
                const Tally t = compareOracle(masks, words, visibility, truth);
                uint64_t gpu_blocked = 0;
                for (const uint32_t m : masks) gpu_blocked += uint64_t(__builtin_popcount(m));
                MESSAGE("far light at ", distance, ", ", std::string(penumbra::softModeName(mode)), ", deferred_pairs ", deferred, ": ",
                        t.bits, " bits, ", blocked, " blocked (oracle), ", gpu_blocked, " (GPU), ", t.ties, " ties, mismatched ",
                        t.mismatched, ", untested ", t.untested, "; pairs ", f.pairs, ", ignored ", f.pairs_ignored, ", unproven ",
                        f.pairs_unproven, ", exact tests ", f.exact_tests);
                CHECK(t.untested == 0);
                CHECK(f.overflow == 0);
                CHECK(t.mismatched == 0);
                CHECK(gpu_blocked > 0);
                if (!brute) CHECK(f.pairs_unproven < f.pairs);  // the LUT still vouches for pairs
            }
        }
    }
}

TEST_CASE("GPU sample-based soft: per-frame misuse returns a Status, setup errors throw") {
    penumbra::test::context();
    penumbra::Light light;
    light.center = dvec3(0, 4, 0);
    light.size = dvec3(0.3);
    penumbra::LightSampleOptions so;
    so.count = 64;
    so.sets = 1;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, so);
    penumbra::LightLutOptions lo;
    lo.resolution = 16;
    const penumbra::LightLutSetup seed_lut = penumbra::lightLutSetup(sets, lo);
    const glm::mat4 vp = penumbra::lightViewProjectionForBounds(glm::vec4(0, 4, 0, 1), glm::vec3(-2, 0, -2), glm::vec3(2, 1, 2));
    penumbra::InfluenceRegionOptions io;
    io.grid_width = io.grid_height = 32;
    io.far_plane = penumbra::influenceFarPlaneAtDepth(vp, 6.0);
    const penumbra::InfluenceRegionSetup influence = penumbra::influenceRegionSetup(light, vp, io);
    penumbra::SampleBasedSoftGpuOptions options;
    options.grid_width = options.grid_height = 32;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }), "certified"));
    options.grid_width = 16;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, nullptr, influence, vp); }), "differs"));
    options.grid_width = 32;
    options.mode = penumbra::SoftMode::Lut;
    // Deferred pairs and fragments beyond one dispatch's groups, and triangle slots beyond 2^24.
    options.deferred_pairs = 65535u * 256u + 1u;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }),
        "deferred_pairs = 16776961"));
    options.deferred_pairs = 1024;
    options.deferred_triangles = (1u << 24) + 1u;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }),
        "deferred_triangles = 16777217"));
    options.deferred_triangles = 0;
    options.deferred_fragments = 65535u * 256u + 1u;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }),
        "deferred_fragments = 16776961"));
    options.deferred_fragments = 0;
    options.overflow_windows = 65;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }),
        "overflow_windows = 65"));
    options.overflow_windows = 32;
    // The coverage pass's box limit beyond 2^20 texels, its records beyond one dispatch's groups.
    options.coverage_texels = (1u << 20) + 1u;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }),
        "coverage_texels = 1048577"));
    options.coverage_texels = 4096;
    options.deferred_regions = 65535u * 64u + 1u;
    CHECK(penumbra::test::contains(
        penumbra::test::errorOf([&] { penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp); }),
        "deferred_regions = 4194241"));
    options.deferred_regions = 0;
    // A binding past the driver's limit is named at construction (with deferral off, the deferred
    // passes' bindings are not used).
    penumbra::SbsBindings far_bindings;
    far_bindings.fragments = uint32_t(penumbra::gl::getInteger(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS));
    CHECK(penumbra::test::contains(penumbra::test::errorOf([&] {
                                       penumbra::SampleBasedSoftShadows p(options, sets, &seed_lut, influence, vp,
                                                                          penumbra::ShaderLibrary::embedded(), far_bindings);
                                   }),
                                   "PENUMBRA_SBS_FRAGMENTS_BINDING = "));
    options.deferred_pairs = 0;
    CHECK_NOTHROW(penumbra::SampleBasedSoftShadows(options, sets, &seed_lut, influence, vp, penumbra::ShaderLibrary::embedded(),
                                                   far_bindings));
    penumbra::SampleBasedSoftShadows pipeline(options, sets, &seed_lut, influence, vp);
    const penumbra::gl::Buffer positions(16 * 4);
    const penumbra::SampleBufferInput input{{positions.id(), 0, positions.size()}, {}};
    const penumbra::gl::Buffer table(seed_lut.tableBytes());
    const penumbra::BufferRange lut_table{table.id(), 0, table.size()};
    auto draw = [](penumbra::CasterClass) {};
#ifdef NDEBUG
    CHECK(pipeline.run(input, 4, lut_table, draw) == Status::NotReserved);
    pipeline.reserve(4);
    CHECK(pipeline.run(input, 4, lut_table.sub(0, 16), draw) == Status::RangeTooSmall);
    CHECK(pipeline.run(input, 4, lut_table, {}) == Status::InvalidArgument);
#else
    pipeline.reserve(4);
#endif
    CHECK(pipeline.run(input, 4, lut_table, draw) == Status::Ok);
    // SoftSkips::silhouettes needs the casters with adjacency: a run without its callback is refused.
    options.skips.silhouettes = true;
    penumbra::SampleBasedSoftShadows silhouettes(options, sets, &seed_lut, influence, vp);
    silhouettes.reserve(4);
#ifdef NDEBUG
    CHECK(silhouettes.run(input, 4, lut_table, draw) == Status::InvalidArgument);
#endif
    CHECK(silhouettes.run(input, 4, lut_table, draw, {}, [] {}) == Status::Ok);
}

TEST_CASE("GPU sample-based soft: G-buffer view samples, exact == oracle, multi-pass == one pass, per-frame contract") {
    penumbra::test::context();
    const penumbra::scene::Scene scene = penumbra::scene::torusKnot(24);
    const penumbra::scene::GpuScene gpu(scene);
    penumbra::scene::GBuffer gbuffer(96, 72);
    const glm::mat4 camera = scene.camera.projection(96.0f / 72.0f) * scene.camera.view();
    gbuffer.render(gpu, camera);
    const std::vector<glm::vec4> positions = gbuffer.positionBuffer().download<glm::vec4>();
    const uint32_t count = 96 * 72;
    REQUIRE(positions.size() >= count);
    const auto [lo, hi] = penumbra::viewSampleBounds(positions.data(), count);
    const glm::mat4 vp = penumbra::lightViewProjectionForBounds(glm::vec4(scene.light.position, 1.0f), lo, hi);
    double far_depth = 0.0;
    std::vector<dvec3> receivers;
    std::vector<uint32_t> ids;
    for (uint32_t i = 0; i < count; ++i) {
        if (positions[i].w == 0.0f) continue;
        far_depth = std::max(far_depth, double((vp * glm::vec4(glm::vec3(positions[i]), 1.0f)).w));
        receivers.push_back(dvec3(glm::vec3(positions[i])));
        ids.push_back(i);
    }
    REQUIRE(!receivers.empty());
    penumbra::Light light;
    light.center = dvec3(scene.light.position);
    light.size = dvec3(double(scene.light.radius));
    const penumbra::LightSampleSets sets = sphereSets(light.center, double(scene.light.radius), 128, 1, 5);
    const CertifiedLut certified(sets, 64);
    const penumbra::LightLutSetup& lut = certified.lut;
    const penumbra::BufferRange lut_table = certified.table();
    penumbra::InfluenceRegionOptions io;
    io.grid_width = io.grid_height = 64;
    io.far_plane = penumbra::influenceFarPlaneAtDepth(vp, far_depth * 1.01 + 1e-3);
    const penumbra::InfluenceRegionSetup influence = penumbra::influenceRegionSetup(light, vp, io);
    const penumbra::SampleBufferInput input{{gbuffer.positionBuffer().id(), 0, gbuffer.positionBuffer().size()}, {}};
    const penumbra::SampleBasedSoftShadows::DrawCasters draw = [&](penumbra::CasterClass c) {
        gpu.drawClass(c == penumbra::CasterClass::Closed);
    };  // built once, outside the frame

    std::vector<uint32_t> reference_masks;
    for (const uint32_t list_block : {16u, 2u}) {
        INFO("list_block " << list_block);
        penumbra::SampleBasedSoftGpuOptions options;
        options.grid_width = options.grid_height = 64;
        options.list_block = list_block;
        options.max_list_blocks = 256;
        options.timings = true;
        penumbra::SampleBasedSoftShadows pipeline(options, sets, &lut, influence, vp);
        pipeline.reserve(count);
        pipeline.validate(input, count, lut_table);
        REQUIRE(pipeline.run(input, count, lut_table, draw) == Status::Ok);
        const std::vector<uint32_t> masks = pipeline.readMasks();
        const std::vector<float> visibility = pipeline.readVisibility();
        const penumbra::SampleBasedSoftFrame f = pipeline.readFrame();
        if (reference_masks.empty()) {
            const penumbra::scene::Mesh merged = scene.merged();
            const penumbra::reference::VisibilityOracle oracle(merged.positions, merged.indices);
            const penumbra::reference::VisibilityResult truth =
                oracle.evaluate(receivers, std::vector<dvec3>(sets.worldSet(0), sets.worldSet(0) + 128));
            uint64_t mismatched = 0, ties = 0, untested = 0, blocked = 0, background_ok = 0;
            for (size_t r = 0; r < ids.size(); ++r) {
                if (visibility[ids[r]] < 0.0f) {
                    ++untested;
                    continue;
                }
                blocked += truth.blockedCount(r);
                for (uint32_t s = 0; s < 128; ++s) {
                    if (truth.isTie(r, s)) {
                        ++ties;
                        continue;
                    }
                    mismatched += bitOf(masks, 4, ids[r], s) != truth.isBlocked(r, s);
                }
            }
            for (uint32_t i = 0; i < count; ++i)
                background_ok += positions[i].w == 0.0f && visibility[i] == float(PENUMBRA_SBS_VISIBILITY_NO_SAMPLE);
            MESSAGE("G-buffer 96x72, N=128: ", receivers.size(), " samples, ", blocked, " blocked bits, ", ties, " ties, mismatched ",
                    mismatched, ", untested ", untested, "; passes ", f.passes, ", uncertain ",
                    double(f.uncertain_bits) / double(std::max<uint64_t>(f.pairs * 128, 1)), " of pair bits");
            CHECK(blocked > 0);
            CHECK(mismatched == 0);
            CHECK(untested == 0);
            CHECK(background_ok == count - receivers.size());
            reference_masks = masks;
        } else {
            MESSAGE("list_block 2: ", f.passes, " passes (max list ", f.statistics.max_list_length, ")");
        }
        // Plumbing only: llvmpipe's GL_TIME_ELAPSED values are not usable (benchmarks/scan_bench.cpp).
        MESSAGE("list_block ", list_block, " GPU timer ms (meaningless on llvmpipe): lists ", f.lists_ns * 1e-6, ", light pass ",
                f.light_pass_ns * 1e-6, ", resolve ", f.resolve_ns * 1e-6);
        if (list_block == 2) {
            CHECK(f.passes > 1);
            CHECK(f.overflow == 0);
            CHECK(masks == reference_masks);
        }
        // Per-frame contract (docs/design.md convention 2): after warm-up, no query, error check,
        // read-back, map, wait or allocation.
        glFinish();
        Status status = Status::Ok;
        const size_t calls = penumbra::test::checkPerFrameContract([&] { status = pipeline.run(input, count, lut_table, draw); });
        CHECK(status == Status::Ok);
        MESSAGE("run: ", calls, " GL calls under the per-frame audit");
        glBindBuffer(0xDEADu, 0);  // an engine's queued error survives run()
        pipeline.run(input, count, lut_table, draw);
        CHECK(glGetError() == GL_INVALID_ENUM);
    }
}

TEST_CASE("GPU sample-based soft: depth-reconstructed view samples, exact == oracle on the positions the GPU used") {
    penumbra::test::context();
    // Depth reconstruction moves samples by ~1e-5 relative: GlWorld pads the light's box so every
    // one is inside.
    const penumbra::test::GlWorld w(penumbra::scene::columns(4));
    const penumbra::test::GlSoftLight soft(w, 64);
    const penumbra::scene::Scene& scene = w.scene;
    const penumbra::scene::GpuScene& gpu = w.gpu;
    const uint32_t count = w.samples();
    const glm::mat4 vp = w.light.view_projection;
    const penumbra::LightSampleSets& sets = soft.sets;
    const penumbra::LightLutSetup& lut = soft.lut;
    const penumbra::BufferRange lut_table = soft.table();
    const penumbra::InfluenceRegionSetup& influence = soft.influence;
    const penumbra::SampleDepthInput input{w.gbuffer.depthTexture(), 0, w.view};
    penumbra::SampleBasedSoftGpuOptions options;
    options.grid_width = options.grid_height = 64;
    options.max_list_blocks = 256;
    penumbra::SampleBasedSoftShadows pipeline(options, sets, &lut, influence, vp);
    pipeline.reserve(count);
    pipeline.validate(input, lut_table);
    REQUIRE(pipeline.run(input, lut_table, [&](penumbra::CasterClass c) { gpu.drawClass(c == penumbra::CasterClass::Closed); }) == Status::Ok);
    const std::vector<uint32_t> masks = pipeline.readMasks();
    const std::vector<float> visibility = pipeline.readVisibility();
    const penumbra::SampleBasedSoftFrame f = pipeline.readFrame();
    // The positions the GPU reconstructed and tested: the lists' slots.
    const penumbra::SampleListsBuffers lists = pipeline.buffers();
    const uint32_t listed = f.statistics.accepted;
    REQUIRE(listed > 0);
    std::vector<glm::vec4> slot_positions(listed);
    std::vector<uint32_t> slot_ids(listed);
    glGetNamedBufferSubData(lists.list_positions.buffer, 0, GLsizeiptr(listed) * 16, slot_positions.data());
    glGetNamedBufferSubData(lists.list_ids.buffer, 0, GLsizeiptr(listed) * 4, slot_ids.data());
    std::vector<dvec3> receivers;
    for (const auto& p : slot_positions) receivers.push_back(dvec3(glm::vec3(p)));
    const penumbra::scene::Mesh merged = scene.merged();
    const penumbra::reference::VisibilityOracle oracle(merged.positions, merged.indices);
    const penumbra::reference::VisibilityResult truth =
        oracle.evaluate(receivers, std::vector<dvec3>(sets.worldSet(0), sets.worldSet(0) + 128));
    uint64_t mismatched = 0, ties = 0, blocked = 0, untested = 0;
    for (uint32_t r = 0; r < listed; ++r) {
        const uint32_t id = slot_ids[r];
        if (visibility[id] < 0.0f) {
            ++untested;
            continue;
        }
        blocked += truth.blockedCount(r);
        for (uint32_t s = 0; s < 128; ++s) {
            if (truth.isTie(r, s)) {
                ++ties;
                continue;
            }
            mismatched += bitOf(masks, 4, id, s) != truth.isBlocked(r, s);
        }
    }
    uint32_t rejected_not_background = 0;
    for (uint32_t reason = 1; reason < f.statistics.rejected.size(); ++reason) rejected_not_background += f.statistics.rejected[reason];
    MESSAGE("depth input 96x72 columns, N=128: ", listed, " listed samples (", rejected_not_background,
            " rejected other than background), ", blocked, " blocked bits, ", ties, " ties, mismatched ", mismatched,
            ", untested ", untested, "; passes ", f.passes, ", uncertain ",
            double(f.uncertain_bits) / double(std::max<uint64_t>(f.pairs * 128, 1)), " of pair bits, unproven pairs ",
            f.pairs_unproven, " of ", f.pairs);
    CHECK(blocked > 0);
    CHECK(mismatched == 0);
    CHECK(untested == 0);
    CHECK(rejected_not_background == 0);
}

TEST_CASE("SoftSkips::empty_blocks: the occupancy stencil changes no bit and no counter, past its 255 blocks too") {
    penumbra::test::context();
    // A 16 x 16 light grid and 4 samples per list block: the longest lists need hundreds of
    // blocks, so the light pass runs blocks the 8-bit stencil cannot count (drawn without it).
    const penumbra::test::GlWorld w(penumbra::scene::columns(4));
    const penumbra::test::GlSoftLight soft(w, 32, 16, 32);
    const penumbra::BufferRange lut_table = soft.table();
    const penumbra::SampleDepthInput input{w.gbuffer.depthTexture(), 0, w.view};
    std::vector<uint32_t> masks[2];
    penumbra::SampleBasedSoftFrame frames[2];
    for (int skip = 0; skip < 2; ++skip) {
        penumbra::SampleBasedSoftGpuOptions options;
        options.grid_width = options.grid_height = 16;
        options.list_block = 4;
        options.max_list_blocks = 4096;
        options.skips.empty_blocks = skip == 1;
        options.coverage_texels = 0;  // every region drawn: the stencil's own culls (the coverage pass emulates them)
        penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
        pipeline.reserve(w.samples());
        pipeline.validate(input, lut_table);
        REQUIRE(pipeline.run(input, lut_table, [&](penumbra::CasterClass c) {
            w.gpu.drawClass(c == penumbra::CasterClass::Closed);
        }) == Status::Ok);
        masks[skip] = pipeline.readMasks();
        frames[skip] = pipeline.readFrame();
    }
    const penumbra::SampleBasedSoftFrame& on = frames[1];
    const penumbra::SampleBasedSoftFrame& off = frames[0];
    MESSAGE("passes ", on.passes, " (max list ", on.statistics.max_list_length, "), fragments ", on.fragments, ", skipped ",
            on.fragments_skipped, " (off: ", off.fragments_skipped, "), pairs ", on.pairs);
    CHECK(on.passes > 255);
    CHECK(on.overflow == 0);
    CHECK(std::count_if(masks[1].begin(), masks[1].end(), [](uint32_t m) { return m != 0u; }) > 0);
    CHECK(masks[1] == masks[0]);
    // The stencil culls the empty blocks' fragments before shading, and in the closed casters'
    // second pass the texels without a flagged receiver (near_stencil.frag.glsl); count_work draws
    // them once more.
    CHECK(on.fragments == off.fragments);
    CHECK(on.fragments_skipped > 0);
    CHECK(on.fragments_skipped > off.fragments_skipped);  // off: only the closed casters' second pass skips
    CHECK(on.pairs == off.pairs);
    CHECK(on.exact_tests == off.exact_tests);
    CHECK(on.triangles_culled == off.triangles_culled);
    CHECK(on.pairs_front == off.pairs_front);
}

TEST_CASE("SoftSkips::closed_casters: the second pass's predicates (count_work off) change no bit, needed or not") {
    penumbra::test::context();
    // With count_work off, the closed casters' second pass draws list block b only when an
    // occlusion query finds a texel whose block b holds a sample flagged near a kept closed
    // triangle. G-buffer positions (on the surfaces, up to rounding) with a wide coplanar reach
    // flag many samples; depth-reconstructed ones at the oracle's default flag none, and then
    // the pass draws nothing. Masks against count_work on (the pass drawn whole) and against
    // closed_casters off.
    for (const bool surface : {true, false}) {
        CAPTURE(surface);
        const penumbra::test::GlWorld w(penumbra::scene::builtin("torus_knot"));
        const penumbra::test::GlSoftLight soft(w, 64, 128, 128);
        const penumbra::BufferRange table = soft.table();
        const auto run = [&](bool count_work, bool closed, penumbra::SampleBasedSoftFrame* frame) {
            penumbra::SampleBasedSoftGpuOptions options;
            options.grid_width = options.grid_height = 128;
            options.list_block = 4;  // several list blocks
            options.count_work = count_work;
            options.skips.closed_casters = closed;
            if (surface) options.oracle.coplanar_epsilon = 1e-5;
            penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
            pipeline.reserve(w.samples());
            const auto draw = [&](penumbra::CasterClass c) { w.drawClass(c); };
            if (surface) {
                pipeline.validate(w.bufferInput(), w.samples(), table);
                REQUIRE(pipeline.run(w.bufferInput(), w.samples(), table, draw) == Status::Ok);
            } else {
                pipeline.validate(w.depthInput(), table);
                REQUIRE(pipeline.run(w.depthInput(), table, draw) == Status::Ok);
            }
            *frame = pipeline.readFrame();
            penumbra::gl::checkErrors("closed casters' predicates");
            return pipeline.readMasks();
        };
        penumbra::SampleBasedSoftFrame counted, quiet, open;
        const std::vector<uint32_t> counted_masks = run(true, true, &counted);
        const std::vector<uint32_t> quiet_masks = run(false, true, &quiet);
        const std::vector<uint32_t> open_masks = run(true, false, &open);
        MESSAGE(std::string(surface ? "G-buffer positions" : "depth input"), ": passes ", counted.passes, ", triangles culled ",
                counted.triangles_culled, ", pairs recovered ", counted.pairs_recovered);
        CHECK(counted.passes > 1);
        CHECK(counted.triangles_culled > 0);
        if (surface) {
            CHECK(counted.pairs_recovered > 0);
        } else {
            CHECK(counted.pairs_recovered == 0);
        }
        CHECK(std::count_if(counted_masks.begin(), counted_masks.end(), [](uint32_t m) { return m != 0u; }) > 0);
        CHECK(quiet_masks == counted_masks);
        CHECK(open_masks == counted_masks);
    }
}

TEST_CASE("SoftSkips::closed_casters: a culled face's bits through the second pass, count_work off too") {
    penumbra::test::context();
    // The CPU twin's tall-box case (sample_based_soft_test.cpp, skipsCoplanarReachCases): receivers
    // just below a closed box's bottom edge, within the coplanar reach of the light-facing side x = 0
    // (its far vertices make the reach large). The oracle ignores that side and counts the bottom
    // face the segment enters through, which faces away from the light: culled in the first pass,
    // these bits come only from the second. The second pass's predicates must let it through.
    penumbra::scene::Mesh box;
    const glm::vec3 lo(-1.0f, 0.0f, 0.0f), hi(0.0f, 1.0f, 10.0f), centre = 0.5f * (lo + hi);
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            glm::vec3 corner[4];
            for (int k = 0; k < 4; ++k) {
                corner[k][axis] = side ? hi[axis] : lo[axis];
                corner[k][u] = (k == 1 || k == 2) ? hi[u] : lo[u];
                corner[k][v] = (k >= 2) ? hi[v] : lo[v];
            }
            const glm::vec3 n = glm::cross(corner[1] - corner[0], corner[2] - corner[0]);
            const bool flip = glm::dot(n, corner[0] - centre) < 0.0f;  // outward: (v1 - v0) x (v2 - v0)
            const uint32_t base = uint32_t(box.positions.size());
            box.positions.insert(box.positions.end(), corner, corner + 4);
            const uint32_t quad[6] = {0, 1, 2, 0, 2, 3};
            for (int k = 0; k < 6; k += 3)
                for (int j = 0; j < 3; ++j) box.indices.push_back(base + quad[k + (flip ? 2 - j : j)]);
        }
    const GpuMesh gpu_box(box);
    const std::vector<glm::vec3> points = {{-3e-9f, 0.5f, -3e-9f}, {-5e-9f, 0.5f, -5e-9f}, {-6e-9f, 0.25f, -5e-9f}};
    const uint32_t n = 64;
    penumbra::Light light;
    light.center = dvec3(0.3, 0.5, 0.6);
    light.size = dvec3(0.05);
    const penumbra::LightSampleSets sets = sphereSets(light.center, 0.05, n, 1, 5);
    const CertifiedLut certified(sets, 32);
    const penumbra::LightLutSetup& lut = certified.lut;
    const penumbra::BufferRange lut_table = certified.table();
    // The light grid over the receivers, grown by 0.01 (they lie on its box otherwise).
    const ReceiverGrid receiver_grid = receiverGrid(points, light, 16, 0.01f);
    const glm::mat4& vp = receiver_grid.vp;
    const penumbra::InfluenceRegionSetup& influence = receiver_grid.influence;
    std::vector<glm::vec4> positions4;
    for (const auto& p : points) positions4.emplace_back(p, 1.0f);
    const penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(positions4);
    const penumbra::SampleBufferInput input{{positions.id(), 0, positions.size()}, {}};
    const uint32_t count = uint32_t(points.size());

    std::vector<dvec3> receivers(points.begin(), points.end());
    std::vector<dvec3> box_d(box.positions.begin(), box.positions.end());
    const penumbra::reference::VisibilityOracle oracle(box_d, box.indices);
    const penumbra::reference::VisibilityResult truth =
        oracle.evaluate(receivers, std::vector<dvec3>(sets.worldSet(0), sets.worldSet(0) + n));
    for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Brute}) {
        for (const bool count_work : {true, false}) {
            CAPTURE(std::string(penumbra::softModeName(mode)));
            CAPTURE(count_work);
            penumbra::SampleBasedSoftGpuOptions options;
            options.mode = mode;
            options.grid_width = options.grid_height = 16;
            options.count_work = count_work;
            const bool brute = mode == penumbra::SoftMode::Brute;
            penumbra::SampleBasedSoftShadows pipeline(options, sets, brute ? nullptr : &lut, influence, vp);
            pipeline.reserve(count);
            const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : lut_table;
            pipeline.validate(input, count, table);
            REQUIRE(pipeline.run(input, count, table, [&](penumbra::CasterClass c) {
                if (c == penumbra::CasterClass::Closed) gpu_box.draw();
            }) == Status::Ok);
            const std::vector<uint32_t> masks = pipeline.readMasks();
            const std::vector<float> visibility = pipeline.readVisibility();
            const penumbra::SampleBasedSoftFrame f = pipeline.readFrame();
            penumbra::gl::checkErrors("culled face");
            const Tally t = compareOracle(masks, (n + 31) / 32, visibility, truth);
            uint64_t blocked = 0, gpu_blocked = 0;
            for (size_t r = 0; r < count; ++r) {
                blocked += truth.blockedCount(r);
                for (uint32_t s = 0; s < n; ++s) gpu_blocked += bitOf(masks, (n + 31) / 32, r, s);
            }
            MESSAGE(std::string(penumbra::softModeName(mode)), ", count_work ", count_work, ": ", blocked, " blocked bits (oracle), ",
                    gpu_blocked, " (GPU), mismatched ", t.mismatched, ", ties ", t.ties, "; triangles culled ", f.triangles_culled,
                    ", pairs recovered ", f.pairs_recovered);
            CHECK(blocked > 0);
            CHECK(gpu_blocked > 0);  // the bottom face's: lost if the second pass were skipped
            CHECK(t.untested == 0);
            CHECK(t.mismatched == 0);
            if (count_work) {
                CHECK(f.triangles_culled > 0);
                CHECK(f.pairs_recovered > 0);
            }
        }
    }
}

TEST_CASE("SoftSkips::silhouettes: one test from the light centre outside every silhouette's region, in every mode") {
    penumbra::test::context();
    // A small light and a fine grid: most pairs lie outside every potential silhouette's region
    // (the one-test path, which shares the exact-test site with the uncertain bits).
    penumbra::scene::Scene scene = penumbra::scene::builtin("torus_knot");
    scene.light.radius = 0.02f;
    const penumbra::test::GlWorld w(std::move(scene));
    const uint32_t n = 128, words = n / 32;
    const penumbra::test::GlSoftLight soft(w, 64, 512, n);
    const penumbra::BufferRange lut_table = soft.table();
    const penumbra::SampleDepthInput input = w.depthInput();
    const auto run = [&](penumbra::SoftMode mode, bool silhouettes, penumbra::SampleBasedSoftFrame* frame) {
        penumbra::SampleBasedSoftGpuOptions options;
        options.mode = mode;
        options.grid_width = options.grid_height = 512;
        options.skips.silhouettes = silhouettes;
        const bool brute = mode == penumbra::SoftMode::Brute;
        penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, brute ? nullptr : &soft.lut, soft.influence,
                                                  w.light.view_projection);
        pipeline.reserve(w.samples());
        const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : lut_table;
        pipeline.validate(input, table);
        REQUIRE(pipeline.run(input, table, [&](penumbra::CasterClass c) { w.drawClass(c); }, {},
                             [&] { w.gpu.drawAdjacency(); }) == Status::Ok);
        if (frame) *frame = pipeline.readFrame();
        return pipeline.readMasks();
    };
    const auto allOrNothing = [&](const std::vector<uint32_t>& m, size_t s) {
        const bool first = (m[s * words] & 1u) != 0u;
        for (uint32_t k = 0; k < words; ++k)
            if (m[s * words + k] != (first ? 0xFFFFFFFFu : 0u)) return false;
        return true;
    };
    std::vector<uint32_t> exact_off;
    for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Brute, penumbra::SoftMode::Lut}) {
        const std::string name = penumbra::softModeName(mode);
        CAPTURE(name);
        penumbra::SampleBasedSoftFrame on;
        const std::vector<uint32_t> off_masks = run(mode, false, nullptr);
        const std::vector<uint32_t> on_masks = run(mode, true, &on);
        REQUIRE(on_masks.size() == off_masks.size());
        const size_t samples = on_masks.size() / words;
        size_t differ = 0, hard_full = 0;
        if (mode == penumbra::SoftMode::Exact) exact_off = off_masks;
        for (size_t s = 0; s < samples; ++s) {
            const bool same = std::equal(on_masks.begin() + s * words, on_masks.begin() + (s + 1) * words,
                                         off_masks.begin() + s * words);
            if (!same) ++differ;
            if (allOrNothing(on_masks, s) && on_masks[s * words] != 0u) ++hard_full;
            if (mode == penumbra::SoftMode::Lut && !same) {
                // Lut is approximate; a sample the skip moved took the centre's verdict, which is the
                // oracle's (Exact's) and all or nothing there.
                CHECK(allOrNothing(on_masks, s));
                CHECK(std::equal(on_masks.begin() + s * words, on_masks.begin() + (s + 1) * words,
                                 exact_off.begin() + s * words));
            }
        }
        MESSAGE(name, ": pairs ", on.pairs, ", one-test pairs ", on.pairs_hard, ", exact tests ",
                on.exact_tests, ", fully shadowed samples ", hard_full, ", samples differing from the skip off ", differ);
        CHECK(on.pairs_hard > on.pairs / 10);  // the one-test path is exercised (17 % on llvmpipe)
        CHECK(hard_full > 0);
        if (mode != penumbra::SoftMode::Lut) CHECK(differ == 0);
    }
}

TEST_CASE("SoftSkips::silhouettes: the GPU's texel marks == the CPU twin's (sampleBasedSoftSilhouetteMarks)") {
    penumbra::test::context();
    struct Case {
        const char* scene;
        float light_radius;  // 0: the scene's
        uint32_t grid;
    };
    for (const Case c : {Case{"torus_knot", 0.02f, 512}, Case{"columns", 0.0f, 128}, Case{"torus_knot", 0.0f, 256}}) {
        penumbra::scene::Scene scene = penumbra::scene::builtin(c.scene);
        if (c.light_radius > 0.0f) scene.light.radius = c.light_radius;
        const penumbra::test::GlWorld w(std::move(scene));
        const penumbra::test::GlSoftLight soft(w, 32, c.grid, 128);
        const penumbra::BufferRange lut_table = soft.table();
        const penumbra::SampleDepthInput input = w.depthInput();
        penumbra::SampleBasedSoftGpuOptions options;
        options.grid_width = options.grid_height = c.grid;
        options.skips.silhouettes = true;
        penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
        pipeline.reserve(w.samples());
        pipeline.validate(input, lut_table);
        REQUIRE(pipeline.run(input, lut_table, [&](penumbra::CasterClass cls) { w.drawClass(cls); }, {},
                             [&] { w.gpu.drawAdjacency(); }) == Status::Ok);
        const std::vector<uint32_t> gpu = pipeline.readMarks();
        const std::vector<glm::vec3>& positions = w.gpu.positions();
        const std::vector<uint32_t> adjacency =
            penumbra::triangleAdjacency(positions.data(), positions.size(), w.gpu.indices().data(), w.gpu.indices().size());
        const penumbra::SilhouetteMarksCpu twin = penumbra::sampleBasedSoftSilhouetteMarks(
            positions.data(), positions.size(), adjacency.data(), adjacency.size() / 6, soft.sets.frame, soft.influence);
        REQUIRE(gpu.size() == twin.marks.size());
        size_t marked = 0, uncertain = 0, gpu_marked = 0, missed = 0, extra = 0;
        for (size_t i = 0; i < gpu.size(); ++i) {
            marked += twin.marks[i];
            uncertain += twin.uncertain[i];
            // Bit 0: the silhouettes' regions (the twin's); bit 1: the coplanar rule's texels.
            gpu_marked += (gpu[i] & 1u) != 0u;
            if (twin.uncertain[i]) continue;
            if (twin.marks[i] && (gpu[i] & 1u) == 0u) ++missed;
            if (!twin.marks[i] && (gpu[i] & 1u) != 0u) ++extra;
        }
        MESSAGE(std::string(c.scene), " (light radius ", w.scene.light.radius, ", grid ", c.grid, "): edges ", twin.edges, ", potential silhouettes ",
                twin.potential, ", regions ", twin.emitted, "; texels marked by the twin ", marked, " (+", uncertain,
                " within 1/256 px of a boundary), by the GPU ", gpu_marked, "; twin-marked texels the GPU left ", missed,
                ", GPU-marked texels the twin did not mark ", extra);
        CHECK(twin.emitted > 0);
        CHECK(marked > 0);
        CHECK(marked < gpu.size());  // some texel lies outside every region
        CHECK(missed == 0);
        CHECK(extra == 0);
    }
}

// SoftSkips::silhouettes under a grazing light (8, 0.02, 0.5), radius 0.01, over the ground's two
// triangles, and a light whose bottom nearly touches the ground's plane, on the demo's fitted grid
// (issue 41, item 1: 159 bits moved at 128 x 96). Depth-rebuilt view samples lie within the
// oracle's coplanar reach of the ground, some just below it: the oracle ignores their own
// triangle and counts the other one, so their segments change verdict where they cross the
// diagonal, which is no silhouette. The coplanar rule's texels (bit 1 of the marks) take the full
// test: no bit of exact or brute moves.
TEST_CASE("SoftSkips::silhouettes: grazing and near-plane lights on a fitted grid change no bit of exact or brute") {
    penumbra::test::context();
    struct Light {
        const char* what;
        glm::vec3 position;
        float radius;
    };
    size_t coplanar_texels = 0;
    for (const Light c : {Light{"grazing", {8.0f, 0.02f, 0.5f}, 0.01f}, Light{"near-plane", {8.0f, 0.0175f, 0.5f}, 0.01f}}) {
        penumbra::scene::Scene scene = penumbra::scene::builtin("torus_knot");
        scene.light.position = c.position;
        scene.light.radius = c.radius;
        const penumbra::test::GlWorld w(std::move(scene));
        // The demo's grid: the §4.3 fit of the view samples, its far plane 1 % beyond the farthest.
        const std::vector<glm::vec4> positions = w.gbuffer.positionBuffer().download<glm::vec4>();
        penumbra::SampleListsOptions fit_options;
        fit_options.cull_back_facing = false;
        fit_options.depth_range = penumbra::LightDepthRange::Unclipped;
        // The sanitizer build: the 128^2 grid only (the host code is the same at 256^2).
        for (const uint32_t grid : penumbra::test::kSanitized ? std::vector<uint32_t>{128u} : std::vector<uint32_t>{128u, 256u}) {
            const penumbra::LightFrustumFit fit = penumbra::fitLightFrustumCpu(
                penumbra::sampleListsSetup(grid, grid, w.samples()), w.light, positions.data(), nullptr, fit_options);
            REQUIRE(fit.valid);
            const glm::mat4 vp = fit.view_projection;
            double far_depth = 0.0;
            for (const glm::vec4& q : positions)
                if (q.w != 0.0f) far_depth = std::max(far_depth, double((vp * glm::vec4(glm::vec3(q), 1.0f)).w));
            const penumbra::LightSampleSets sets = sphereSets(dvec3(c.position), double(c.radius), 128, 1, 7);
            const CertifiedLut lut(sets, 32);
            penumbra::InfluenceRegionOptions io;
            io.grid_width = io.grid_height = int(grid);
            io.far_plane = penumbra::influenceFarPlaneAtDepth(vp, far_depth * 1.01 + 1e-3);
            const penumbra::InfluenceRegionSetup influence = penumbra::influenceRegionSetup(
                [&] {
                    penumbra::Light l;
                    l.center = dvec3(c.position);
                    l.size = dvec3(double(c.radius));
                    return l;
                }(),
                vp, io);
            const penumbra::SampleDepthInput input = w.depthInput();
            for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Brute}) {
                const bool brute = mode == penumbra::SoftMode::Brute;
                const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : lut.table();
                std::vector<uint32_t> masks[2], marks;
                for (int on = 0; on < 2; ++on) {
                    penumbra::SampleBasedSoftGpuOptions options;
                    options.mode = mode;
                    options.grid_width = options.grid_height = grid;
                    options.oracle.coplanar_epsilon = 2e-5;  // the demo's for depth-rebuilt samples
                    options.skips.silhouettes = on != 0;
                    penumbra::SampleBasedSoftShadows pipeline(options, sets, brute ? nullptr : &lut.lut, influence, vp);
                    pipeline.reserve(w.samples());
                    pipeline.validate(input, table);
                    REQUIRE(pipeline.run(input, table, [&](penumbra::CasterClass cls) { w.drawClass(cls); }, {},
                                         [&] { w.gpu.drawAdjacency(); }) == Status::Ok);
                    masks[on] = pipeline.readMasks();
                    if (on) marks = pipeline.readMarks();
                }
                REQUIRE(masks[0].size() == masks[1].size());
                size_t moved = 0;
                for (size_t i = 0; i < masks[0].size(); ++i) moved += masks[0][i] != masks[1][i];
                size_t coplanar = 0;
                for (const uint32_t m : marks) coplanar += (m & 2u) != 0u;
                coplanar_texels += coplanar;
                MESSAGE(std::string(c.what), " light, grid ", grid, ", ", std::string(penumbra::softModeName(mode)), ": ", moved,
                        " mask words moved by the skip; texels marked by the coplanar rule ", coplanar);
                CHECK(moved == 0);
            }
        }
    }
    CHECK(coplanar_texels > 0);  // the case the rule is for occurs here
}

namespace {

/// One frame of the pipeline on `w`'s depth input, every caster drawn by class and the adjacency
/// draw given (skips.silhouettes): its masks, its counters in `frame`.
std::vector<uint32_t> runFrame(const penumbra::SampleBasedSoftGpuOptions& options, const penumbra::test::GlWorld& w,
                               const penumbra::test::GlSoftLight& soft, const penumbra::SampleDepthInput& input,
                               const penumbra::BufferRange& table, const char* what, penumbra::SampleBasedSoftFrame* frame) {
    const bool brute = options.mode == penumbra::SoftMode::Brute;
    penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, brute ? nullptr : &soft.lut, soft.influence, w.light.view_projection);
    pipeline.reserve(w.samples());
    pipeline.validate(input, table);
    REQUIRE(pipeline.run(input, table, [&](penumbra::CasterClass c) { w.drawClass(c); }, {}, [&] { w.gpu.drawAdjacency(); }) ==
            Status::Ok);
    *frame = pipeline.readFrame();
    penumbra::gl::checkErrors(what);
    return pipeline.readMasks();
}

}  // namespace

TEST_CASE("Deferred pairs: the compute pass gives the fragment stage's bits and counters, past its capacities too") {
    penumbra::test::context();
    // Every skip on (closed casters' second pass included: its pairs are worked after the first
    // pass's), in every mode; capacities large enough for every pair, and small ones: the draws
    // that overflow them are drawn again by the fragment-stage program; pending exact-test words
    // past their buffer are tested in the compute pass's own loop.
    struct Capacity {
        uint32_t pairs, triangles, tests, fragments;
    };
    for (const std::string& name : sweptScenes({"columns", "torus_knot"})) {
        const penumbra::test::GlWorld w(penumbra::scene::builtin(name));
        const uint32_t n = 128;
        const penumbra::test::GlSoftLight soft(w, 64, 128, n);
        const penumbra::SampleDepthInput input = w.depthInput();
        for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Lut, penumbra::SoftMode::Brute}) {
            const std::string mode_name = penumbra::softModeName(mode);
            const bool brute = mode == penumbra::SoftMode::Brute;
            if (brute && name != "columns") continue;  // the same code as Exact's all-exact pairs; slow
            const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : soft.table();
            const auto run = [&](Capacity capacity, penumbra::SampleBasedSoftFrame* frame) {
                penumbra::SampleBasedSoftGpuOptions options;
                options.mode = mode;
                options.grid_width = options.grid_height = 128;
                options.list_block = 8;  // several list blocks: pairs of every block in one dispatch
                options.skips.closed_casters = options.skips.silhouettes = true;
                options.deferred_pairs = capacity.pairs;
                options.deferred_triangles = capacity.triangles;
                options.deferred_tests = capacity.tests;
                options.deferred_fragments = capacity.fragments;
                options.coverage_texels = 0;  // every region drawn, as the fragment-stage program draws them
                return runFrame(options, w, soft, input, table, "deferred pairs", frame);
            };
            penumbra::SampleBasedSoftFrame off;
            const std::vector<uint32_t> off_masks = run({0, 0, 0, 0}, &off);
            CHECK(std::count_if(off_masks.begin(), off_masks.end(), [](uint32_t m) { return m != 0u; }) > 0);
            CHECK(off.pairs_deferred == 0);
            CHECK(off.deferral_fallbacks == 0);
            const uint64_t worked = off.fragments - off.fragments_skipped;  // fragments past the early returns
            uint64_t all_deferred = 0;  // pairs_deferred with every buffer large enough
            // Every buffer large enough; the exact-test words' small (the rest run in the passes that
            // hand them on); the pairs' small (the rest go whole to the fragments buffer, worked a
            // fragment per invocation); the pairs' and the fragments' small, or the triangle slots'
            // (redrawn).
            for (const Capacity capacity :
                 {Capacity{1u << 20, 1u << 18, 1u << 18, 1u << 18}, Capacity{1u << 20, 1u << 18, 8, 1u << 18},
                  Capacity{64, 1u << 18, 0, 1u << 18}, Capacity{64, 1u << 18, 0, 16}, Capacity{1u << 20, 16, 0, 0}}) {
                if (brute && capacity.fragments == 16) break;  // the redraw does not depend on the mode: exact and lut test it
                CAPTURE(name);
                CAPTURE(mode_name);
                CAPTURE(capacity.pairs);
                CAPTURE(capacity.triangles);
                CAPTURE(capacity.tests);
                CAPTURE(capacity.fragments);
                penumbra::SampleBasedSoftFrame on;
                const std::vector<uint32_t> on_masks = run(capacity, &on);
                MESSAGE(name, " ", mode_name, ", capacity ", capacity.pairs, " pairs / ", capacity.triangles, " triangles / ",
                        capacity.tests, " test words / ", capacity.fragments, " fragments: passes ", on.passes, ", fragments ", on.fragments, ", pairs ", on.pairs,
                        ", exact tests ", on.exact_tests, ", recovered ", on.pairs_recovered, "; pairs deferred ",
                        on.pairs_deferred, " (", worked, " fragments past the early returns), fallbacks ",
                        on.deferral_fallbacks);
                CHECK(on.passes > 1);
                if (capacity.fragments >= (1u << 18) && capacity.triangles >= (1u << 18)) {
                    // Every pair in the compute pass: one per view sample of each worked fragment's
                    // list block (at least one, at most list_block) that SoftSkips::wedges keeps;
                    // every pair walked (the cut ones and those past the cut: pairs counts the
                    // ignored too) among them.
                    CHECK(on.pairs_deferred + on.pairs_wedged >= worked);
                    CHECK(on.pairs_deferred + on.pairs_wedged <= 8 * worked);
                    CHECK(on.pairs_deferred >= off.pairs + off.pairs_cut);
                    CHECK(on.deferral_fallbacks == 0);
                    if (capacity.pairs >= (1u << 20)) all_deferred = on.pairs_deferred;
                    // Most by the per-fragment program: the same count (the straddling fragment's
                    // empty pairs below the capacity are not counted, its samples are, once).
                    if (capacity.pairs == 64) CHECK(on.pairs_deferred == all_deferred);
                } else {
                    // The first pass overflows and is drawn again; the second's few pairs fit.
                    CHECK(on.deferral_fallbacks >= 1);
                    CHECK(on.pairs_deferred < off.pairs + off.pairs_cut);
                }
                CHECK(on_masks == off_masks);
                CHECK(on.fragments == off.fragments);
                CHECK(on.fragments_skipped == off.fragments_skipped);
                CHECK(on.pairs == off.pairs);
                CHECK(on.pairs_ignored == off.pairs_ignored);
                CHECK(on.pairs_unproven == off.pairs_unproven);
                CHECK(on.uncertain_bits == off.uncertain_bits);
                CHECK(on.exact_tests == off.exact_tests);
                CHECK(on.planes_unproven == off.planes_unproven);
                CHECK(on.triangles_culled == off.triangles_culled);
                CHECK(on.pairs_cut == off.pairs_cut);
                CHECK(on.pairs_hard == off.pairs_hard);
                CHECK(on.pairs_recovered == off.pairs_recovered);
                CHECK(on.pairs_front == off.pairs_front);
            }
        }
    }
}

TEST_CASE("SoftSkips::wedges: no bit of exact or brute changes, in every tier of the light pass") {
    penumbra::test::context();
    // The geometry stage's wedge planes, tested per view sample by the deferring fragment stage
    // (pairs never appended), by the per-fragment compute pass (fragments past the pairs buffer)
    // and by the fragment-stage program (deferral off): the same bits as wedges off, the same
    // counters in every tier, and every pair accounted for.
    for (const std::string& name : sweptScenes({"columns", "torus_knot"})) {
        const penumbra::test::GlWorld w(penumbra::scene::builtin(name));
        const penumbra::test::GlSoftLight soft(w, 64, 128, 128);
        const penumbra::SampleDepthInput input = w.depthInput();
        for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Lut, penumbra::SoftMode::Brute}) {
            const bool brute = mode == penumbra::SoftMode::Brute;
            if (brute && name != "columns") continue;
            const std::string mode_name = penumbra::softModeName(mode);
            const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : soft.table();
            const auto run = [&](bool wedges, uint32_t pairs, penumbra::SampleBasedSoftFrame* frame) {
                penumbra::SampleBasedSoftGpuOptions options;
                options.mode = mode;
                options.grid_width = options.grid_height = 128;
                options.list_block = 8;
                options.skips.wedges = wedges;
                options.deferred_pairs = pairs;
                options.deferred_fragments = options.deferred_triangles = pairs > 0 ? 1u << 18 : 0u;
                options.coverage_texels = 0;  // every region drawn in every tier (the coverage pass has its own test)
                penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, brute ? nullptr : &soft.lut, soft.influence,
                                                          w.light.view_projection);
                pipeline.reserve(w.samples());
                pipeline.validate(input, table);
                REQUIRE(pipeline.run(input, table, [&](penumbra::CasterClass c) { w.drawClass(c); }) == Status::Ok);
                *frame = pipeline.readFrame();
                penumbra::gl::checkErrors("wedges");
                return pipeline.readMasks();
            };
            penumbra::SampleBasedSoftFrame off;
            const std::vector<uint32_t> off_masks = run(false, 1u << 20, &off);
            CHECK(off.pairs_wedged == 0);
            penumbra::SampleBasedSoftFrame tiers[3];
            std::vector<uint32_t> tier_masks[3];
            const uint32_t capacities[3] = {1u << 20, 64u, 0u};  // pairs buffer; fragments buffer; fragment stage
            for (int t = 0; t < 3; ++t) tier_masks[t] = run(true, capacities[t], &tiers[t]);
            const penumbra::SampleBasedSoftFrame& on = tiers[0];
            uint64_t lut_moved = 0;
            for (size_t i = 0; i < off_masks.size(); ++i) lut_moved += uint64_t(__builtin_popcount(off_masks[i] ^ tier_masks[0][i]));
            MESSAGE(name, " ", mode_name, ": pairs ", off.pairs, " + cut ", off.pairs_cut, " without wedges, ", on.pairs, " + cut ",
                    on.pairs_cut, " + wedged ", on.pairs_wedged, " with; deferred pairs ", off.pairs_deferred, " -> ",
                    on.pairs_deferred, "; bits moved ", lut_moved);
            CHECK(on.pairs_wedged > 0);
            CHECK(on.deferral_fallbacks == 0);
            CHECK(tiers[1].deferral_fallbacks == 0);
            CHECK(on.pairs + on.pairs_cut + on.pairs_wedged == off.pairs + off.pairs_cut);
            CHECK(on.pairs_deferred + on.pairs_wedged <= off.pairs_deferred);
            if (mode != penumbra::SoftMode::Lut) CHECK(tier_masks[0] == off_masks);
            for (int t = 1; t < 3; ++t) {
                CAPTURE(t);
                CHECK(tier_masks[t] == tier_masks[0]);
                CHECK(tiers[t].pairs == on.pairs);
                CHECK(tiers[t].pairs_wedged == on.pairs_wedged);
                CHECK(tiers[t].fragments == on.fragments);
                CHECK(tiers[t].exact_tests == on.exact_tests);
                CHECK(tiers[t].pairs_front == on.pairs_front);
                if (t == 1) CHECK(tiers[t].pairs_deferred == on.pairs_deferred);
            }
        }
    }
}

TEST_CASE("Coverage pass: the drawn regions' bits, a few more pairs, past its records and slots too") {
    penumbra::test::context();
    // SampleBasedSoftGpuOptions::coverage_texels: the regions the geometry stage hands to the
    // coverage pass instead of drawing them (every skip on, closed casters' second pass included)
    // against every region drawn (coverage_texels = 0). The pass visits every texel GL's rule covers
    // and a few more on the boundary (tests/influence_region_test.cpp: the CPU twin against GL's
    // rule), so Exact and Brute keep every bit while the work counters grow a little; Lut's extra
    // pairs may add bits of its approximation (counted). Also: few records (the rest drawn), small
    // boxes only, and too few triangle slots (the draws overflow and are drawn again).
    struct Config {
        uint32_t texels, regions, triangles;
    };
    for (const std::string& name : sweptScenes({"columns", "torus_knot"})) {
        const penumbra::test::GlWorld w(penumbra::scene::builtin(name));
        const penumbra::test::GlSoftLight soft(w, 64, 128, 128);
        const penumbra::SampleDepthInput input = w.depthInput();
        for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Lut, penumbra::SoftMode::Brute}) {
            const bool brute = mode == penumbra::SoftMode::Brute;
            if (brute && name != "columns") continue;
            const std::string mode_name = penumbra::softModeName(mode);
            const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : soft.table();
            const auto run = [&](Config config, penumbra::SampleBasedSoftFrame* frame) {
                penumbra::SampleBasedSoftGpuOptions options;
                options.mode = mode;
                options.grid_width = options.grid_height = 128;
                options.list_block = 8;
                options.skips.closed_casters = options.skips.silhouettes = true;
                options.coverage_texels = config.texels;
                options.deferred_regions = config.regions;
                options.deferred_triangles = config.triangles;
                return runFrame(options, w, soft, input, table, "coverage", frame);
            };
            penumbra::SampleBasedSoftFrame drawn;
            const std::vector<uint32_t> drawn_masks = run({0, 0, 0}, &drawn);
            CHECK(std::count_if(drawn_masks.begin(), drawn_masks.end(), [](uint32_t m) { return m != 0u; }) > 0);
            for (const Config config : {Config{4096, 0, 0}, Config{1u << 20, 0, 0}, Config{4096, 16, 0}, Config{16, 0, 0},
                                        Config{4096, 0, 16}}) {
                CAPTURE(name);
                CAPTURE(mode_name);
                CAPTURE(config.texels);
                CAPTURE(config.regions);
                CAPTURE(config.triangles);
                penumbra::SampleBasedSoftFrame covered;
                const std::vector<uint32_t> masks = run(config, &covered);
                uint64_t moved = 0;
                for (size_t i = 0; i < drawn_masks.size(); ++i) moved += uint64_t(__builtin_popcount(drawn_masks[i] ^ masks[i]));
                MESSAGE(name, " ", mode_name, ", coverage_texels ", config.texels, " / regions ", config.regions, " / triangles ",
                        config.triangles, ": fragments ", covered.fragments, " (drawn ", drawn.fragments, "), pairs ", covered.pairs,
                        " (", drawn.pairs, "), deferred ", covered.pairs_deferred, " (", drawn.pairs_deferred, "), fallbacks ",
                        covered.deferral_fallbacks, ", bits moved ", moved);
                if (mode != penumbra::SoftMode::Lut) CHECK(masks == drawn_masks);
                // A few more texels and pairs, never fewer; none of the skips' work differs in kind.
                CHECK(covered.fragments >= drawn.fragments);
                CHECK(covered.fragments <= drawn.fragments + drawn.fragments / 20);
                CHECK(covered.pairs + covered.pairs_cut + covered.pairs_wedged >= drawn.pairs + drawn.pairs_cut + drawn.pairs_wedged);
                CHECK(covered.pairs <= drawn.pairs + drawn.pairs / 20 + 16);
                CHECK(covered.triangles_culled == drawn.triangles_culled);
                CHECK(covered.overflow == drawn.overflow);
                if (config.triangles == 16) {
                    CHECK(covered.deferral_fallbacks >= 1);  // the slots ran out: drawn again, as without the pass
                    CHECK(masks == drawn_masks);
                } else {
                    CHECK(covered.deferral_fallbacks == 0);
                }
                if (mode == penumbra::SoftMode::Lut) CHECK(moved <= drawn_masks.size() * 32 / 1000);  // at most 0.1 % of the bits
            }
        }
    }
}

TEST_CASE("Coverage pass: the texels it visits are the CPU twin's (influenceCoverageTexels), region by region") {
    penumbra::test::context();
    // Every region to the coverage pass (coverage_texels 2^20 > the 64^2 grid), no skip (no
    // stencil, no culled triangle), one list block: with count_work every texel the pass visits
    // counts as one fragment, so the frame's fragments are the sum over the drawn triangles of the
    // twin's visited texels. Holds where the GPU's influence regions are the CPU's bit for bit
    // (correctly rounded float, llvmpipe: the influence-region block's own test checks that); on
    // other drivers the sum may differ by boundary texels.
    const penumbra::test::GlWorld w(penumbra::scene::builtin("columns"));
    const penumbra::test::GlSoftLight soft(w, 32, 64, 128);
    const penumbra::SampleDepthInput input = w.depthInput();
    penumbra::SampleBasedSoftGpuOptions options;
    options.mode = penumbra::SoftMode::Lut;
    options.grid_width = options.grid_height = 64;
    options.list_block = 4096;
    options.skips.empty_blocks = options.skips.closed_casters = options.skips.plane_cut = false;
    options.skips.silhouettes = options.skips.wedges = false;
    options.coverage_texels = 1u << 20;
    options.deferred_pairs = options.deferred_fragments = 1u << 22;  // no redraw
    options.deferred_triangles = 1u << 16;
    penumbra::SampleBasedSoftFrame frame;
    (void)runFrame(options, w, soft, input, soft.table(), "coverage twin", &frame);
    uint64_t expected = 0, regions = 0;
    const std::vector<glm::vec3>& positions = w.gpu.positions();
    const std::vector<uint32_t>& indices = w.gpu.indices();
    for (size_t t = 0; t + 2 < indices.size(); t += 3) {
        const glm::vec3 a = positions[indices[t]], b = positions[indices[t + 1]], c = positions[indices[t + 2]];
        if (penumbra::detail::degenerateTriangle(glm::dvec3(a), glm::dvec3(b), glm::dvec3(c))) continue;
        const penumbra::InfluenceRegion region = penumbra::influenceRegion(a, b, c, soft.influence);
        if (region.count <= 0) continue;
        ++regions;
        expected += penumbra::influenceCoverageTexels(region, soft.influence).size();
    }
    MESSAGE("columns, 64^2 grid: ", indices.size() / 3, " triangles, ", regions, " regions, ", expected,
            " texels visited by the twin, ", frame.fragments, " fragments counted by the GPU pass; passes ", frame.passes);
    CHECK(frame.passes == 1);
    CHECK(frame.deferral_fallbacks == 0);
    CHECK(regions > 100);
    CHECK(frame.fragments == expected);
}

TEST_CASE("Deferred pairs: a pair's entry unpacks to its triangle slot, list-block index and texel at the options' limits") {
    penumbra::test::context();
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.addDirectory(penumbra::test::testShaderDir());
    const penumbra::gl::Program program = penumbra::gl::buildComputeProgram("sample_based_soft/pair_pack_test.comp.glsl", {}, lib);
    // Slots < 2^24 (deferred_triangles <= 2^24), indices < 4096 (list_block <= 4096), texels < 8192
    // (grid sides <= 8192): every limit, its neighbours, and random values.
    std::vector<glm::uvec4> inputs;
    const uint32_t slots[] = {0u, 1u, 255u, 256u, (1u << 24) - 1u};
    const uint32_t indices[] = {0u, 1u, 255u, 256u, 4095u};
    const uint32_t coords[] = {0u, 1u, 4096u, 8191u};
    for (uint32_t s : slots)
        for (uint32_t i : indices)
            for (uint32_t x : coords)
                for (uint32_t y : coords) inputs.emplace_back(s, i, x, y);
    std::mt19937 rng(penumbra::test::testSeed());
    for (int k = 0; k < 4096; ++k)
        inputs.emplace_back(rng() % (1u << 24), rng() % 4096u, rng() % 8192u, rng() % 8192u);
    const penumbra::gl::Buffer in = penumbra::gl::Buffer::fromVector(inputs);
    const penumbra::gl::Buffer out(inputs.size() * sizeof(glm::uvec4));
    glUseProgram(program.id());
    glUniform1ui(0, static_cast<GLuint>(inputs.size()));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, in.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, out.id());
    glDispatchCompute(static_cast<GLuint>((inputs.size() + 63) / 64), 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    const std::vector<glm::uvec4> unpacked = out.download<glm::uvec4>();
    size_t mismatched = 0;
    for (size_t k = 0; k < inputs.size(); ++k) {
        if (unpacked[k] == inputs[k]) continue;
        if (++mismatched <= 5)
            MESSAGE("in ", inputs[k].x, " ", inputs[k].y, " ", inputs[k].z, " ", inputs[k].w, " -> ", unpacked[k].x, " ",
                    unpacked[k].y, " ", unpacked[k].z, " ", unpacked[k].w);
    }
    CHECK(mismatched == 0);
    penumbra::gl::checkErrors("pair pack test");
}

namespace {

/// SoftLightPass::Compute's masks (and frame) for the world's casters as buffers.
std::vector<uint32_t> runComputeFrame(const penumbra::SampleBasedSoftGpuOptions& options, const penumbra::test::GlWorld& w,
                                      const penumbra::test::GlSoftLight& soft, const std::vector<penumbra::CasterBuffer>& casters,
                                      bool depth, const penumbra::BufferRange& table, penumbra::SampleBasedSoftFrame* frame) {
    const bool brute = options.mode == penumbra::SoftMode::Brute;
    penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, brute ? nullptr : &soft.lut, soft.influence, w.light.view_projection);
    pipeline.reserve(w.samples());
    pipeline.validateCasters(casters.data(), static_cast<uint32_t>(casters.size()));
    const Status s = depth ? pipeline.run(w.depthInput(), table, casters.data(), static_cast<uint32_t>(casters.size()))
                           : pipeline.run(w.bufferInput(), w.samples(), table, casters.data(), static_cast<uint32_t>(casters.size()));
    REQUIRE(s == Status::Ok);
    *frame = pipeline.readFrame();
    penumbra::gl::checkErrors("compute light pass");
    return pipeline.readMasks();
}

}  // namespace

namespace {

// SoftLightPass::Compute (casters as buffers, no draw) against SoftLightPass::Raster (the
// callback; every region drawn: coverage_texels = 0), closed casters' second pass included,
// several list blocks: Exact and Brute word for word; Lut reported. Also small capacities: few
// triangle slots (the host runs the deferred passes between chunks), a pairs buffer that
// overflows into the fragments buffer, and both overflowing (the coverage pass works the pairs
// itself). `full`: every mode, input and capacity on every scene; else Exact on depth input with
// every capacity on the first scene, the default capacities elsewhere, G-buffer input and Lut on
// the first, Brute with both overflowing on columns.
void checkComputeAgainstRaster(const std::vector<std::string>& names, bool full) {
    penumbra::test::context();
    struct Capacity {
        uint32_t pairs, triangles, fragments, windows;
    };
    constexpr uint32_t kTwelfth = 0xFFFFFFFFu;  // fragments: a twelfth of the default run's visits
    for (const std::string& name : names) {
        const bool first = name == names.front();
        const bool obj = name.size() > 4 && name.compare(name.size() - 4, 4, ".obj") == 0;
        const penumbra::test::GlWorld w(obj ? penumbra::scene::loadObj(penumbra::test::sharedScenesDir() + "/" + name)
                                            : penumbra::scene::builtin(name));
        const penumbra::test::GlSoftLight soft(w, 64, 128, 128);
        const std::vector<penumbra::CasterBuffer>& casters = w.gpu.casterBuffers();
        for (const penumbra::SoftMode mode : {penumbra::SoftMode::Exact, penumbra::SoftMode::Lut, penumbra::SoftMode::Brute}) {
            const bool brute = mode == penumbra::SoftMode::Brute;
            if (brute && name != "columns") continue;  // Exact's all-exact pairs' code; slow
            if (!full && mode == penumbra::SoftMode::Lut && !first) continue;
            const std::string mode_name = penumbra::softModeName(mode);
            const penumbra::BufferRange table = brute ? penumbra::BufferRange{} : soft.table();
            for (const bool depth : {true, false}) {
                if (!depth && (mode != penumbra::SoftMode::Exact || (!full && !first))) continue;
                penumbra::SampleBasedSoftGpuOptions options;
                options.mode = mode;
                options.grid_width = options.grid_height = 128;
                options.list_block = 8;
                options.skips.closed_casters = true;
                options.coverage_texels = 0;
                penumbra::SampleBasedSoftFrame raster;
                std::vector<uint32_t> raster_masks;
                {
                    penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, brute ? nullptr : &soft.lut, soft.influence,
                                                              w.light.view_projection);
                    pipeline.reserve(w.samples());
                    const auto draw = [&](penumbra::CasterClass c) { w.drawClass(c); };
                    REQUIRE((depth ? pipeline.run(w.depthInput(), table, draw) : pipeline.run(w.bufferInput(), w.samples(), table, draw)) ==
                            Status::Ok);
                    raster = pipeline.readFrame();
                    raster_masks = pipeline.readMasks();
                }
                CHECK(std::count_if(raster_masks.begin(), raster_masks.end(), [](uint32_t m) { return m != 0u; }) > 0);
                CHECK(raster.chunks == 0);
                options.light_pass = penumbra::SoftLightPass::Compute;
                uint64_t default_chunks = 0, default_fragments = 0;  // with the default capacities (the first run below)
                // Overflows (64 pairs): into 2^20 fragments (none); into a twelfth of the frame's
                // fragments (split into windows on the GPU, none worked inline); into 16 fragments
                // (every window overflows too: inline), without windows (the whole run inline);
                // with few slots too (runs of later list blocks, which no windows follow, inline).
                // 512 slots: a few hundred runs (every host path between chunks; 64 slots took
                // 3 000 runs, 5 min under the sanitizers, for no path more).
                constexpr uint32_t kFewSlots = 512;
                for (const Capacity capacity : {Capacity{0, 0, 0, 8}, Capacity{0, kFewSlots, 0, 8}, Capacity{64, 0, 1u << 20, 8},
                                                Capacity{64, 0, kTwelfth, 64}, Capacity{64, 0, 16, 8}, Capacity{64, 0, 16, 0},
                                                Capacity{64, kFewSlots, 16, 2}}) {
                    if (!depth && capacity.pairs + capacity.triangles != 0) continue;
                    const bool all = capacity.pairs + capacity.triangles + capacity.fragments == 0;
                    if (!full && !all && !(first && mode == penumbra::SoftMode::Exact) &&
                        !(brute && capacity.fragments == 16 && capacity.windows != 0))
                        continue;
                    CAPTURE(name);
                    CAPTURE(mode_name);
                    CAPTURE(depth);
                    CAPTURE(capacity.pairs);
                    CAPTURE(capacity.triangles);
                    CAPTURE(capacity.fragments);
                    CAPTURE(capacity.windows);
                    penumbra::SampleBasedSoftGpuOptions o = options;
                    if (capacity.pairs) o.deferred_pairs = capacity.pairs;
                    o.deferred_triangles = capacity.triangles;
                    o.deferred_fragments = capacity.fragments == kTwelfth ? uint32_t(std::max<uint64_t>(16, default_fragments / 12))
                                                                        : capacity.fragments;
                    o.overflow_windows = capacity.windows;
                    penumbra::SampleBasedSoftFrame computed;
                    const std::vector<uint32_t> masks = runComputeFrame(o, w, soft, casters, depth, table, &computed);
                    uint64_t moved = 0;
                    for (size_t i = 0; i < raster_masks.size(); ++i) moved += uint64_t(__builtin_popcount(raster_masks[i] ^ masks[i]));
                    MESSAGE(name, " ", mode_name, std::string(depth ? " depth" : " g-buffer"), ", pairs ", o.deferred_pairs, " / slots ",
                            capacity.triangles, " / fragments ", o.deferred_fragments, " / windows ", o.overflow_windows,
                            ": fragments ", computed.fragments, " (raster ",
                            raster.fragments, "), pairs ", computed.pairs, " (", raster.pairs, "), fallbacks ",
                            computed.deferral_fallbacks, ", chunks ", computed.chunks, ", bits moved ", moved);
                    if (mode != penumbra::SoftMode::Lut) CHECK(masks == raster_masks);
                    if (mode == penumbra::SoftMode::Lut) CHECK(moved <= raster_masks.size() * 32 / 1000);
                    CHECK(computed.triangles_culled == raster.triangles_culled);
                    CHECK(computed.overflow == raster.overflow);
                    CHECK(computed.caster_indices_out_of_range == 0);
                    // The coverage pass's visits of non-empty blocks: every one the rasteriser
                    // shades, a few more (it neither visits nor counts empty texels).
                    const uint64_t shaded = raster.fragments - raster.fragments_skipped;
                    CHECK(computed.fragments_skipped == 0);
                    CHECK(computed.fragments >= shaded);
                    CHECK(computed.fragments <= shaded + shaded / 20);
                    CHECK((computed.deferral_fallbacks != 0) == (capacity.fragments == 16));
                    // Chunks: at least one run had work; few slots, or windows, split the frame
                    // into more.
                    CHECK(computed.chunks >= 1);
                    if (all) default_chunks = computed.chunks;
                    if (all) default_fragments = computed.fragments;
                    if (capacity.fragments == kTwelfth) CHECK(computed.chunks > default_chunks);
                    if (all && first && mode == penumbra::SoftMode::Exact && depth) {  // counted without count_work too
                        penumbra::SampleBasedSoftGpuOptions quiet = o;
                        quiet.count_work = false;
                        penumbra::SampleBasedSoftFrame uncounted;
                        CHECK(runComputeFrame(quiet, w, soft, casters, depth, table, &uncounted) == masks);
                        CHECK(uncounted.chunks == computed.chunks);
                        CHECK(uncounted.pairs == 0);
                    }
                    if (capacity.triangles != 0) CHECK(computed.chunks > default_chunks);
                }
            }
        }
    }
}

/// The shared OBJ scenes present (file names; none when ../shared is absent).
std::vector<std::string> sharedObjNames() {
    std::vector<std::string> names;
    const std::string dir = penumbra::test::sharedScenesDir();
    if (!std::filesystem::is_directory(dir)) {
        MESSAGE("skipping the shared OBJ scenes: ", dir, " is absent");
        return names;
    }
    for (const auto& e : std::filesystem::directory_iterator(dir))
        if (e.path().extension() == ".obj") names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

TEST_CASE("memoryBound: before construction, what reserve() makes the pipeline allocate, and no frame more") {
    penumbra::test::context();
    const penumbra::test::GlWorld w(penumbra::scene::builtin("torus_knot"));
    const penumbra::test::GlSoftLight soft(w, 64, 64, 128);
    const penumbra::BufferRange table = soft.table();
    const GLint alignment = penumbra::gl::getInteger(GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT);
    REQUIRE(alignment > 0);
    REQUIRE(alignment <= 256);
    const auto stride = [](size_t align) { return (sizeof(penumbra::SbsParams) + align - 1) / align * align; };
    struct Case {
        const char* name;
        penumbra::SoftLightPass pass;
        uint32_t deferred_pairs, coverage_texels;
        bool empty_blocks, closed_casters, silhouettes;
    };
    for (const Case c : {Case{"raster, defaults", penumbra::SoftLightPass::Raster, 1u << 20, 64, true, true, false},
                         Case{"raster, no deferred pairs", penumbra::SoftLightPass::Raster, 0, 0, true, false, false},
                         Case{"raster, no coverage, no stencil", penumbra::SoftLightPass::Raster, 1u << 16, 0, false, true, false},
                         Case{"compute", penumbra::SoftLightPass::Compute, 1u << 20, 64, true, true, false},
                         Case{"compute, small buffers", penumbra::SoftLightPass::Compute, 4096, 64, false, false, false},
                         Case{"raster, small buffers, silhouettes", penumbra::SoftLightPass::Raster, 4096, 64, false, false, true}}) {
        CAPTURE(c.name);
        penumbra::SampleBasedSoftGpuOptions options;
        options.light_pass = c.pass;
        options.grid_width = options.grid_height = 64;
        options.deferred_pairs = c.deferred_pairs;
        options.coverage_texels = c.coverage_texels;
        options.skips.empty_blocks = c.empty_blocks;
        options.skips.closed_casters = c.closed_casters;
        options.skips.silhouettes = c.silhouettes;
        options.max_list_blocks = 32;
        const uint32_t max_samples = w.samples() + 1000;  // more than a frame uses
        const uint64_t bound = penumbra::SampleBasedSoftShadows::memoryBound(options, soft.sets, soft.influence, max_samples);
        penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
        pipeline.reserve(max_samples);
        const uint64_t reserved = pipeline.memoryBytes();
        // The bound is what was allocated, but the parameter slots' alignment (256 bytes in it).
        const uint64_t slack = (stride(256) - stride(size_t(alignment))) * (1 + 6 * uint64_t(options.max_list_blocks));
        MESSAGE(std::string(c.name), ": memoryBound ", bound, " bytes, allocated ", reserved, " (uniform alignment ", alignment, ")");
        CHECK(bound == reserved + slack);
        if (c.silhouettes) continue;  // a run with silhouettes needs the adjacency draw; the sizes are checked
        Status status;
        if (c.pass == penumbra::SoftLightPass::Compute) {
            status = pipeline.run(w.depthInput(), table, w.gpu.casterBuffers().data(), uint32_t(w.gpu.casterBuffers().size()));
        } else {
            status = pipeline.run(w.depthInput(), table, [&](penumbra::CasterClass k) { w.drawClass(k); });
        }
        REQUIRE(status == Status::Ok);
        CHECK(pipeline.memoryBytes() == reserved);
    }
    // Bad options: the constructor's errors, naming the values.
    penumbra::SampleBasedSoftGpuOptions bad;
    bad.grid_width = 0;
    bad.grid_height = 64;
    CHECK_THROWS_WITH(penumbra::SampleBasedSoftShadows::memoryBound(bad, soft.sets, soft.influence, 100),
                      doctest::Contains("grid 0 x 64 must be 1 .. 8192 per side"));
    bad.grid_width = bad.grid_height = 32;
    CHECK_THROWS_WITH(penumbra::SampleBasedSoftShadows::memoryBound(bad, soft.sets, soft.influence, 100),
                      doctest::Contains("the influence setup's grid 64 x 64 differs from the options' 32 x 32"));
}

TEST_CASE("Compute light pass: the raster pass's bits, both inputs, small capacities (torus knot, columns, one OBJ)") {
    std::vector<std::string> names = {"torus_knot", "columns"};
    const std::vector<std::string> objs = sharedObjNames();
    if (!objs.empty()) names.push_back(objs.front());
    checkComputeAgainstRaster(sweptScenes(names), false);
}

TEST_SUITE("stress") {
    TEST_CASE("Compute light pass (stress): the raster pass's bits on every built-in and shared scene, every mode, input and capacity") {
        std::vector<std::string> names = penumbra::scene::builtinNames();
        for (const std::string& obj : sharedObjNames()) names.push_back(obj);
        checkComputeAgainstRaster(names, true);
    }
}

namespace {

/// One batch of random and adversarial caster triangles between a ground square of side 4 and a
/// spherical light 4 above it (all shifted by `offset`): 75 % small ones of any orientation, 15 %
/// slivers (one in ten exactly collinear: degenerate), 5 % just below the light (regions larger
/// than the grid), 5 % needles 40-80 long crossing the whole grid (vertices far outside it).
penumbra::scene::Mesh adversarialSoup(uint32_t triangles, const glm::vec3& offset, const glm::vec3& light, float light_radius,
                                      std::mt19937& rng) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f), sym(-1.0f, 1.0f);
    const auto direction = [&] {
        for (;;) {
            const glm::vec3 d(sym(rng), sym(rng), sym(rng));
            const float l = glm::length(d);
            if (l > 0.1f && l <= 1.0f) return d / l;
        }
    };
    penumbra::scene::Mesh mesh;
    for (uint32_t t = 0; t < triangles; ++t) {
        const float kind = unit(rng);
        const glm::vec3 centre(4.0f * unit(rng) - 2.0f, 0.2f + 3.0f * unit(rng), 4.0f * unit(rng) - 2.0f);
        glm::vec3 a, b, c;
        if (kind < 0.75f) {  // small, any orientation
            const float size = 0.02f + 0.18f * unit(rng);
            a = centre + size * direction(), b = centre + size * direction(), c = centre + size * direction();
        } else if (kind < 0.90f) {  // sliver: c next to (or on) the segment ab
            const glm::vec3 d = (0.05f + 0.45f * unit(rng)) * direction();
            a = centre, b = centre + d;
            c = centre + unit(rng) * d;
            if (unit(rng) >= 0.1f) c += 1e-5f * glm::length(d) * glm::normalize(glm::cross(d, direction()));
        } else if (kind < 0.95f) {  // just below the light: a region larger than the grid
            const glm::vec3 near = light - glm::vec3(0.3f * sym(rng), light_radius + 0.01f + 0.1f * unit(rng), 0.3f * sym(rng)) - offset;
            const float size = 0.01f + 0.03f * unit(rng);
            a = near + size * direction(), b = near + size * direction(), c = near + size * direction();
        } else {  // a needle crossing the grid, its ends far outside it
            const glm::vec3 d = (40.0f + 40.0f * unit(rng)) * glm::normalize(glm::vec3(sym(rng), 0.05f * sym(rng), sym(rng)));
            a = centre - 0.5f * d, b = centre + 0.5f * d;
            c = centre + 0.05f * direction();
        }
        for (const glm::vec3& v : {a, b, c}) {
            mesh.indices.push_back(uint32_t(mesh.positions.size()));
            mesh.positions.push_back(v + offset);
        }
    }
    return mesh;
}

/// The compute light pass on `batches` batches of adversarialSoup(per_batch): the texels it visits
/// against the CPU twin's, and brute masks against the oracle (same float receivers, same light
/// samples): a mismatched non-tie bit is a shadow the setup, binning or coverage lost or invented.
/// (The regions are conservative, so a few texels missed at their edges rarely shows in the
/// bits: a left edge 0.01 px short kept every bit and was caught only by the texel count.)
void checkAdversarialBatches(uint32_t batches, uint32_t per_batch, const glm::vec3& offset) {
    penumbra::test::context();
    const uint32_t n = 32, grid = 64;
    const glm::vec3 light_position = glm::vec3(0.0f, 4.0f, 0.0f) + offset;
    const float light_radius = 0.5f;
    const penumbra::LightSampleSets sets = sphereSets(dvec3(light_position), light_radius, n, 1, 7);
    const CertifiedLut certified(sets, 64);
    std::vector<dvec3> samples;
    {
        const std::vector<glm::dvec4> table = penumbra::sampleBasedSoftSampleTable(sets, 1);
        for (uint32_t i = 0; i < n; ++i) samples.emplace_back(table[i]);
    }
    std::mt19937 rng(penumbra::test::testSeed(uint32_t(offset.x)));
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    // Receivers: 1500 on the ground square, 500 on each batch's triangles (refreshed per batch).
    std::vector<glm::vec3> ground;
    for (int i = 0; i < 1500; ++i) ground.push_back(offset + glm::vec3(4.0f * unit(rng) - 2.0f, 0.0f, 4.0f * unit(rng) - 2.0f));
    std::vector<glm::vec3> frame_box = ground;
    frame_box.push_back(offset + glm::vec3(0.0f, 3.2f, 0.0f));  // the grid covers the casters' heights too
    penumbra::Light light;
    light.center = dvec3(light_position);
    light.size = dvec3(light_radius);
    const ReceiverGrid receiver_grid = receiverGrid(frame_box, light, grid, 0.05f);
    penumbra::SampleBasedSoftGpuOptions options;
    options.grid_width = options.grid_height = grid;
    options.light_pass = penumbra::SoftLightPass::Compute;
    options.rotations = 1;
    const uint32_t receiver_count = 2000;
    // The shadows: brute (every bit by the exact segment test; the LUT's modes are compared with
    // it on the same passes elsewhere).
    options.mode = penumbra::SoftMode::Brute;
    penumbra::SampleBasedSoftShadows pipeline(options, sets, nullptr, receiver_grid.influence, receiver_grid.vp);
    pipeline.reserve(receiver_count);
    // The texels visited: one view sample at every texel's centre (on the ground plane), every
    // skip off, count_work: the frame's fragments are the visits of every region's texels, which
    // must be the CPU twin's (influenceCoverageTexels: GL's rule and more, tested on 10^5 regions
    // in influence_region_test) region by region summed. Holds where the GPU's regions are the
    // CPU's bit for bit (correctly rounded float: llvmpipe).
    std::vector<glm::vec4> centres;
    {
        const glm::mat4 inverse = glm::inverse(receiver_grid.vp);
        for (uint32_t y = 0; y < grid; ++y)
            for (uint32_t x = 0; x < grid; ++x) {
                const glm::vec2 ndc(2.0f * (float(x) + 0.5f) / float(grid) - 1.0f, 2.0f * (float(y) + 0.5f) / float(grid) - 1.0f);
                const glm::vec4 a = inverse * glm::vec4(ndc, -1.0f, 1.0f), b = inverse * glm::vec4(ndc, 1.0f, 1.0f);
                const glm::vec3 p = glm::vec3(a) / a.w, q = glm::vec3(b) / b.w;
                centres.emplace_back(p + (offset.y - p.y) / (q.y - p.y) * (q - p), 1.0f);
            }
    }
    const penumbra::gl::Buffer centre_buffer = penumbra::gl::Buffer::fromVector(centres);
    const penumbra::SampleBufferInput centre_input{{centre_buffer.id(), 0, centre_buffer.size()}, {}};
    penumbra::SampleBasedSoftGpuOptions visit_options = options;
    visit_options.mode = penumbra::SoftMode::Lut;
    visit_options.skips.empty_blocks = visit_options.skips.closed_casters = visit_options.skips.plane_cut = false;
    visit_options.skips.silhouettes = visit_options.skips.wedges = false;
    penumbra::SampleBasedSoftShadows visits(visit_options, sets, &certified.lut, receiver_grid.influence, receiver_grid.vp);
    visits.reserve(uint32_t(centres.size()));
    Tally total;
    uint64_t blocked = 0, triangles = 0, texels_visited = 0, texels_twin = 0, regions = 0;
    for (uint32_t batch = 0; batch < batches; ++batch) {
        const penumbra::scene::Mesh soup = adversarialSoup(per_batch, offset, light_position, light_radius, rng);
        triangles += soup.triangleCount();
        // Receivers on the casters: those inside the grid's box (needles reach far outside it).
        std::vector<glm::vec3> points = ground;
        for (const glm::vec3& p : surfacePoints(soup, 8 * (receiver_count - ground.size()), uint32_t(rng()))) {
            const glm::vec3 q = p - offset;
            if (points.size() < receiver_count && std::abs(q.x) <= 2.0f && std::abs(q.z) <= 2.0f && q.y >= 0.0f && q.y <= 3.2f)
                points.push_back(p);
        }
        REQUIRE(points.size() == receiver_count);
        std::vector<glm::vec4> positions4;
        std::vector<dvec3> receivers;
        for (const glm::vec3& p : points) positions4.emplace_back(p, 1.0f), receivers.emplace_back(p);
        const penumbra::gl::Buffer positions = penumbra::gl::Buffer::fromVector(positions4);
        const penumbra::gl::Buffer vertices = penumbra::gl::Buffer::fromVector(soup.positions);
        const penumbra::gl::Buffer indices = penumbra::gl::Buffer::fromVector(soup.indices);
        const penumbra::SampleBufferInput input{{positions.id(), 0, positions.size()}, {}};
        penumbra::CasterBuffer casters;
        casters.positions = {vertices.id(), 0, vertices.size()};
        casters.indices = {indices.id(), 0, indices.size()};
        casters.triangles = uint32_t(soup.triangleCount());
        const std::vector<dvec3> mesh_d(soup.positions.begin(), soup.positions.end());
        const penumbra::reference::VisibilityResult truth =
            penumbra::reference::VisibilityOracle(mesh_d, soup.indices).evaluate(receivers, samples);
        for (size_t r = 0; r < truth.receivers; ++r) blocked += truth.blockedCount(r);
        {
            REQUIRE(pipeline.run(input, receiver_count, penumbra::BufferRange{}, &casters, 1) == Status::Ok);
            const penumbra::SampleBasedSoftFrame f = pipeline.readFrame();
            const Tally t = compareOracle(pipeline.readMasks(), 1, pipeline.readVisibility(), truth);
            total.bits += t.bits, total.ties += t.ties, total.mismatched += t.mismatched, total.untested += t.untested;
            CHECK(f.overflow == 0);
            CHECK(f.caster_indices_out_of_range == 0);
            if (t.mismatched != 0 || t.untested != 0) MESSAGE("batch ", batch, ": mismatched ", t.mismatched, ", untested ", t.untested);
        }
        {
            REQUIRE(visits.run(centre_input, uint32_t(centres.size()), certified.table(), &casters, 1) == Status::Ok);
            const penumbra::SampleBasedSoftFrame f = visits.readFrame();
            uint64_t twin = 0;
            for (size_t t = 0; t < soup.triangleCount(); ++t) {
                const glm::vec3 a = soup.positions[soup.indices[3 * t]], b = soup.positions[soup.indices[3 * t + 1]],
                                c = soup.positions[soup.indices[3 * t + 2]];
                if (penumbra::detail::degenerateTriangle(glm::dvec3(a), glm::dvec3(b), glm::dvec3(c))) continue;
                const penumbra::InfluenceRegion region = penumbra::influenceRegion(a, b, c, receiver_grid.influence);
                if (region.count <= 0) continue;
                ++regions;
                twin += penumbra::influenceCoverageTexels(region, receiver_grid.influence).size();
            }
            CHECK(f.statistics.occupied_lists == grid * grid);  // every texel holds its centre's sample
            if (f.fragments != twin) MESSAGE("batch ", batch, ": ", f.fragments, " texels visited, the twin's ", twin);
            texels_visited += f.fragments;
            texels_twin += twin;
        }
        penumbra::gl::checkErrors("adversarial batches");
    }
    MESSAGE(regions, " regions: ", texels_visited, " texels visited on the GPU, ", texels_twin, " by the CPU twin");
    CHECK(texels_visited == texels_twin);
    MESSAGE(triangles, " triangles in ", batches, " batches, offset (", offset.x, ", ", offset.y, ", ", offset.z, "): ",
            total.bits, " bits, ", blocked, " blocked (oracle), ties ", total.ties, ", mismatched ", total.mismatched, ", untested ",
            total.untested);
    CHECK(blocked > total.bits / 100);  // the batches do cast shadows
    CHECK(total.mismatched == 0);
    CHECK(total.untested == 0);
}

}  // namespace

TEST_CASE("Compute light pass: no shadow lost or invented, 10^5 random and adversarial triangles (slivers, needles, near the light, far from the origin)") {
    // 10^5 triangles in 100 batches at the origin, 10^4 at (1000, 0, -1000); the sanitizer build
    // runs a tenth (the same code paths).
    const uint32_t batches = penumbra::test::kSanitized ? 10 : 100;
    if (penumbra::test::kSanitized) MESSAGE("sanitizer build: ", batches, " batches of 1000 triangles (the Release run: 100)");
    checkAdversarialBatches(batches, 1000, glm::vec3(0.0f));
    checkAdversarialBatches(std::max<uint32_t>(1, batches / 10), 1000, glm::vec3(1000.0f, 0.0f, -1000.0f));
}

TEST_SUITE("stress") {
    TEST_CASE("Compute light pass (stress): no shadow lost or invented, 10^6 random and adversarial triangles") {
        checkAdversarialBatches(1000, 1000, glm::vec3(0.0f));
        checkAdversarialBatches(100, 1000, glm::vec3(1000.0f, 0.0f, -1000.0f));
    }
}

TEST_CASE("Compute light pass: misuse returns a Status, bad indices are counted, bad setup throws") {
    penumbra::test::context();
    const penumbra::test::GlWorld w(penumbra::scene::builtin("columns"));
    const penumbra::test::GlSoftLight soft(w, 64, 64, 32);
    const std::vector<penumbra::CasterBuffer>& casters = w.gpu.casterBuffers();
    penumbra::SampleBasedSoftGpuOptions options;
    options.grid_width = options.grid_height = 64;
    options.light_pass = penumbra::SoftLightPass::Compute;
    {
        penumbra::SampleBasedSoftGpuOptions bad = options;
        bad.skips.silhouettes = true;
        CHECK_THROWS_WITH_AS(penumbra::SampleBasedSoftShadows(bad, soft.sets, &soft.lut, soft.influence, w.light.view_projection),
                             doctest::Contains("skips.silhouettes"), penumbra::Error);
        bad = options;
        bad.deferred_pairs = 0;
        CHECK_THROWS_WITH_AS(penumbra::SampleBasedSoftShadows(bad, soft.sets, &soft.lut, soft.influence, w.light.view_projection),
                             doctest::Contains("deferred_pairs > 0"), penumbra::Error);
    }
    penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
    pipeline.reserve(w.samples());
    const penumbra::SampleDepthInput input = w.depthInput();
    const auto expect = [&](const penumbra::CasterBuffer& c, Status status) {
        CAPTURE(c.stride);
        CAPTURE(c.triangles);
        CHECK(pipeline.run(input, soft.table(), &c, 1) == status);
    };
    const penumbra::CasterBuffer good = casters.front();
    penumbra::CasterBuffer c = good;
    c.stride = 10;
#ifdef NDEBUG  // misuse asserts in debug builds
    expect(c, Status::InvalidArgument);
#endif
    CHECK_THROWS_WITH_AS(pipeline.validateCasters(&c, 1), doctest::Contains("stride 10"), penumbra::Error);
#ifdef NDEBUG
    c = good;
    c.indices.size = 12ull * c.triangles - 4;
    expect(c, Status::RangeTooSmall);
    c = good;
    c.indices = {};  // non-indexed: 3 vertices a triangle, more than the buffer holds
    c.triangles = static_cast<uint32_t>(w.gpu.positions().size());
    expect(c, Status::RangeTooSmall);
    c = good;
    c.positions.offset = 4;
    expect(c, Status::Misaligned);
    CHECK(pipeline.run(input, soft.table(), nullptr, 1) == Status::InvalidArgument);
    CHECK(pipeline.run(input, soft.table(), [&](penumbra::CasterClass k) { w.drawClass(k); }) == Status::InvalidArgument);
#else
    (void)expect;
#endif
    // An index past the positions: the triangle casts nothing and is counted, once per frame.
    std::vector<uint32_t> indices = w.gpu.indices();
    indices[4] = 0x7FFFFFFFu;
    const penumbra::gl::Buffer bad_indices = penumbra::gl::Buffer::fromVector(indices);
    c = good;
    c.indices = {bad_indices.id(), 0, bad_indices.size()};
    c.triangles = static_cast<uint32_t>(indices.size() / 3);
    c.caster_class = penumbra::CasterClass::Open;
    REQUIRE(pipeline.run(input, soft.table(), &c, 1) == Status::Ok);
    CHECK(pipeline.readFrame().caster_indices_out_of_range == 1);
    penumbra::gl::checkErrors("compute light pass misuse");
    // And the raster pipeline refuses casters as buffers.
    options.light_pass = penumbra::SoftLightPass::Raster;
    penumbra::SampleBasedSoftShadows raster(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
    raster.reserve(w.samples());
#ifdef NDEBUG
    CHECK(raster.run(input, soft.table(), &good, 1) == Status::InvalidArgument);
#endif
}

TEST_CASE("Compute light pass: a frame makes no draw, query, stencil or framebuffer call, and keeps the per-frame contract") {
    penumbra::test::context();
    const penumbra::test::GlWorld w(penumbra::scene::builtin("columns"));
    const penumbra::test::GlSoftLight soft(w, 64, 64, 32);
    const std::vector<penumbra::CasterBuffer>& casters = w.gpu.casterBuffers();
    for (const bool depth : {true, false}) {
        CAPTURE(depth);
        penumbra::SampleBasedSoftGpuOptions options;
        options.grid_width = options.grid_height = 64;
        options.light_pass = penumbra::SoftLightPass::Compute;
        options.timings = false;
        penumbra::SampleBasedSoftShadows pipeline(options, soft.sets, &soft.lut, soft.influence, w.light.view_projection);
        pipeline.reserve(w.samples());
        const penumbra::SampleDepthInput depth_input = w.depthInput();
        const penumbra::SampleBufferInput buffer_input = w.bufferInput();
        const penumbra::BufferRange table = soft.table();
        Status status = Status::Ok;
        const auto frame = [&] {
            status = depth ? pipeline.run(depth_input, table, casters.data(), static_cast<uint32_t>(casters.size()))
                           : pipeline.run(buffer_input, w.samples(), table, casters.data(), static_cast<uint32_t>(casters.size()));
        };
        frame();  // warm-up
        penumbra::test::checkPerFrameContract(frame);
        CHECK(status == Status::Ok);
        penumbra::test::GlAudit audit;
        audit.start();
        frame();
        audit.stop();
        const std::vector<std::string> names = audit.names();
        const size_t graphics = audit.graphicsCalls().size();
        for (const std::string& name : audit.graphicsCalls()) MESSAGE("graphics-pipeline call in a compute frame: ", name);
        CHECK(!audit.overflowed());
        CHECK(graphics == 0);
        MESSAGE("compute light pass frame (", std::string(depth ? "depth" : "buffer"), " input): ", names.size(), " GL calls, ", graphics,
                " draw / query / stencil / framebuffer calls");
    }
}
