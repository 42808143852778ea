// penumbra_casting.hpp (laine2005 hierarchical penumbra casting) against the oracle: on every
// built-in scene and the shared OBJ scenes, with planar (disk, rectangle) and volumetric (sphere,
// ellipsoid) lights and K sample sets, the blocked bits equal the oracle's on every pair it does
// not call a tie (ties are counted, and the tie bits are compared too). Every optimisation switched
// off alone, other thread counts and batch sizes give the same bits; on-demand masks stay below
// R * N / 8; degenerate input, a point light, cancellation. Receivers lie on the scenes' surfaces.
#include "penumbra/penumbra_casting.hpp"
#include "penumbra/reference/visibility.hpp"
#include "penumbra/scene/obj.hpp"
#include "penumbra/scene/scene.hpp"
#include "support/source_paths.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

using glm::dvec3;
using penumbra::test::contains;
using penumbra::test::errorOf;

namespace {

bool stressRun() { return std::getenv("PENUMBRA_STRESS") != nullptr; }

struct Mesh {
    std::vector<dvec3> positions;
    std::vector<uint32_t> indices;
    size_t triangles() const { return indices.size() / 3; }
};

struct Case {
    std::string name;
    penumbra::scene::Scene scene;
    Mesh mesh;
};

Mesh toMesh(const penumbra::scene::Mesh& m) {
    Mesh out;
    out.positions.assign(m.positions.begin(), m.positions.end());
    out.indices = m.indices;
    return out;
}

std::vector<Case> allScenes() {
    std::vector<Case> cases;
    for (const auto& name : penumbra::scene::builtinNames()) {
        penumbra::scene::Scene scene = penumbra::scene::builtin(name);
        Mesh mesh = toMesh(scene.merged());
        cases.push_back({name, std::move(scene), std::move(mesh)});
    }
    const std::string dir = penumbra::test::sharedScenesDir();
    if (std::filesystem::is_directory(dir)) {
        std::vector<std::string> files;
        for (const auto& e : std::filesystem::directory_iterator(dir))
            if (e.path().extension() == ".obj") files.push_back(e.path().string());
        std::sort(files.begin(), files.end());
        for (const auto& file : files) {
            penumbra::scene::Scene scene = penumbra::scene::loadObj(file);
            Mesh mesh = toMesh(scene.merged());
            cases.push_back({std::filesystem::path(file).filename().string(), std::move(scene), std::move(mesh)});
        }
    } else {
        MESSAGE("skipping the shared OBJ scenes: ", dir, " is absent");
    }
    return cases;
}

/// `count` points on random triangles of the mesh (uniform per triangle index).
std::vector<dvec3> surfacePoints(const Mesh& mesh, size_t count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_int_distribution<size_t> pick(0, mesh.triangles() - 1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<dvec3> points;
    while (points.size() < count) {
        const size_t t = pick(rng);
        const dvec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
                    c = mesh.positions[mesh.indices[3 * t + 2]];
        double u = unit(rng), v = unit(rng);
        if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
        points.push_back(a + u * (b - a) + v * (c - a));
    }
    return points;
}

/// The scene's light as each of the four shapes (planar ones face the scene's centre).
std::vector<std::pair<std::string, penumbra::Light>> lightsOf(const penumbra::scene::Scene& scene) {
    const dvec3 position(scene.light.position);
    const double radius = std::max(0.05, double(scene.light.radius));
    const penumbra::scene::Bounds bounds = scene.bounds();
    const dvec3 centre = 0.5 * (dvec3(bounds.min) + dvec3(bounds.max));
    const dvec3 down = centre - position;
    std::vector<std::pair<std::string, penumbra::Light>> lights;
    penumbra::Light disk;
    disk.shape = penumbra::LightShape::Disk;
    disk.center = position;
    disk.axis_z = down;
    disk.axis_x = glm::cross(down, dvec3(0.3, 0.2, 1.0));
    disk.size = dvec3(1.5 * radius);
    lights.emplace_back("disk", disk);
    penumbra::Light rect = disk;
    rect.shape = penumbra::LightShape::Rectangle;
    rect.size = dvec3(1.6 * radius, 0.7 * radius, 1.0);
    lights.emplace_back("rectangle", rect);
    penumbra::Light sphere;
    sphere.shape = penumbra::LightShape::Sphere;
    sphere.center = position;
    sphere.size = dvec3(radius);
    lights.emplace_back("sphere", sphere);
    penumbra::Light ellipsoid = sphere;
    ellipsoid.shape = penumbra::LightShape::Ellipsoid;
    ellipsoid.axis_z = dvec3(0.2, 1.0, 0.3);
    ellipsoid.axis_x = dvec3(1.0, 0.0, 0.4);
    ellipsoid.size = dvec3(1.4 * radius, 0.6 * radius, 0.9 * radius);
    lights.emplace_back("ellipsoid", ellipsoid);
    return lights;
}

/// The oracle with each receiver's own set, scattered back into receiver order.
penumbra::reference::VisibilityResult oracleTruth(const penumbra::reference::VisibilityOracle& oracle,
                                                  const std::vector<dvec3>& receivers,
                                                  const std::vector<uint32_t>& receiver_sets,
                                                  const penumbra::LightSampleSets& sets,
                                                  const penumbra::reference::VisibilityOptions& options = {}) {
    const uint32_t n = sets.count();
    penumbra::reference::VisibilityResult truth;
    truth.receivers = receivers.size();
    truth.samples = n;
    truth.words_per_receiver = (n + 31) / 32;
    truth.blocked.assign(receivers.size() * truth.words_per_receiver, 0u);
    truth.ties.assign(receivers.size() * truth.words_per_receiver, 0u);
    for (uint32_t set = 0; set < sets.sets(); ++set) {
        std::vector<dvec3> group;
        std::vector<size_t> ids;
        for (size_t r = 0; r < receivers.size(); ++r)
            if (receiver_sets[r] == set) {
                group.push_back(receivers[r]);
                ids.push_back(r);
            }
        if (group.empty()) continue;
        const penumbra::reference::VisibilityResult part =
            oracle.evaluate(group, std::vector<dvec3>(sets.worldSet(set), sets.worldSet(set) + n), options);
        for (size_t g = 0; g < ids.size(); ++g)
            for (uint32_t w = 0; w < truth.words_per_receiver; ++w) {
                truth.blocked[ids[g] * truth.words_per_receiver + w] = part.blocked[g * part.words_per_receiver + w];
                truth.ties[ids[g] * truth.words_per_receiver + w] = part.ties[g * part.words_per_receiver + w];
            }
        truth.tie_count += part.tie_count;
    }
    return truth;
}

struct Tally {
    uint64_t pairs = 0, blocked = 0, ties = 0, mismatched = 0, tie_mismatched = 0;
};

Tally compare(const penumbra::PenumbraCastingResult& result, const penumbra::reference::VisibilityResult& truth) {
    Tally t;
    REQUIRE(result.blocked.size() == truth.blocked.size());
    REQUIRE(result.words_per_receiver == truth.words_per_receiver);
    for (size_t r = 0; r < truth.receivers; ++r)
        for (uint32_t s = 0; s < truth.samples; ++s) {
            ++t.pairs;
            t.tie_mismatched += result.isTie(r, s) != truth.isTie(r, s);
            if (truth.isTie(r, s)) {
                ++t.ties;
                continue;
            }
            t.blocked += truth.isBlocked(r, s);
            t.mismatched += result.isBlocked(r, s) != truth.isBlocked(r, s);
        }
    return t;
}

penumbra::PenumbraCastingResult cast(const Mesh& mesh, const std::vector<dvec3>& receivers, const penumbra::Light& light,
                                     const penumbra::LightSampleSets& sets, const penumbra::PenumbraCastingOptions& options = {},
                                     const std::vector<uint32_t>& receiver_sets = {}) {
    size_t t = 0;
    return penumbra::penumbraCast(
        receivers, light, sets,
        [&](dvec3& a, dvec3& b, dvec3& c) {
            if (t == mesh.triangles()) return false;
            a = mesh.positions[mesh.indices[3 * t]];
            b = mesh.positions[mesh.indices[3 * t + 1]];
            c = mesh.positions[mesh.indices[3 * t + 2]];
            ++t;
            return true;
        },
        options, receiver_sets);
}

std::vector<uint32_t> defaultSets(size_t receivers, uint32_t k) {
    std::vector<uint32_t> sets(receivers);
    for (size_t r = 0; r < receivers; ++r) sets[r] = uint32_t(r % k);
    return sets;
}

void equalsOracle(size_t receiver_count, uint32_t n, uint32_t k) {
    const uint32_t seed = penumbra::test::testSeed();
    Tally total;
    for (const Case& c : allScenes()) {
        const penumbra::reference::VisibilityOracle oracle(c.mesh.positions, c.mesh.indices);
        const std::vector<dvec3> receivers = surfacePoints(c.mesh, receiver_count, seed + uint32_t(c.mesh.triangles()));
        for (const auto& [light_name, light] : lightsOf(c.scene)) {
            INFO(c.name << " " << light_name << " N=" << n << " K=" << k);
            penumbra::LightSampleOptions sample_options;
            sample_options.count = n;
            sample_options.sets = k;
            sample_options.seed = seed;
            const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
            const penumbra::PenumbraCastingResult result = cast(c.mesh, receivers, light, sets);
            const penumbra::reference::VisibilityResult truth =
                oracleTruth(oracle, receivers, result.receiver_sets, sets);
            CHECK(result.receiver_sets == defaultSets(receivers.size(), k));
            const Tally t = compare(result, truth);
            CHECK(t.mismatched == 0);
            CHECK(t.tie_mismatched == 0);
            CHECK(result.stats.ties == truth.tie_count);
            CHECK(result.stats.triangles == c.mesh.triangles());
            MESSAGE(c.name, " ", light_name, ": ", c.mesh.triangles(), " triangles, ", t.pairs, " pairs, ", t.blocked,
                    " blocked, ", t.ties, " oracle ties (excluded), ", t.mismatched, " mismatched; pairs tested ",
                    result.stats.pairs_tested, ", hard-culled ", result.stats.pairs_hard_culled, ", nodes ",
                    result.stats.nodes_visited, ", near-light triangles ", result.stats.triangles_near_light);
            total.pairs += t.pairs;
            total.ties += t.ties;
            total.mismatched += t.mismatched;
            total.tie_mismatched += t.tie_mismatched;
        }
    }
    MESSAGE("all scenes and lights: ", total.pairs, " pairs, ", total.ties, " oracle ties excluded, ", total.mismatched,
            " blocked mismatches, ", total.tie_mismatched, " tie-bit mismatches");
}

}  // namespace

TEST_CASE("penumbra casting equals the oracle on every scene, planar and volumetric lights, K sets") {
    equalsOracle(240, 64, 4);
}

TEST_SUITE("stress") {
    TEST_CASE("penumbra casting equals the oracle: 3000 receivers, N = 256, K = 8") { equalsOracle(3000, 256, 8); }
}

TEST_CASE("every optimisation off alone, thread counts, batch sizes: identical bits") {
    const uint32_t seed = penumbra::test::testSeed(1);
    struct Setup {
        std::string name;
        penumbra::scene::Scene scene;
        size_t light_index;
    };
    std::vector<Setup> setups;
    setups.push_back({"torus_knot", penumbra::scene::torusKnot(24), 0});  // disk
    setups.push_back({"hairball", penumbra::scene::hairball(3000, 5), 2});  // sphere
    for (const Setup& setup : setups) {
        const Mesh mesh = toMesh(setup.scene.merged());
        const auto lights = lightsOf(setup.scene);
        const penumbra::Light& light = lights[setup.light_index].second;
        penumbra::LightSampleOptions sample_options;
        sample_options.count = 128;
        sample_options.sets = 8;
        const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
        const std::vector<dvec3> receivers = surfacePoints(mesh, 1500, seed);
        penumbra::PenumbraCastingOptions base;
        base.threads = 1;
        const penumbra::PenumbraCastingResult reference = cast(mesh, receivers, light, sets, base);
        const penumbra::reference::VisibilityOracle oracle(mesh.positions, mesh.indices);
        const Tally t = compare(reference, oracleTruth(oracle, receivers, reference.receiver_sets, sets));
        CHECK(t.mismatched == 0);
        CHECK(t.tie_mismatched == 0);

        std::vector<std::pair<std::string, penumbra::PenumbraCastingOptions>> variants;
        auto add = [&](const std::string& name, auto&& change) {
            penumbra::PenumbraCastingOptions o = base;
            change(o);
            variants.emplace_back(name, o);
        };
        add("umbra_bits off", [](auto& o) { o.umbra_bits = false; });
        add("active_planes off", [](auto& o) { o.active_planes = false; });
        add("lazy_volumes off", [](auto& o) { o.lazy_volumes = false; });
        add("on_demand_masks off", [](auto& o) { o.on_demand_masks = false; });
        add("area_sort off", [](auto& o) { o.area_sort = false; });
        add("certified_fast_path off", [](auto& o) { o.certified_fast_path = false; });
        add("2 threads", [](auto& o) { o.threads = 2; });
        add("3 threads", [](auto& o) { o.threads = 3; });
        add("batches of 1000", [](auto& o) { o.batch_triangles = 1000; });
        add("leaf 4, group 8", [](auto& o) {
            o.leaf_size = 4;
            o.group_size = 8;
        });
        add("everything off", [](auto& o) {
            o.umbra_bits = o.active_planes = o.lazy_volumes = o.on_demand_masks = o.area_sort = o.certified_fast_path = false;
        });
        for (const auto& [name, options] : variants) {
            INFO(setup.name << ": " << name);
            const penumbra::PenumbraCastingResult r = cast(mesh, receivers, light, sets, options);
            CHECK(r.blocked == reference.blocked);
            CHECK(r.ties == reference.ties);
            if (name == "2 threads" || name == "3 threads") {
                // Work counters do not depend on the thread count either.
                CHECK(r.stats.nodes_visited == reference.stats.nodes_visited);
                CHECK(r.stats.pairs_tested == reference.stats.pairs_tested);
                CHECK(r.stats.pairs_certified == reference.stats.pairs_certified);
                CHECK(r.stats.coplanar_skips == reference.stats.coplanar_skips);
                CHECK(r.stats.umbra_skips == reference.stats.umbra_skips);
            }
            MESSAGE(setup.name, " ", name, ": pairs tested ", r.stats.pairs_tested, " (all on: ",
                    reference.stats.pairs_tested, "), nodes ", r.stats.nodes_visited, ", umbra skips ", r.stats.umbra_skips,
                    ", volumes V_k ", r.stats.group_volumes_built, " V_i ", r.stats.hard_volumes_built, ", rebuilds ",
                    r.stats.rebuilds);
        }
    }
}

namespace {

/// Adversarial configurations for the certified fast path: receivers on and within 1e-12 .. 1e-6
/// (relative) of hard-shadow boundaries (an edge of T seen from a sample, and the vertices), just
/// behind T (t near 0) and on T's plane, a triangle nearly edge-on to the light, one close to the
/// light (t near 1), a floor the receivers lie on; optionally rotated and moved 1e5 away with
/// dyadic coordinates. Returns the mesh, the receivers, their sets and the sample sets.
/// x rotated, rounded to a multiple of 2^-24 (dyadic), then offset: the translation is exact, so
/// the far-from-origin variants see the same geometry.
dvec3 dyadicPlace(const glm::dmat3& rotation, double offset, const dvec3& x) {
    dvec3 y = rotation * x;
    for (int a = 0; a < 3; ++a) y[a] = std::ldexp(std::round(std::ldexp(y[a], 24)), -24) + offset;
    return y;
}

struct Adversarial {
    Mesh mesh;
    std::vector<dvec3> receivers;
    std::vector<uint32_t> receiver_sets;
    penumbra::Light light;
    penumbra::LightSampleSets sets;
};

Adversarial adversarialScene(bool rotate, bool far, uint32_t seed) {
    const double offset = far ? 1e5 : 0.0;
    const glm::dmat3 rotation = rotate ? glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.7, glm::normalize(dvec3(0.3, 1.0, -0.5))))
                                       : glm::dmat3(1.0);
    const auto place = [&](const dvec3& x) { return dyadicPlace(rotation, offset, x); };
    Adversarial adv;
    adv.light.shape = penumbra::LightShape::Disk;
    adv.light.center = dvec3(0.0, 3.0, 0.0);
    adv.light.axis_z = dvec3(0.0, -1.0, 0.0);
    adv.light.size = dvec3(0.6);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 64;
    sample_options.sets = 4;
    sample_options.seed = seed;
    adv.sets = penumbra::makeLightSampleSets(adv.light, sample_options);
    for (dvec3& x : adv.sets.world) x = place(x);
    adv.sets.frame.center = place(adv.sets.frame.center);
    adv.sets.frame.rotation = rotation * adv.sets.frame.rotation;
    adv.light.center = adv.sets.frame.center;
    adv.light.axis_z = rotation * adv.light.axis_z;
    const std::vector<std::array<dvec3, 3>> blockers = {
        {dvec3(-0.5, 1.0, -0.4), dvec3(0.6, 1.0, -0.3), dvec3(0.1, 1.0, 0.5)},      // parallel to the light
        {dvec3(0.2, 0.4, -0.5), dvec3(0.2 + 1e-7, 1.9, 0.0), dvec3(0.2, 0.5, 0.6)},  // nearly edge-on to the light
        {dvec3(-0.3, 2.75, -0.2), dvec3(0.25, 2.8, -0.1), dvec3(0.0, 2.7, 0.3)},    // close to the light (t near 1)
        {dvec3(-0.9, 1.3, 0.4), dvec3(-0.2, 1.6, 0.9), dvec3(-0.6, 1.1, 1.1)},      // tilted
    };
    const dvec3 floor[4] = {dvec3(-4, -0.5, -4), dvec3(4, -0.5, -4), dvec3(4, -0.5, 4), dvec3(-4, -0.5, 4)};
    std::vector<std::array<dvec3, 3>> placed;
    for (const auto& tri : blockers) placed.push_back({place(tri[0]), place(tri[1]), place(tri[2])});
    placed.push_back({place(floor[0]), place(floor[1]), place(floor[2])});
    placed.push_back({place(floor[0]), place(floor[2]), place(floor[3])});
    for (const auto& tri : placed) {
        for (const dvec3& v : tri) {
            adv.mesh.indices.push_back(uint32_t(adv.mesh.positions.size()));
            adv.mesh.positions.push_back(v);
        }
    }
    std::mt19937 rng(seed);
    std::uniform_int_distribution<uint32_t> pick_set(0, adv.sets.sets() - 1), pick_sample(0, adv.sets.count() - 1);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const double deltas[] = {0.0, 1e-12, -1e-12, 1e-10, -1e-10, 1e-9, -1e-9, 1e-8, -1e-8, 1e-6, -1e-6};
    const auto add = [&](const dvec3& p, uint32_t set) {
        adv.receivers.push_back(p);
        adv.receiver_sets.push_back(set);
    };
    for (size_t b = 0; b < blockers.size(); ++b) {
        const auto& tri = placed[b];
        for (int pick = 0; pick < 5; ++pick) {
            const uint32_t set = pick_set(rng);
            const dvec3 s = adv.sets.worldSet(set)[pick_sample(rng)];
            for (int e = 0; e < 3; ++e) {
                const dvec3 a = tri[e], c = tri[(e + 1) % 3];
                for (double lambda : {0.0, 0.35, 0.5, 1.0}) {
                    const dvec3 q = a + lambda * (c - a);
                    const dvec3 m = glm::normalize(glm::cross(c - a, q - s));
                    for (double tau : {1.0 + 1e-9, 1.7, 3.0}) {
                        const dvec3 p0 = s + tau * (q - s);
                        for (double delta : deltas) add(p0 + delta * glm::length(p0 - s) * m, set);
                    }
                }
            }
            // Just behind T (t near 0), on T's plane (inside, on an edge) and beyond, interior lines.
            const dvec3 inner = (tri[0] + tri[1] + tri[2]) / 3.0;
            const dvec3 edge_mid = 0.5 * (tri[0] + tri[1]);
            for (double delta : {0.0, 1e-12, 1e-9, 1e-6, -1e-9}) {
                add(inner + delta * (inner - s), set);
                add(edge_mid + delta * (edge_mid - s), set);
            }
            for (int i = 0; i < 10; ++i) {
                double u = unit(rng), v = unit(rng);
                if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
                const dvec3 q = tri[0] + u * (tri[1] - tri[0]) + v * (tri[2] - tri[0]);
                add(s + (1.0 + 2.0 * unit(rng)) * (q - s), set);
                add(q, set);
            }
        }
    }
    // Receivers on the floor (their own triangles: the coplanar rule), on its shared diagonal.
    for (int i = 0; i < 200; ++i) {
        const double u = unit(rng), v = unit(rng);
        add(place(dvec3(-3.0 + 6.0 * u, -0.5, -3.0 + 6.0 * v)), uint32_t(i % 4));
        add(place(dvec3(-3.0 + 6.0 * u, -0.5, -3.0 + 6.0 * u)), uint32_t(i % 4));
    }
    return adv;
}

}  // namespace

TEST_CASE("certified fast path: adversarial receivers near hard-shadow boundaries, edge-on blockers, far offset") {
    const uint32_t seed = penumbra::test::testSeed(6);
    uint64_t certified = 0, classified = 0, coplanar = 0, pairs = 0, ties = 0;
    for (int variant = 0; variant < 3; ++variant) {
        const Adversarial adv = adversarialScene(variant >= 1, variant == 2, seed + uint32_t(variant));
        const penumbra::reference::VisibilityOracle oracle(adv.mesh.positions, adv.mesh.indices);
        for (const auto& eps : {std::pair<double, double>{1e-9, 1e-9}, {1e-6, 1e-7}, {1e-12, 1e-12}}) {
            INFO("variant " << variant << " tie_epsilon " << eps.first << " coplanar_epsilon " << eps.second);
            penumbra::PenumbraCastingOptions options;
            options.oracle.tie_epsilon = eps.first;
            options.oracle.coplanar_epsilon = eps.second;
            options.threads = 2;
            const penumbra::PenumbraCastingResult fast = cast(adv.mesh, adv.receivers, adv.light, adv.sets, options, adv.receiver_sets);
            options.certified_fast_path = false;
            const penumbra::PenumbraCastingResult slow = cast(adv.mesh, adv.receivers, adv.light, adv.sets, options, adv.receiver_sets);
            const penumbra::reference::VisibilityResult truth =
                oracleTruth(oracle, adv.receivers, adv.receiver_sets, adv.sets, options.oracle);
            const Tally t = compare(fast, truth);
            CHECK(t.mismatched == 0);
            CHECK(t.tie_mismatched == 0);
            CHECK(fast.blocked == slow.blocked);
            CHECK(fast.ties == slow.ties);
            CHECK(slow.stats.pairs_certified == 0);
            CHECK(fast.stats.pairs_classified == fast.stats.pairs_tested);
            certified += fast.stats.pairs_certified;
            classified += fast.stats.pairs_classified;
            coplanar += fast.stats.coplanar_skips;
            pairs += t.pairs;
            ties += t.ties;
        }
    }
    CHECK(certified > 0);
    CHECK(coplanar > 0);
    MESSAGE("adversarial: ", pairs, " pairs, ", ties, " oracle ties, ", certified, " pairs certified, ", classified,
            " classified, ", coplanar, " coplanar skips; 0 mismatches");
}

namespace {

/// Certified verdicts of one scene against detail::oracle::classifySegment of each triangle alone,
/// along the caster's path: coplanar skip, 4-plane pyramid, else the miss-only pyramid. Receivers
/// r = offset, offset + stride, ... per triangle. new_misses: misses certified only by the
/// miss-only pyramid or the backward test (the 2-sided edge tests alone would not).
struct CertifiedTally {
    uint64_t hits = 0, misses = 0, new_misses = 0, flat_misses = 0, open = 0, coplanar_pairs = 0, wrong = 0;
    uint64_t pyramids = 0, miss_pyramids = 0, rejected = 0;
};

void certifiedVsOracle(const Adversarial& adv, const penumbra::reference::VisibilityOptions& options, size_t stride,
                       CertifiedTally& tally) {
    namespace dc = penumbra::detail::casting;
    namespace oracle = penumbra::detail::oracle;
    for (size_t t = 0; t < adv.mesh.triangles(); ++t) {
        dc::TriangleRecord rec;
        dc::setTriangle(rec, adv.mesh.positions[adv.mesh.indices[3 * t]], adv.mesh.positions[adv.mesh.indices[3 * t + 1]],
                        adv.mesh.positions[adv.mesh.indices[3 * t + 2]]);
        for (size_t r = t % stride; r < adv.receivers.size(); r += stride) {
            const dvec3& p = adv.receivers[r];
            const dvec3* samples = adv.sets.worldSet(adv.receiver_sets[r]);
            std::vector<dvec3> set(samples, samples + adv.sets.count());
            double reach2 = 0.0, reach_inf = 0.0;
            dc::sampleReach(set, 0.0, p, reach2, reach_inf);  // the samples themselves: tighter than the caster's
            const bool coplanar = dc::coplanarIgnoredForAll(rec, p, options.coplanar_epsilon);
            dc::Pyramid py;
            const bool full = !coplanar && dc::buildPyramid(rec, p, reach2, reach_inf, options.tie_epsilon,
                                                            options.coplanar_epsilon, py);
            const bool flat = !coplanar && !full && dc::buildMissPyramid(rec, p, reach2, reach_inf, options.tie_epsilon, py);
            tally.pyramids += full;
            tally.miss_pyramids += flat;
            tally.rejected += !coplanar && !full && !flat;
            dc::Pyramid two_sided = py;  // the edge-separation misses only
            two_sided.back_hi = -std::numeric_limits<double>::infinity();
            for (const dvec3& s : set) {
                if (p == s) continue;
                const oracle::Verdict v = oracle::classifySegment(rec.tri, oracle::makeSegmentQuery(p, s, options));
                if (coplanar) {
                    ++tally.coplanar_pairs;
                    tally.wrong += v.hit || v.fragile;
                    continue;
                }
                if (!full && !flat) continue;
                double hit = 0.0, miss = 0.0, hit2 = 0.0, miss2 = 0.0;
                dc::pyramidScores(py, s.x - p.x, s.y - p.y, s.z - p.z, hit, miss);
                dc::pyramidScores(two_sided, s.x - p.x, s.y - p.y, s.z - p.z, hit2, miss2);
                tally.wrong += hit > 0.0 && miss > 0.0;
                tally.wrong += flat && hit > 0.0;
                if (hit > 0.0) {
                    ++tally.hits;
                    tally.wrong += !(v.hit && !v.fragile);
                } else if (miss > 0.0) {
                    ++tally.misses;
                    tally.new_misses += flat || !(miss2 > 0.0);
                    tally.flat_misses += flat;
                    tally.wrong += v.hit || v.fragile;
                } else {
                    ++tally.open;
                }
            }
        }
    }
}

/// A closed octagonal column with a bevelled top (rounded-prism-like: neighbouring faces at
/// 45 and 22.5 degrees, side quads split in two coplanar triangles) standing on a floor, lit from
/// the side and above. Receivers on every face, on and within 1e-12 .. 1e-6 (relative) of the
/// shared edges and vertices, off each face's plane on both sides, and in each face's plane
/// outside it. Optionally rotated and moved 1e5 away (dyadic coordinates).
Adversarial prismScene(bool rotate, bool far, uint32_t seed) {
    const double offset = far ? 1e5 : 0.0;
    const glm::dmat3 rotation = rotate ? glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.4, glm::normalize(dvec3(-0.2, 1.0, 0.7))))
                                       : glm::dmat3(1.0);
    const auto place = [&](const dvec3& x) { return dyadicPlace(rotation, offset, x); };
    Adversarial adv;
    adv.light.shape = penumbra::LightShape::Rectangle;
    adv.light.center = dvec3(1.2, 2.6, 0.5);
    adv.light.axis_z = glm::normalize(dvec3(-1.2, -2.6, -0.5));
    adv.light.size = dvec3(0.8, 0.5, 0.5);
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 32;
    sample_options.sets = 4;
    sample_options.seed = seed;
    adv.sets = penumbra::makeLightSampleSets(adv.light, sample_options);
    for (dvec3& x : adv.sets.world) x = place(x);
    adv.sets.frame.center = place(adv.sets.frame.center);
    adv.sets.frame.rotation = rotation * adv.sets.frame.rotation;
    adv.light.center = adv.sets.frame.center;
    adv.light.axis_z = rotation * adv.light.axis_z;
    std::vector<std::array<dvec3, 3>> tris;
    const int sides = 8;
    const auto ring = [&](int i, double radius, double y) {
        const double a = 2.0 * 3.14159265358979323846 * i / sides;
        return place(dvec3(radius * std::cos(a), y, radius * std::sin(a)));
    };
    const dvec3 top = place(dvec3(0.0, 1.3, 0.0));
    for (int i = 0; i < sides; ++i) {
        const int j = (i + 1) % sides;
        const dvec3 b0 = ring(i, 0.3, 0.0), b1 = ring(j, 0.3, 0.0), m0 = ring(i, 0.3, 1.1), m1 = ring(j, 0.3, 1.1);
        const dvec3 t0 = ring(i, 0.2, 1.3), t1 = ring(j, 0.2, 1.3);
        tris.push_back({b0, m0, m1});  // side quad: two coplanar triangles
        tris.push_back({b0, m1, b1});
        tris.push_back({m0, t0, t1});  // bevel quad
        tris.push_back({m0, t1, m1});
        tris.push_back({t0, top, t1});  // cap fan
    }
    const size_t column_triangles = tris.size();
    tris.push_back({place(dvec3(-3, 0, -3)), place(dvec3(3, 0, -3)), place(dvec3(3, 0, 3))});
    tris.push_back({place(dvec3(-3, 0, -3)), place(dvec3(3, 0, 3)), place(dvec3(-3, 0, 3))});
    for (const auto& tri : tris) {
        for (const dvec3& v : tri) {
            adv.mesh.indices.push_back(uint32_t(adv.mesh.positions.size()));
            adv.mesh.positions.push_back(v);
        }
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    uint32_t next_set = 0;
    const auto add = [&](const dvec3& p) {
        adv.receivers.push_back(p);
        adv.receiver_sets.push_back(next_set++ % 4);
    };
    const double deltas[] = {0.0, 1e-12, -1e-12, 1e-9, -1e-9, 1e-6, -1e-6};
    for (size_t t = 0; t < column_triangles; ++t) {
        const auto& tri = tris[t];
        const dvec3 n = glm::normalize(glm::cross(tri[1] - tri[0], tri[2] - tri[0]));
        const double size = glm::length(tri[1] - tri[0]);
        for (int e = 0; e < 3; ++e) {
            const dvec3 a = tri[e], b = tri[(e + 1) % 3];
            const dvec3 out = glm::normalize(glm::cross(b - a, n));  // in T's plane, away from T
            for (double lambda : {0.0, 0.5, 1.0 - 1e-9}) {
                const dvec3 q = a + lambda * (b - a);
                for (double delta : deltas) {
                    add(q + delta * size * n);    // off the plane, at the edge / vertex
                    add(q + delta * size * out);  // in the plane, across the edge (a neighbour's face)
                }
                add(q + 1e-3 * size * out + 1e-9 * size * n);
            }
        }
        for (int i = 0; i < 6; ++i) {
            double u = unit(rng), v = unit(rng);
            if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
            const dvec3 q = tri[0] + u * (tri[1] - tri[0]) + v * (tri[2] - tri[0]);
            add(q);
            add(q + (i % 2 ? 1e-9 : -1e-7) * size * n);
        }
    }
    for (int i = 0; i < 60; ++i) {  // the floor around the column (coplanar neighbours, its shadow)
        const double a = 6.283185307179586 * unit(rng), radius = 0.3 + 1.2 * unit(rng) * unit(rng);
        add(place(dvec3(radius * std::cos(a), 0.0, radius * std::sin(a))));
    }
    return adv;
}

}  // namespace

TEST_CASE("certified fast path: every certified verdict is the oracle's classification of that triangle") {
    // No masking by other triangles: each (T, p, s) the fast path certifies is compared with
    // detail::oracle::classifySegment of T alone. Receivers include offsets around the margins.
    const uint32_t seed = penumbra::test::testSeed(7);
    CertifiedTally tally;
    for (int variant = 0; variant < 3; ++variant) {
        Adversarial adv = adversarialScene(variant >= 1, variant == 2, seed + uint32_t(variant));
        // Extra receivers around the certification margins (2^-26 relative, t error 2^-20).
        const size_t base_count = adv.receivers.size();
        for (size_t r = 0; r < base_count; r += 7) {
            const dvec3 p = adv.receivers[r];
            for (double d : {3e-8, 6e-8, 1.2e-7, 2.5e-7, 5e-7, 2e-6, 5e-6, 1e-5, 1e-4}) {
                adv.receivers.push_back(p + d * dvec3(0.6, 0.0, 0.8) * glm::length(p - adv.sets.frame.center));
                adv.receiver_sets.push_back(adv.receiver_sets[r]);
                adv.receivers.push_back(p + d * dvec3(0.0, 1.0, 0.0) * glm::length(p - adv.sets.frame.center));
                adv.receiver_sets.push_back(adv.receiver_sets[r]);
            }
        }
        for (const auto& eps : {std::pair<double, double>{1e-9, 1e-9}, {1e-6, 1e-7}, {0.0, 0.0}}) {
            INFO("variant " << variant << " tie_epsilon " << eps.first << " coplanar_epsilon " << eps.second);
            penumbra::reference::VisibilityOptions options;
            options.tie_epsilon = eps.first;
            options.coplanar_epsilon = eps.second;
            certifiedVsOracle(adv, options, 3, tally);  // a third of the receivers per triangle: test time
        }
    }
    const uint64_t hits = tally.hits, misses = tally.misses, open = tally.open, coplanar_pairs = tally.coplanar_pairs;
    const uint64_t wrong = tally.wrong, pyramids = tally.pyramids, rejected = tally.rejected;
    CHECK(wrong == 0);
    CHECK(hits > 0);
    CHECK(misses > 0);
    CHECK(coplanar_pairs > 0);
    MESSAGE("certified verdicts vs the oracle per triangle: ", hits, " hits, ", misses, " misses, ", coplanar_pairs,
            " coplanar-ignored, ", open, " left to the oracle, ", wrong, " wrong; pyramids ", pyramids, ", unusable ",
            rejected, "; misses by the miss-only pyramid ", tally.flat_misses, ", by the backward test ",
            tally.new_misses - tally.flat_misses);
}

TEST_CASE("certified fast path: closed column, receivers on shared edges / vertices and near neighbouring planes") {
    // Receivers on a face adjacent to T (shared edge or vertex), within 1e-12 .. 1e-6 of T's plane
    // or of its edges' lines, in T's plane outside T: the ill-conditioned pyramids (miss-only
    // pyramid) and the backward crossings of convex neighbours. Per triangle against
    // classifySegment, and the whole cast against the oracle and the slow path.
    const uint32_t seed = penumbra::test::testSeed(8);
    CertifiedTally tally;
    uint64_t certified = 0, classified = 0, pairs = 0;
    for (int variant = 0; variant < 2; ++variant) {
        const Adversarial adv = prismScene(variant == 1, variant == 1, seed + uint32_t(variant));
        const penumbra::reference::VisibilityOracle oracle(adv.mesh.positions, adv.mesh.indices);
        for (const auto& eps : {std::pair<double, double>{1e-9, 1e-9}, {0.0, 0.0}}) {
            INFO("variant " << variant << " tie_epsilon " << eps.first << " coplanar_epsilon " << eps.second);
            penumbra::PenumbraCastingOptions options;
            options.oracle.tie_epsilon = eps.first;
            options.oracle.coplanar_epsilon = eps.second;
            options.threads = 2;
            const uint64_t wrong_before = tally.wrong;
            certifiedVsOracle(adv, options.oracle, 3, tally);  // a third of the receivers per triangle: test time
            CHECK(tally.wrong == wrong_before);
            const penumbra::PenumbraCastingResult fast = cast(adv.mesh, adv.receivers, adv.light, adv.sets, options, adv.receiver_sets);
            options.certified_fast_path = false;
            const penumbra::PenumbraCastingResult slow = cast(adv.mesh, adv.receivers, adv.light, adv.sets, options, adv.receiver_sets);
            const penumbra::reference::VisibilityResult truth =
                oracleTruth(oracle, adv.receivers, adv.receiver_sets, adv.sets, options.oracle);
            const Tally t = compare(fast, truth);
            CHECK(t.mismatched == 0);
            CHECK(t.tie_mismatched == 0);
            CHECK(fast.blocked == slow.blocked);
            CHECK(fast.ties == slow.ties);
            certified += fast.stats.pairs_certified;
            classified += fast.stats.pairs_classified;
            pairs += t.pairs;
        }
    }
    CHECK(tally.wrong == 0);
    CHECK(tally.miss_pyramids > 0);
    CHECK(tally.flat_misses > 0);
    CHECK(tally.new_misses > tally.flat_misses);
    CHECK(tally.hits > 0);
    MESSAGE("column: ", pairs, " pairs cast, ", certified, " certified, ", classified, " classified; per triangle ",
            tally.hits, " hits, ", tally.misses, " misses (", tally.flat_misses, " by the miss-only pyramid, ",
            tally.new_misses - tally.flat_misses, " backward), ", tally.open, " open, ", tally.coplanar_pairs,
            " coplanar-ignored; pyramids ", tally.pyramids, ", miss-only ", tally.miss_pyramids, ", unusable ",
            tally.rejected, "; ", tally.wrong, " wrong");
}

TEST_CASE("on-demand masks: peak bytes below R * N / 8 with many unshadowed receivers") {
    const penumbra::scene::Scene scene = penumbra::scene::torusKnot(24);
    const Mesh mesh = toMesh(scene.merged());
    const penumbra::Light light = lightsOf(scene)[2].second;  // sphere
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 256;
    sample_options.sets = 8;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
    const std::vector<dvec3> receivers = surfacePoints(mesh, 4000, penumbra::test::testSeed(2));
    penumbra::PenumbraCastingOptions options;
    const penumbra::PenumbraCastingResult on = cast(mesh, receivers, light, sets, options);
    options.on_demand_masks = false;
    const penumbra::PenumbraCastingResult off = cast(mesh, receivers, light, sets, options);
    CHECK(on.stats.mask_bytes_full == receivers.size() * 256 / 8);
    CHECK(on.stats.mask_bytes_peak < on.stats.mask_bytes_full);
    CHECK(off.stats.mask_bytes_peak >= off.stats.mask_bytes_full);
    CHECK(on.blocked == off.blocked);
    size_t lit = 0, umbra = 0;
    for (size_t r = 0; r < receivers.size(); ++r) {
        lit += on.visibleFraction(r) == 1.0;
        umbra += on.visibleFraction(r) == 0.0;
    }
    MESSAGE("masks: on demand peak ", on.stats.mask_bytes_peak, " bytes, up front peak ", off.stats.mask_bytes_peak,
            " bytes, R * N / 8 = ", on.stats.mask_bytes_full, " (", lit, " of ", receivers.size(), " receivers fully lit, ",
            umbra, " in full umbra)");
}

TEST_CASE("a receiver hierarchy of many SAH subtrees: the same bits and work for 1, 2 and 3 threads") {
    // 40 000 receivers: the halving levels leave dozens of SAH subtrees, built concurrently and
    // appended in a fixed order, so the tree (and every work counter) must not depend on threads.
    const penumbra::scene::Scene scene = penumbra::scene::torusKnot(24);
    const Mesh mesh = toMesh(scene.merged());
    const penumbra::Light light = lightsOf(scene)[0].second;
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 32;
    sample_options.sets = 4;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);
    const std::vector<dvec3> receivers = surfacePoints(mesh, 40000, penumbra::test::testSeed(7));
    penumbra::PenumbraCastingOptions options;
    options.threads = 1;
    const penumbra::PenumbraCastingResult one = cast(mesh, receivers, light, sets, options);
    for (unsigned threads : {2u, 3u}) {
        INFO(threads << " threads");
        options.threads = threads;
        const penumbra::PenumbraCastingResult r = cast(mesh, receivers, light, sets, options);
        CHECK(r.blocked == one.blocked);
        CHECK(r.ties == one.ties);
        CHECK(r.stats.nodes_visited == one.stats.nodes_visited);
        CHECK(r.stats.pairs_tested == one.stats.pairs_tested);
        CHECK(r.stats.pairs_certified == one.stats.pairs_certified);
        CHECK(r.stats.umbra_skips == one.stats.umbra_skips);
        CHECK(r.stats.rebuilds == one.stats.rebuilds);
    }
    // Spot check against the oracle: every 97th receiver.
    std::vector<dvec3> some;
    std::vector<uint32_t> some_sets;
    std::vector<size_t> ids;
    for (size_t r = 0; r < receivers.size(); r += 97) {
        some.push_back(receivers[r]);
        some_sets.push_back(one.receiver_sets[r]);
        ids.push_back(r);
    }
    const penumbra::reference::VisibilityOracle oracle(mesh.positions, mesh.indices);
    const penumbra::reference::VisibilityResult truth = oracleTruth(oracle, some, some_sets, sets);
    size_t mismatched = 0;
    for (size_t k = 0; k < ids.size(); ++k)
        for (size_t w = 0; w < one.words_per_receiver; ++w) {
            const uint32_t tie = truth.ties[k * truth.words_per_receiver + w];
            mismatched += ((one.blocked[ids[k] * one.words_per_receiver + w] ^ truth.blocked[k * truth.words_per_receiver + w]) &
                           ~tie) != 0;
        }
    CHECK(mismatched == 0);
}

TEST_CASE("finish into a reused result: every field equals a fresh result's") {
    const penumbra::scene::Scene big_scene = penumbra::scene::hairball(3000, 5);
    const Mesh big = toMesh(big_scene.merged());
    const penumbra::Light big_light = lightsOf(big_scene)[2].second;
    penumbra::LightSampleOptions sample_options;
    sample_options.count = 128;
    sample_options.sets = 8;
    const penumbra::LightSampleSets big_sets = penumbra::makeLightSampleSets(big_light, sample_options);
    const penumbra::scene::Scene small_scene = penumbra::scene::torusKnot(24);
    const Mesh small = toMesh(small_scene.merged());
    const penumbra::Light small_light = lightsOf(small_scene)[0].second;
    sample_options.count = 64;
    sample_options.sets = 4;
    const penumbra::LightSampleSets small_sets = penumbra::makeLightSampleSets(small_light, sample_options);
    const std::vector<dvec3> big_receivers = surfacePoints(big, 3000, penumbra::test::testSeed(8));
    const std::vector<dvec3> small_receivers = surfacePoints(small, 1200, penumbra::test::testSeed(9));

    // A result full of another cast's bits (more receivers, more samples, umbra words of ones),
    // then a smaller and a same-sized cast into it.
    penumbra::PenumbraCastingResult reused = cast(big, big_receivers, big_light, big_sets);
    REQUIRE(reused.stats.pairs_certified_hits > 0);
    const auto castInto = [](penumbra::PenumbraCastingResult& out, const Mesh& mesh, const std::vector<dvec3>& receivers,
                             const penumbra::Light& light, const penumbra::LightSampleSets& sets) {
        size_t t = 0;
        penumbra::penumbraCast(out, receivers, light, sets, [&](dvec3& a, dvec3& b, dvec3& c) {
            if (t == mesh.triangles()) return false;
            a = mesh.positions[mesh.indices[3 * t]];
            b = mesh.positions[mesh.indices[3 * t + 1]];
            c = mesh.positions[mesh.indices[3 * t + 2]];
            ++t;
            return true;
        });
    };
    const auto same = [](const penumbra::PenumbraCastingResult& a, const penumbra::PenumbraCastingResult& b) {
        CHECK(a.samples == b.samples);
        CHECK(a.words_per_receiver == b.words_per_receiver);
        CHECK(a.receiver_sets == b.receiver_sets);
        CHECK(a.blocked == b.blocked);
        CHECK(a.ties == b.ties);
        CHECK(a.stats.ties == b.stats.ties);
        CHECK(a.stats.pairs_certified == b.stats.pairs_certified);
        CHECK(a.stats.nodes_visited == b.stats.nodes_visited);
        CHECK(a.stats.mask_bytes_full == b.stats.mask_bytes_full);
    };
    const penumbra::PenumbraCastingResult fresh_small = cast(small, small_receivers, small_light, small_sets);
    castInto(reused, small, small_receivers, small_light, small_sets);
    same(reused, fresh_small);
    const penumbra::PenumbraCastingResult fresh_big = cast(big, big_receivers, big_light, big_sets);
    castInto(reused, big, big_receivers, big_light, big_sets);
    same(reused, fresh_big);
}

TEST_CASE("degenerate blockers: zero area dropped and counted, NaN / Inf rejected naming the value") {
    penumbra::Light light;
    light.center = dvec3(0.0, 3.0, 0.0);
    light.axis_z = dvec3(0.0, -1.0, 0.0);
    light.size = dvec3(0.5);
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {64, 2});
    std::vector<dvec3> receivers;
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) receivers.push_back(dvec3(-1.0 + 0.2 * i, 0.0, -1.0 + 0.2 * j));
    penumbra::PenumbraCaster caster(receivers, light, sets);
    caster.addTriangle(dvec3(-1, 1, -1), dvec3(1, 1, -1), dvec3(0, 1, -1));        // collinear
    caster.addTriangle(dvec3(-1, 1, -1), dvec3(-1, 1, -1), dvec3(1, 1, 1));        // repeated vertex
    caster.addTriangle(dvec3(0.5, 1, 0.5), dvec3(0.5, 1, 0.5), dvec3(0.5, 1, 0.5));  // a point
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    const std::string nan_error = errorOf([&] { caster.addTriangle(dvec3(0, 1, 0), dvec3(nan, 1, 0), dvec3(0, 1, 1)); });
    CHECK(contains(nan_error, "vertex b of triangle 3"));
    CHECK(contains(nan_error, "nan"));
    const std::string inf_error = errorOf([&] { caster.addTriangle(dvec3(0, 1, 0), dvec3(1, 1, 0), dvec3(0, inf, 1)); });
    CHECK(contains(inf_error, "vertex c of triangle 3"));
    CHECK(contains(inf_error, "inf"));
    // Still usable: a real blocker after the rejected ones.
    caster.addTriangle(dvec3(-0.3, 1, -0.3), dvec3(0.3, 1, -0.3), dvec3(0, 1, 0.3));
    const penumbra::PenumbraCastingResult result = caster.finish();
    CHECK(result.stats.triangles == 4);
    CHECK(result.stats.triangles_degenerate == 3);
    const std::vector<dvec3> positions = {dvec3(-0.3, 1, -0.3), dvec3(0.3, 1, -0.3), dvec3(0, 1, 0.3)};
    const penumbra::reference::VisibilityOracle oracle(positions, {0, 1, 2});
    const Tally t = compare(result, oracleTruth(oracle, receivers, result.receiver_sets, sets));
    CHECK(t.mismatched == 0);
    CHECK(t.blocked > 0);
    CHECK(contains(errorOf([&] { caster.addTriangle(dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0)); }), "spent"));
}

TEST_CASE("receivers exactly on a blocker's plane are not blocked by it (coplanar rule, as the oracle)") {
    penumbra::Light light;
    light.shape = penumbra::LightShape::Rectangle;
    light.center = dvec3(0.25, 2.0, 0.0);
    light.axis_z = dvec3(-0.2, -1.0, 0.1);
    light.size = dvec3(0.4, 0.3, 1.0);
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {128, 4});
    // A tilted floor of two triangles with dyadic vertices, receivers on it (inside, on edges,
    // on the shared diagonal, at vertices), and below it.
    const dvec3 a(-1, 0.5, -1), b(1, 0.25, -1), c(1, 0.75, 1), d(-1, 1.0, 1);
    const std::vector<dvec3> positions = {a, b, c, d};
    const std::vector<uint32_t> indices = {0, 1, 2, 0, 2, 3};
    std::vector<dvec3> receivers = {a, b, c, d, 0.5 * (a + c), 0.5 * (a + b), 0.25 * a + 0.75 * c};
    std::mt19937 rng(penumbra::test::testSeed(3));
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 200; ++i) {
        const double u = unit(rng), v = unit(rng);
        receivers.push_back(a + u * (b - a) + v * (d - a));
        receivers.push_back(u + v <= 1.0 ? a + u * (b - a) + v * (c - a) : a + (1 - u) * (c - a) + (1 - v) * (d - a));
    }
    const size_t on_plane = receivers.size();
    for (int i = 0; i < 50; ++i) receivers.push_back(dvec3(unit(rng) - 0.5, -0.5, unit(rng) - 0.5));
    Mesh mesh{positions, indices};
    const penumbra::PenumbraCastingResult result = cast(mesh, receivers, light, sets);
    const penumbra::reference::VisibilityOracle oracle(positions, indices);
    const Tally t = compare(result, oracleTruth(oracle, receivers, result.receiver_sets, sets));
    CHECK(t.mismatched == 0);
    CHECK(t.tie_mismatched == 0);
    // The floor is a parallelogram (a + c == b + d): every receiver on it is unblocked by both of
    // its triangles; everything below is in full umbra.
    for (size_t r = 0; r < on_plane; ++r) CHECK(result.visibleFraction(r) == 1.0);
    for (size_t r = on_plane; r < receivers.size(); ++r) CHECK(result.visibleFraction(r) == 0.0);
}

TEST_CASE("a light of zero area: coincident samples act as a point light, as the oracle with that point") {
    penumbra::Light light;
    light.center = dvec3(0.3, 2.5, -0.2);
    light.size = dvec3(0.2);
    penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {32, 2});
    for (dvec3& s : sets.world) s = light.center;  // makeLightSampleSets rejects a zero radius
    const penumbra::scene::Scene scene = penumbra::scene::columns(4);
    const Mesh mesh = toMesh(scene.merged());
    const std::vector<dvec3> receivers = surfacePoints(mesh, 2000, penumbra::test::testSeed(4));
    const penumbra::PenumbraCastingResult result = cast(mesh, receivers, light, sets);
    const penumbra::reference::VisibilityOracle oracle(mesh.positions, mesh.indices);
    const penumbra::reference::VisibilityResult point = oracle.evaluate(receivers, {light.center});
    size_t shadowed = 0, ties = 0;
    for (size_t r = 0; r < receivers.size(); ++r) {
        const uint32_t expected = point.isTie(r, 0) ? 0u : (point.isBlocked(r, 0) ? 0xffffffffu : 0u);
        if (point.isTie(r, 0)) {
            ++ties;
            CHECK(result.ties[r] == 0xffffffffu);
            continue;
        }
        CHECK(result.blocked[r] == expected);
        CHECK(result.ties[r] == 0u);
        shadowed += expected != 0;
    }
    CHECK(shadowed > 0);
    MESSAGE("point light: ", shadowed, " of ", receivers.size(), " receivers in shadow, ", ties, " ties");
}

TEST_CASE("empty receivers, no triangles, bad arguments") {
    penumbra::Light light;
    light.center = dvec3(0, 2, 0);
    light.size = dvec3(0.3);
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {32, 3});
    const Mesh quad{{dvec3(-1, 1, -1), dvec3(1, 1, -1), dvec3(1, 1, 1), dvec3(-1, 1, 1)}, {0, 1, 2, 0, 2, 3}};

    const penumbra::PenumbraCastingResult empty = cast(quad, {}, light, sets);
    CHECK(empty.blocked.empty());
    CHECK(empty.receivers() == 0);
    CHECK(empty.stats.triangles == 2);
    CHECK(empty.stats.mask_bytes_full == 0);

    const std::vector<dvec3> receivers = {dvec3(0, 0, 0), dvec3(5, 0, 5), dvec3(0, 3, 0)};
    const penumbra::PenumbraCastingResult none = cast(Mesh{}, receivers, light, sets);
    CHECK(none.blocked == std::vector<uint32_t>(3, 0u));
    CHECK(none.ties == std::vector<uint32_t>(3, 0u));
    for (size_t r = 0; r < 3; ++r) CHECK(none.visibleFraction(r) == 1.0);
    CHECK(none.stats.mask_bytes_peak == 0);

    const penumbra::PenumbraCastingResult lit = cast(quad, receivers, light, sets, {}, {2, 1, 0});
    CHECK(lit.receiver_sets == std::vector<uint32_t>{2, 1, 0});
    CHECK(lit.visibleFraction(0) == 0.0);
    CHECK(lit.visibleFraction(1) == 1.0);
    CHECK(lit.visibleFraction(2) == 1.0);

    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(receivers, light, sets, {}, {0, 1}); }), "receiver_sets has 2"));
    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(receivers, light, sets, {}, {0, 3, 1}); }), "receiver_sets[1] = 3"));
    penumbra::PenumbraCastingOptions bad;
    bad.leaf_size = 0;
    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(receivers, light, sets, bad); }), "leaf_size"));
    bad = {};
    bad.group_size = 0;
    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(receivers, light, sets, bad); }), "group_size"));
    bad = {};
    bad.oracle.tie_epsilon = -1.0;
    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(receivers, light, sets, bad); }), "tie_epsilon"));
    const std::vector<dvec3> nan_receiver = {dvec3(0, std::numeric_limits<double>::quiet_NaN(), 0)};
    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(nan_receiver, light, sets); }), "receivers[0]"));
    penumbra::LightSampleSets short_sets = sets;
    short_sets.world.pop_back();
    CHECK(contains(errorOf([&] { penumbra::PenumbraCaster(receivers, light, short_sets); }), "sets.world holds 95"));
}

TEST_CASE("cancellation through the progress callback") {
    const penumbra::scene::Scene scene = penumbra::scene::hairball(20000, 2);
    const Mesh mesh = toMesh(scene.merged());
    const penumbra::Light light = lightsOf(scene)[2].second;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {64, 4});
    const std::vector<dvec3> receivers = surfacePoints(mesh, 3000, penumbra::test::testSeed(5));

    std::vector<double> fractions;
    penumbra::PenumbraCastingOptions options;
    options.batch_triangles = 5000;
    options.progress = [&](double f) {
        fractions.push_back(f);
        return true;
    };
    const penumbra::PenumbraCastingResult full = cast(mesh, receivers, light, sets, options);
    CHECK_FALSE(full.stats.cancelled);
    REQUIRE(!fractions.empty());
    CHECK(fractions.back() == 1.0);
    for (double f : fractions) CHECK((f >= 0.0 && f <= 1.0));

    size_t calls = 0, pulled = 0;
    options.progress = [&](double) { return ++calls < 3; };
    size_t t = 0;
    const penumbra::PenumbraCastingResult cut = penumbra::penumbraCast(
        receivers, light, sets,
        [&](dvec3& a, dvec3& b, dvec3& c) {
            if (t == mesh.triangles()) return false;
            a = mesh.positions[mesh.indices[3 * t]];
            b = mesh.positions[mesh.indices[3 * t + 1]];
            c = mesh.positions[mesh.indices[3 * t + 2]];
            ++t;
            ++pulled;
            return true;
        },
        options);
    CHECK(cut.stats.cancelled);
    CHECK(calls == 3);
    CHECK(pulled < mesh.triangles());  // penumbraCast stops pulling triangles
    CHECK(cut.stats.pairs_tested < full.stats.pairs_tested);
    MESSAGE("cancelled after ", pulled, " of ", mesh.triangles(), " triangles: ", cut.stats.pairs_tested, " of ",
            full.stats.pairs_tested, " pair tests done");
}

// Under ASan (tools/test.sh's second build) the times mean nothing and the run is ~10x slower:
// a quarter of the image each way still compares every bit with the oracle.
#if defined(__SANITIZE_ADDRESS__)
constexpr uint32_t kSpeedImageDivisor = 4;
#else
constexpr uint32_t kSpeedImageDivisor = 1;
#endif

TEST_CASE("speed: penumbra casting vs VisibilityOracle::evaluate, torus knot, primary-ray receivers") {
    const penumbra::scene::Scene scene = penumbra::scene::builtin("torus_knot");
    const Mesh mesh = toMesh(scene.merged());
    const penumbra::reference::VisibilityOracle oracle(mesh.positions, mesh.indices);
    const uint32_t width = (stressRun() ? 640 : 320) / kSpeedImageDivisor,
                   height = (stressRun() ? 480 : 240) / kSpeedImageDivisor;
    const glm::dmat4 view_projection =
        glm::dmat4(scene.camera.projection(float(width) / float(height))) * glm::dmat4(scene.camera.view());
    const glm::dmat4 inverse = glm::inverse(view_projection);
    std::vector<dvec3> receivers;
    std::vector<uint32_t> receiver_sets;
    const uint32_t k = 8;
    for (uint32_t y = 0; y < height; ++y)
        for (uint32_t x = 0; x < width; ++x) {
            const double ndc_x = (x + 0.5) / width * 2.0 - 1.0, ndc_y = (y + 0.5) / height * 2.0 - 1.0;
            const glm::dvec4 near = inverse * glm::dvec4(ndc_x, ndc_y, -1.0, 1.0);
            const glm::dvec4 far = inverse * glm::dvec4(ndc_x, ndc_y, 1.0, 1.0);
            const dvec3 origin = dvec3(near) / near.w;
            const dvec3 direction = dvec3(far) / far.w - origin;
            const penumbra::reference::Hit hit = oracle.closestHit(origin, direction, 0.0, 1.0);
            if (!hit.hit) continue;
            receivers.push_back(origin + hit.t * direction);
            receiver_sets.push_back(penumbra::lightSampleSet(x, y, 0, k));  // laine2005 §3.4 per pixel
        }
    const penumbra::Light light = lightsOf(scene)[0].second;  // disk
    penumbra::LightSampleOptions sample_options;
    sample_options.count = stressRun() ? 1024 : 256;
    sample_options.sets = k;
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, sample_options);

    const auto t0 = std::chrono::steady_clock::now();
    const penumbra::PenumbraCastingResult result = cast(mesh, receivers, light, sets, {}, receiver_sets);
    const auto t1 = std::chrono::steady_clock::now();
    const penumbra::reference::VisibilityResult truth = oracleTruth(oracle, receivers, receiver_sets, sets);
    const auto t2 = std::chrono::steady_clock::now();
    const Tally t = compare(result, truth);
    CHECK(t.mismatched == 0);
    CHECK(t.tie_mismatched == 0);
    const double cast_s = std::chrono::duration<double>(t1 - t0).count();
    const double oracle_s = std::chrono::duration<double>(t2 - t1).count();
    MESSAGE("torus knot ", width, "x", height, " (", receivers.size(), " receivers), N = ", sample_options.count, ", K = ", k,
            ", ", mesh.triangles(), " triangles, ", std::thread::hardware_concurrency(), " threads: penumbra casting ", cast_s,
            " s, oracle evaluate ", oracle_s, " s (", oracle_s / cast_s, "x); pairs classified ",
            result.stats.pairs_classified, ", certified ", result.stats.pairs_certified, " (hits ",
            result.stats.pairs_certified_hits, "), hard-culled ", result.stats.pairs_hard_culled, ", coplanar skips ",
            result.stats.coplanar_skips, ", pyramids ", result.stats.pyramids_built, ", V_i built ",
            result.stats.hard_volumes_built, ", masks peak ", result.stats.mask_bytes_peak, " of ", result.stats.mask_bytes_full, " bytes, rebuilds ",
            result.stats.rebuilds, ", ties ", t.ties);
}

TEST_CASE("far lights: with scene_extent = the oracle's E, the oracle's bits at 1e4 .. 1e9 (issue 41)") {
    // A floor y = 0 over [-2, 2]^2 (8 x 8 cells) and an occluder quad [-0.5, 0.5] x [-0.25, 0.25]
    // at y = 0.5; a sphere light of fixed angular size (radius 0.02 D) D away along u. The oracle
    // caps the segment's length in its tolerances at the scene's extent E = 4; the caster passes
    // classifySegment the same E, so its bits are the oracle's and the shadow stays. Uncapped
    // (the default), the coplanar reach 1e-7 |s - p| exceeds 0.5 past 5e6: no shadow at 1e9.
    Mesh mesh;
    const auto quad = [&](double x0, double x1, double z0, double z1, double y) {
        const uint32_t base = uint32_t(mesh.positions.size());
        mesh.positions.insert(mesh.positions.end(), {dvec3(x0, y, z0), dvec3(x0, y, z1), dvec3(x1, y, z1), dvec3(x1, y, z0)});
        mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
    };
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) quad(-2.0 + 0.5 * i, -1.5 + 0.5 * i, -2.0 + 0.5 * j, -1.5 + 0.5 * j, 0.0);
    quad(-0.5, 0.5, -0.25, 0.25, 0.5);
    const penumbra::reference::VisibilityOracle oracle(mesh.positions, mesh.indices);
    REQUIRE(oracle.sceneExtent() == 4.0);
    std::vector<dvec3> receivers;
    for (double y : {0.0, 1e-3, 0.2})
        for (int i = 0; i < 20; ++i)
            for (int j = 0; j < 20; ++j) receivers.push_back(dvec3(-1.9 + 0.19 * i + 0.0071, y, -1.9 + 0.19 * j + 0.0037));
    const dvec3 u = glm::normalize(dvec3(0.3, 1.0, -0.2));
    for (double distance : {1e4, 1e6, 1e9}) {
        CAPTURE(distance);
        penumbra::Light light;
        light.center = distance * u;
        light.size = dvec3(0.02 * distance);
        const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {64, 2});
        penumbra::PenumbraCastingOptions options;
        options.scene_extent = oracle.sceneExtent();
        const penumbra::PenumbraCastingResult result = cast(mesh, receivers, light, sets, options);
        const Tally t = compare(result, oracleTruth(oracle, receivers, result.receiver_sets, sets));
        penumbra::PenumbraCastingOptions uncapped;
        const Tally old = compare(cast(mesh, receivers, light, sets, uncapped),
                                  oracleTruth(oracle, receivers, result.receiver_sets, sets));
        MESSAGE("D = ", distance, ": ", t.pairs, " pairs, ", t.blocked, " blocked, ", t.ties, " ties, mismatched ",
                t.mismatched, ", tie mismatched ", t.tie_mismatched, "; uncapped: mismatched ", old.mismatched,
                "; certified ", result.stats.pairs_certified, ", classified ", result.stats.pairs_classified);
        CHECK(t.blocked > t.pairs / 50);
        CHECK(t.mismatched == 0);
        CHECK(t.tie_mismatched == 0);
        if (distance >= 1e9) CHECK(old.mismatched > 0);  // what E fixes
    }
    penumbra::Light light;
    light.center = dvec3(0, 5, 0);
    light.size = dvec3(0.1);
    const penumbra::LightSampleSets sets = penumbra::makeLightSampleSets(light, {32, 1});
    for (double bad : {0.0, -2.0, std::numeric_limits<double>::quiet_NaN()}) {
        penumbra::PenumbraCastingOptions options;
        options.scene_extent = bad;
        const std::string message = errorOf([&] { penumbra::PenumbraCaster(receivers, light, sets, options); });
        CAPTURE(message);
        CHECK(contains(message, "scene_extent"));
        CHECK(contains(message, bad == 0.0 ? "got 0" : bad < 0 ? "got -2" : "got nan"));
    }
}
