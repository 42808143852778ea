// Tests of the light-sample sets (penumbra/light_samples.hpp): strata, containment, the |q| bound
// the light-sample LUT relies on, K distinct sets, golden bits, the normalised space (toLocal /
// toWorld / planeToLocal), the symmetric flag, per-pixel selection and bad input. The GLSL twin of
// the selection is tested in light_samples_gl_test.cpp; the reference:: functions' own tests (and
// golden hashes) are in visibility_test.cpp.
//
// Random inputs come from support/test_support.hpp's testSeed(): fixed by default and printed;
// PENUMBRA_SEED=<n> replays a run, PENUMBRA_SEED=random draws fresh ones.
#include <penumbra/light_samples.hpp>
#include <penumbra/reference/light_samples.hpp>

#include "support/splitmix.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <set>
#include <string>
#include <vector>

namespace {

using glm::dvec3;
using glm::dvec4;
using penumbra::Light;
using penumbra::LightFrame;
using penumbra::LightSampleOptions;
using penumbra::LightSampleSets;
using penumbra::LightShape;
using penumbra::SamplePattern;
using penumbra::test::contains;
using penumbra::test::errorOf;
namespace ls = penumbra::detail::light_samples;

constexpr LightShape kShapes[] = {LightShape::Disk, LightShape::Rectangle, LightShape::Sphere, LightShape::Ellipsoid};
constexpr SamplePattern kPatterns[] = {SamplePattern::Stratified, SamplePattern::LowDiscrepancy};

const char* shapeName(LightShape s) {
    switch (s) {
        case LightShape::Disk: return "Disk";
        case LightShape::Rectangle: return "Rectangle";
        case LightShape::Sphere: return "Sphere";
        default: return "Ellipsoid";
    }
}

using Rng = penumbra::test::SplitMix64;

uint64_t hashSamples(const dvec3* samples, size_t n) {
    uint64_t h = 1469598103934665603ull;  // FNV-1a over the raw bits
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            uint64_t bits;
            std::memcpy(&bits, &samples[i][k], sizeof bits);
            for (int byte = 0; byte < 8; ++byte) {
                h ^= (bits >> (8 * byte)) & 0xffu;
                h *= 1099511628211ull;
            }
        }
    return h;
}

/// A random light of `shape`: anywhere, any orientation, sizes over three decades.
Light randomLight(Rng& rng, LightShape shape) {
    Light light;
    light.shape = shape;
    light.center = rng.point(-100, 100);
    light.axis_z = rng.point(-1, 1) + dvec3(0, 0, 0.05);
    light.axis_x = rng.point(-1, 1) + dvec3(0.05, 0, 0);
    light.size = dvec3(std::pow(10.0, rng.uniform(-1, 2)), std::pow(10.0, rng.uniform(-1, 2)),
                       std::pow(10.0, rng.uniform(-1, 2)));
    return light;
}

/// The stratified coordinate t in [0, 1] of local sample q (for the rectangle's Stratified grid
/// also the second, b) — the inverse of the header's maps.
struct Coordinates {
    double t = 0.0, b = 0.0;
};

Coordinates coordinates(const Light& light, const LightFrame& frame, const dvec3& q) {
    Coordinates c;
    switch (light.shape) {
        case LightShape::Sphere:
        case LightShape::Ellipsoid: c.t = std::pow(glm::length(q) / ls::kInset, 3.0); break;
        case LightShape::Disk: c.t = glm::dot(q, q) / (ls::kInset * ls::kInset); break;
        case LightShape::Rectangle: {
            const double ex = ls::kInset * light.size.x / frame.scale.x, ey = ls::kInset * light.size.y / frame.scale.x;
            c.t = (q.x / ex + 1.0) / 2.0;
            c.b = (q.y / ey + 1.0) / 2.0;
            break;
        }
    }
    return c;
}

bool inStratum(double t, uint32_t i, uint32_t n) {
    return t >= static_cast<double>(i) / n - 1e-9 && t <= static_cast<double>(i + 1) / n + 1e-9;
}

}  // namespace

TEST_SUITE("light_samples") {

// ================================================================================================
// Strata, containment, the bound

TEST_CASE("light samples: every stratum holds exactly one sample (both patterns, all shapes)") {
    Rng rng(penumbra::test::testSeed(10));
    for (LightShape shape : kShapes) {
        for (SamplePattern pattern : kPatterns) {
            for (uint32_t count : {32u, 96u, 128u, 160u, 1024u}) {
                const Light light = randomLight(rng, shape);
                LightSampleOptions options;
                options.count = count;
                options.sets = 3;
                options.pattern = pattern;
                options.seed = static_cast<uint32_t>(rng.next());
                CAPTURE(shapeName(shape));
                CAPTURE(static_cast<int>(pattern));
                CAPTURE(count);
                const LightSampleSets sets = penumbra::makeLightSampleSets(light, options);
                REQUIRE(sets.local.size() == size_t(count) * 3);
                uint32_t nu = 0, nv = 0;
                ls::rectGrid(count, light.size.x, light.size.y, nu, nv);
                size_t misplaced = 0;
                for (uint32_t s = 0; s < 3; ++s) {
                    // Sample i lies in stratum i: a bijection samples -> strata.
                    std::set<uint32_t> cells;
                    for (uint32_t i = 0; i < count; ++i) {
                        const Coordinates c = coordinates(light, sets.frame, sets.localSet(s)[i]);
                        if (shape == LightShape::Rectangle && pattern == SamplePattern::Stratified) {
                            misplaced += !inStratum(c.t, i % nu, nu) || !inStratum(c.b, i / nu, nv);
                            cells.insert(std::min(nu - 1, uint32_t(c.t * nu)) + nu * std::min(nv - 1, uint32_t(c.b * nv)));
                        } else {
                            misplaced += !inStratum(c.t, i, count);
                            cells.insert(std::min(count - 1, uint32_t(c.t * count)));
                        }
                    }
                    CHECK(cells.size() == count);
                }
                CHECK(misplaced == 0);
            }
        }
    }
}

TEST_CASE("light samples: the rectangle's grid has the squarest cells") {
    uint32_t nu = 0, nv = 0;
    ls::rectGrid(128, 1.0, 1.0, nu, nv);
    CHECK((nu == 8 && nv == 16));  // tie between 8 x 16 and 16 x 8: smaller nu
    ls::rectGrid(128, 2.0, 1.0, nu, nv);
    CHECK((nu == 16 && nv == 8));
    ls::rectGrid(1024, 1.0, 1.0, nu, nv);
    CHECK((nu == 32 && nv == 32));
    ls::rectGrid(96, 1.0, 1.5, nu, nv);
    CHECK((nu == 8 && nv == 12));
    ls::rectGrid(64, 1e6, 1.0, nu, nv);
    CHECK((nu == 64 && nv == 1));
}

TEST_CASE("light samples: LowDiscrepancy with N = 2^m is a (0, m, 2)-net in (t, u) and in (u, v)") {
    for (uint32_t m : {5u, 6u, 7u, 8u, 10u}) {
        const uint32_t n = 1u << m;
        for (uint32_t seed : {0u, 1u, 0xdeadbeefu}) {
            CAPTURE(n);
            CAPTURE(seed);
            std::vector<ls::CubePoint> points(n);
            for (uint32_t i = 0; i < n; ++i) points[i] = ls::lowDiscrepancyPoint(seed, n, i);
            for (uint32_t k = 0; k <= m; ++k) {
                std::set<uint32_t> tu, uv;
                for (const ls::CubePoint& p : points) {
                    tu.insert((uint32_t(p.t * (1u << k)) << (m - k)) | uint32_t(p.u * (1u << (m - k))));
                    uv.insert((uint32_t(p.u * (1u << k)) << (m - k)) | uint32_t(p.v * (1u << (m - k))));
                }
                CHECK(tu.size() == n);
                CHECK(uv.size() == n);
            }
        }
    }
}

TEST_CASE("light samples: every sample lies inside its shape, |q| <= 1 - 2^-20, planar shapes at q.z = 0") {
    Rng rng(penumbra::test::testSeed(20));
    double largest = 0.0;
    for (int trial = 0; trial < 40; ++trial) {
        for (LightShape shape : kShapes) {
            for (SamplePattern pattern : kPatterns) {
                const Light light = randomLight(rng, shape);
                LightSampleOptions options;
                options.count = 32u * (1u + static_cast<uint32_t>(rng.next() % 32));
                options.sets = 1u + static_cast<uint32_t>(rng.next() % 8);
                options.pattern = pattern;
                options.seed = static_cast<uint32_t>(rng.next());
                const LightSampleSets sets = penumbra::makeLightSampleSets(light, options);
                const glm::dmat3& r = sets.frame.rotation;
                size_t outside = 0, over_bound = 0, off_plane = 0;
                for (size_t i = 0; i < sets.local.size(); ++i) {
                    const dvec3& q = sets.local[i];
                    const double length = std::sqrt(glm::dot(q, q));
                    largest = std::max(largest, length);
                    over_bound += !(length <= penumbra::kLightSampleBound);
                    const dvec3 d = sets.world[i] - light.center;
                    // Coordinates along the light's own axes (world space, no normalised space).
                    const double x = glm::dot(d, r[0]), y = glm::dot(d, r[1]), z = glm::dot(d, r[2]);
                    const double tol = 1e-12 * (1.0 + glm::length(light.center));
                    switch (shape) {
                        case LightShape::Disk:
                            off_plane += q.z != 0.0 || std::abs(z) > tol;
                            outside += std::sqrt(x * x + y * y) > light.size.x;
                            break;
                        case LightShape::Rectangle:
                            off_plane += q.z != 0.0 || std::abs(z) > tol;
                            outside += std::abs(x) > light.size.x || std::abs(y) > light.size.y;
                            break;
                        case LightShape::Sphere: outside += glm::length(d) > light.size.x; break;
                        case LightShape::Ellipsoid: {
                            const double e = (x / light.size.x) * (x / light.size.x) + (y / light.size.y) * (y / light.size.y) +
                                             (z / light.size.z) * (z / light.size.z);
                            outside += e > 1.0;
                            break;
                        }
                    }
                }
                CAPTURE(shapeName(shape));
                CHECK(outside == 0);
                CHECK(over_bound == 0);
                CHECK(off_plane == 0);
            }
        }
    }
    MESSAGE("largest |q| ", largest, " (bound ", penumbra::kLightSampleBound, ")");
    CHECK(largest > 1.0 - 1e-3);  // the samples do reach the rim
}

TEST_CASE("light samples: set 0 of a Stratified sphere / disk is the reference:: pattern") {
    for (uint32_t seed : {0u, 42u}) {
        Light ball;  // unit sphere at the origin
        LightSampleOptions options;
        options.count = 256;
        options.sets = 2;
        options.seed = seed;
        const LightSampleSets sets = penumbra::makeLightSampleSets(ball, options);
        const std::vector<dvec3> old = penumbra::reference::sphereLightSamples(dvec3(0), 1.0, 256, seed);
        double worst = 0.0;
        for (uint32_t i = 0; i < 256; ++i) worst = std::max(worst, glm::length(sets.localSet(0)[i] - ls::kInset * old[i]));
        CHECK(worst < 1e-15);
        Light disk;
        disk.shape = LightShape::Disk;
        const LightSampleSets disk_sets = penumbra::makeLightSampleSets(disk, options);
        const std::vector<dvec3> old_disk = penumbra::reference::diskLightSamples(dvec3(0), dvec3(0, 0, 1), 1.0, 256, seed);
        worst = 0.0;
        for (uint32_t i = 0; i < 256; ++i)
            worst = std::max(worst, glm::length(disk_sets.localSet(0)[i] - ls::kInset * old_disk[i]));
        CHECK(worst < 1e-15);
    }
}

TEST_CASE("light samples: uniform over the light (means and halves)") {
    for (LightShape shape : kShapes) {
        for (SamplePattern pattern : kPatterns) {
            Light light;
            light.shape = shape;
            LightSampleOptions options;
            options.count = 1024;
            options.sets = 4;
            options.pattern = pattern;
            const LightSampleSets sets = penumbra::makeLightSampleSets(light, options);
            dvec3 mean(0.0);
            size_t positive_x = 0, positive_y = 0;
            for (const dvec3& q : sets.local) {
                mean += q;
                positive_x += q.x > 0;
                positive_y += q.y > 0;
            }
            mean /= double(sets.local.size());
            CAPTURE(shapeName(shape));
            CAPTURE(static_cast<int>(pattern));
            CHECK(glm::length(mean) < 0.01);
            CHECK(std::abs(double(positive_x) / sets.local.size() - 0.5) < 0.02);
            CHECK(std::abs(double(positive_y) / sets.local.size() - 0.5) < 0.02);
        }
    }
}

// ================================================================================================
// Sets, determinism, the normalised space

TEST_CASE("light samples: the K sets are pairwise distinct") {
    for (LightShape shape : kShapes) {
        for (SamplePattern pattern : kPatterns) {
            Light light;
            light.shape = shape;
            LightSampleOptions options;
            options.count = 32;
            options.sets = 64;
            options.pattern = pattern;
            options.seed = 7;
            const LightSampleSets sets = penumbra::makeLightSampleSets(light, options);
            std::set<uint64_t> hashes;
            size_t shared_samples = 0;
            for (uint32_t s = 0; s < sets.sets(); ++s) {
                hashes.insert(hashSamples(sets.localSet(s), sets.count()));
                for (uint32_t t = 0; t < s; ++t)
                    for (uint32_t i = 0; i < sets.count(); ++i) shared_samples += sets.localSet(s)[i] == sets.localSet(t)[i];
            }
            CAPTURE(shapeName(shape));
            CHECK(hashes.size() == 64);
            CHECK(shared_samples == 0);  // not even one sample in common
        }
    }
}

TEST_CASE("light samples: bit-identical on every platform (golden values)") {
    // Computed once on x86-64 (glibc, GCC); any IEEE-754 platform and any -ffp-contract must
    // reproduce them (integer sequences, cosSinTurns, cubeRoot, explicit fma, opaque products).
    Light ellipsoid;
    ellipsoid.shape = LightShape::Ellipsoid;
    ellipsoid.center = dvec3(1, 2, 3);
    ellipsoid.axis_z = dvec3(0.2, -0.3, 1);
    ellipsoid.axis_x = dvec3(1, 0.1, 0);
    ellipsoid.size = dvec3(0.5, 0.25, 0.125);
    Light rect = ellipsoid;
    rect.shape = LightShape::Rectangle;
    Light disk = ellipsoid;
    disk.shape = LightShape::Disk;
    LightSampleOptions stratified;
    stratified.count = 128;
    stratified.sets = 4;
    stratified.seed = 11;
    LightSampleOptions low = stratified;
    low.pattern = SamplePattern::LowDiscrepancy;
    const LightSampleSets a = penumbra::makeLightSampleSets(ellipsoid, stratified);
    const LightSampleSets b = penumbra::makeLightSampleSets(rect, low);
    const LightSampleSets c = penumbra::makeLightSampleSets(disk, low);
    const LightSampleSets d = penumbra::makeLightSampleSets(rect, stratified);
    const uint64_t golden[][2] = {
        {hashSamples(a.localSet(0), 128), hashSamples(a.worldSet(3), 128)},
        {hashSamples(b.localSet(1), 128), hashSamples(b.worldSet(2), 128)},
        {hashSamples(c.localSet(2), 128), hashSamples(c.worldSet(0), 128)},
        {hashSamples(d.localSet(3), 128), hashSamples(d.worldSet(1), 128)},
    };
    CHECK(golden[0][0] == 1371761416185098202ull);
    CHECK(golden[0][1] == 11165246898973859978ull);
    CHECK(golden[1][0] == 2734352315644684090ull);
    CHECK(golden[1][1] == 5006553489894661386ull);
    CHECK(golden[2][0] == 18381302583656323161ull);
    CHECK(golden[2][1] == 5203166548827503213ull);
    CHECK(golden[3][0] == 1321723804587343554ull);
    CHECK(golden[3][1] == 11246636553031015823ull);
    // Same inputs, same bits (a second run).
    CHECK(hashSamples(a.world.data(), a.world.size()) ==
          hashSamples(penumbra::makeLightSampleSets(ellipsoid, stratified).world.data(), a.world.size()));
}

TEST_CASE("light samples: world == toWorld(local) bit for bit; toLocal inverts it") {
    Rng rng(penumbra::test::testSeed(30));
    for (LightShape shape : kShapes) {
        const Light light = randomLight(rng, shape);
        LightSampleOptions options;
        options.sets = 2;
        const LightSampleSets sets = penumbra::makeLightSampleSets(light, options);
        size_t differ = 0;
        double worst = 0.0;
        for (size_t i = 0; i < sets.local.size(); ++i) {
            differ += !(sets.world[i] == sets.frame.toWorld(sets.local[i]));
            worst = std::max(worst, glm::length(sets.frame.toLocal(sets.world[i]) - sets.local[i]));
        }
        CAPTURE(shapeName(shape));
        CHECK(differ == 0);
        CHECK(worst < 1e-9);  // |centre| <= 100 and sizes >= 0.1: relative 1e-14 of the coordinates
    }
}

TEST_CASE("light frame: orthonormal right-handed rotation from axis_z / axis_x; scale per shape") {
    Rng rng(penumbra::test::testSeed(40));
    for (int trial = 0; trial < 200; ++trial) {
        const Light light = randomLight(rng, kShapes[trial % 4]);
        const LightFrame frame = penumbra::lightFrame(light);
        const dvec3 x = frame.rotation[0], y = frame.rotation[1], z = frame.rotation[2];
        CHECK(std::abs(glm::length(x) - 1.0) < 1e-15);
        CHECK(std::abs(glm::length(y) - 1.0) < 1e-15);
        CHECK(std::abs(glm::length(z) - 1.0) < 1e-15);
        CHECK(std::abs(glm::dot(x, y)) < 1e-15);
        CHECK(std::abs(glm::dot(x, z)) < 1e-15);
        CHECK(std::abs(glm::dot(y, z)) < 1e-15);
        CHECK(glm::length(glm::cross(x, y) - z) < 1e-15);
        CHECK(glm::length(z - glm::normalize(light.axis_z)) < 1e-15);
        CHECK(glm::dot(x, light.axis_x) > 0.0);                               // same side as axis_x
        CHECK(std::abs(glm::dot(glm::normalize(glm::cross(light.axis_z, light.axis_x)), x)) < 1e-12);  // x in span(axis_x, z)
    }
    Light rect;
    rect.shape = LightShape::Rectangle;
    rect.size = dvec3(3, 4, 99);
    CHECK(penumbra::lightFrame(rect).scale == dvec3(5.0));
    Light disk;
    disk.shape = LightShape::Disk;
    disk.size = dvec3(2, 0, -1);  // only x is used
    CHECK(penumbra::lightFrame(disk).scale == dvec3(2.0));
    Light ellipsoid;
    ellipsoid.shape = LightShape::Ellipsoid;
    ellipsoid.size = dvec3(1, 2, 3);
    CHECK(penumbra::lightFrame(ellipsoid).scale == dvec3(1, 2, 3));
    // Tiny and huge axes are fine (scaled before squaring).
    Light tiny;
    tiny.axis_z = dvec3(0, 0, 1e-300);
    tiny.axis_x = dvec3(1e300, 0, 0);
    CHECK(penumbra::lightFrame(tiny).rotation == glm::dmat3(1.0));
}

TEST_CASE("light frame: planeToLocal keeps the sign of every point's plane value; d' is the centre's distance") {
    Rng rng(penumbra::test::testSeed(50));
    size_t compared = 0, wrong = 0;
    for (int trial = 0; trial < 400; ++trial) {
        Light light = randomLight(rng, kShapes[trial % 4]);
        if (trial % 8 == 3) light.size = dvec3(0.1, 7.0, 40.0);  // strongly non-uniform ellipsoid
        const LightFrame frame = penumbra::lightFrame(light);
        // A plane through a point near the light, random normal (not unit), random scale.
        const dvec3 n = rng.point(-1, 1) * std::pow(10.0, rng.uniform(-3, 3));
        const dvec3 through = light.center + rng.point(-2, 2) * light.size;
        const dvec4 world_plane(n, -glm::dot(n, through));
        const dvec4 local_plane = frame.planeToLocal(world_plane);
        CHECK(std::abs(glm::length(dvec3(local_plane)) - 1.0) < 1e-14);
        for (int k = 0; k < 50; ++k) {
            const dvec3 q = rng.point(-1.5, 1.5);
            const dvec3 p = frame.toWorld(q);
            const double world_value = glm::dot(n, p) + world_plane.w;
            const double local_value = glm::dot(dvec3(local_plane), q) + local_plane.w;
            // Skip points within rounding of the plane.
            if (std::abs(world_value) < 1e-9 * glm::length(n) * (glm::length(p) + glm::length(through))) continue;
            ++compared;
            wrong += (world_value > 0) != (local_value > 0);
        }
    }
    MESSAGE(compared, " points compared");
    CHECK(wrong == 0);
    CHECK(compared > 15000);
    // d': a sphere of radius 2 and planes at distance 0, 2 (tangent) and 6 from its centre.
    Light sphere;
    sphere.center = dvec3(1, 1, 1);
    sphere.size = dvec3(2.0);
    const LightFrame frame = penumbra::lightFrame(sphere);
    CHECK(frame.planeToLocal(dvec4(0, 0, 3, -3)).w == doctest::Approx(0.0));
    CHECK(frame.planeToLocal(dvec4(0, 0, 3, 3)).w == doctest::Approx(1.0));    // z = -1: tangent below
    CHECK(frame.planeToLocal(dvec4(0, -1, 0, 7)).w == doctest::Approx(3.0));   // y = 7: 6 away, 3 radii
    // Ellipsoid semi-axes 1, 2, 4 along x, y, z: the plane z = c + 4 is tangent, |d'| = 1.
    Light e;
    e.shape = LightShape::Ellipsoid;
    e.size = dvec3(1, 2, 4);
    const dvec4 tangent = penumbra::lightFrame(e).planeToLocal(dvec4(0, 0, 1, -4));
    CHECK(tangent.w == doctest::Approx(-1.0));
    CHECK(tangent.z == doctest::Approx(1.0));
    // Bad planes.
    CHECK(contains(errorOf([&] { frame.planeToLocal(dvec4(0, 0, 0, 1)); }), "non-zero"));
    CHECK(contains(errorOf([&] { frame.planeToLocal(dvec4(0, NAN, 1, 1)); }), "world_plane"));
}

TEST_CASE("light frame: the symmetric flag") {
    Light light;
    CHECK(penumbra::lightFrame(light).symmetric);  // sphere
    light.shape = LightShape::Disk;
    CHECK(penumbra::lightFrame(light).symmetric);
    light.shape = LightShape::Rectangle;
    light.size = dvec3(1, 1, 1);  // even a square is not rotation-invariant
    CHECK(!penumbra::lightFrame(light).symmetric);
    light.shape = LightShape::Ellipsoid;
    light.size = dvec3(2, 2, 5);
    CHECK(penumbra::lightFrame(light).symmetric);
    light.size = dvec3(2, 3, 2);
    CHECK(!penumbra::lightFrame(light).symmetric);
    light.size = dvec3(2, 2, 2);
    CHECK(penumbra::lightFrame(light).symmetric);
}

// ================================================================================================
// Per-pixel selection

TEST_CASE("light sample selection: 8 neighbours use other sets (sets >= 4); every set once in K frames") {
    for (uint32_t sets = 1; sets <= 64; ++sets) {
        CAPTURE(sets);
        const uint32_t c = penumbra::lightSampleSetStride(sets);
        if (sets >= 4) CHECK((c >= 2 && c <= sets - 2));
        size_t out_of_range = 0, same_neighbour = 0, missing = 0;
        for (uint32_t frame : {0u, 1u, 5u, 1000003u}) {
            for (uint32_t y = 0; y < 70; ++y)
                for (uint32_t x = 0; x < 70; ++x) {
                    const uint32_t s = penumbra::lightSampleSet(x, y, frame, sets);
                    out_of_range += s >= std::max(sets, 1u);
                    if (sets < 4 || x == 0 || y == 0) continue;
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            if (dx == 0 && dy == 0) continue;
                            same_neighbour += s == penumbra::lightSampleSet(x + dx, y + dy, frame, sets);
                        }
                }
        }
        // Far from the origin too (no overflow in the pattern).
        for (uint32_t y = 0xfffffff0u; y < 0xffffffffu; ++y)
            for (uint32_t x = 0xfffff000u; x < 0xfffff010u; ++x) {
                const uint32_t s = penumbra::lightSampleSet(x, y, 3, sets);
                if (sets >= 4) same_neighbour += s == penumbra::lightSampleSet(x + 1, y + 1, 3, sets);
            }
        // Temporal: each pixel takes every set once in `sets` consecutive frames.
        for (uint32_t y = 0; y < 8; ++y)
            for (uint32_t x = 0; x < 8; ++x) {
                std::set<uint32_t> seen;
                for (uint32_t f = 17; f < 17 + sets; ++f) seen.insert(penumbra::lightSampleSet(x, y, f, sets));
                missing += seen.size() != sets;
            }
        CHECK(out_of_range == 0);
        CHECK(same_neighbour == 0);
        CHECK(missing == 0);
    }
    CHECK(penumbra::lightSampleSet(5, 7, 9, 0) == 0u);
    CHECK(penumbra::lightSampleSet(5, 7, 9, 1) == 0u);
    CHECK(penumbra::lightSampleSetStride(5) == 3u);  // the brief's (x + 3y + frame) mod 5
    CHECK(penumbra::lightSampleSetStride(8) == 5u);
}

TEST_CASE("light sample rotation: hash -> turns in [0, 1), uniform, float twin truncated") {
    std::vector<size_t> bins(16, 0);
    size_t out_of_range = 0, float_mismatch = 0, total = 0;
    std::set<uint32_t> distinct;
    for (uint32_t frame = 0; frame < 4; ++frame)
        for (uint32_t y = 0; y < 64; ++y)
            for (uint32_t x = 0; x < 64; ++x) {
                const uint32_t h = penumbra::lightSampleRotationHash(x, y, frame, 99);
                const double t = penumbra::lightSampleRotationTurns(x, y, frame, 99);
                const float tf = penumbra::lightSampleRotationTurnsFloat(x, y, frame, 99);
                out_of_range += !(t >= 0.0 && t < 1.0) || !(tf >= 0.0f && tf < 1.0f);
                float_mismatch += t != h * 0x1.0p-32 || double(tf) != double(h >> 8) * 0x1.0p-24;
                ++bins[static_cast<size_t>(t * 16)];
                distinct.insert(h);
                ++total;
            }
    CHECK(out_of_range == 0);
    CHECK(float_mismatch == 0);
    for (size_t b : bins) CHECK(std::abs(double(b) / total - 1.0 / 16) < 0.1 / 16);
    CHECK(distinct.size() > total - 10);  // a 32-bit hash: collisions are rare
    // The extremes stay below 1 (2^32 - 1 -> float would round to 1.0f without the truncation).
    CHECK(0xffffffffu * 0x1.0p-32 < 1.0);
    CHECK(float(0xffffffffu >> 8) * 0x1.0p-24f < 1.0f);
    // The seed, the frame and both coordinates change the hash.
    const uint32_t h = penumbra::lightSampleRotationHash(3, 4, 5, 6);
    CHECK(h != penumbra::lightSampleRotationHash(3, 4, 5, 7));
    CHECK(h != penumbra::lightSampleRotationHash(3, 4, 6, 6));
    CHECK(h != penumbra::lightSampleRotationHash(4, 3, 5, 6));
    CHECK(h != penumbra::lightSampleRotationHash(3, 5, 5, 6));
    // Golden values (the GLSL twin must give the same; light_samples_gl_test.cpp).
    CHECK(h == 1068723664u);
    CHECK(penumbra::lightSampleRotationHash(0, 0, 0, 0) == 1106484830u);
}

// ================================================================================================
// Bad input: one case each

TEST_CASE("bad input: count not a multiple of 32") {
    LightSampleOptions o;
    o.count = 100;
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "options.count"));
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "got 100"));
}

TEST_CASE("bad input: count below 32 or above 1024") {
    LightSampleOptions o;
    o.count = 0;
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "options.count"));
    o.count = 16;
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "got 16"));
    o.count = 1056;
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "got 1056"));
    o.count = 1024;
    CHECK(penumbra::makeLightSampleSets(Light{}, o).local.size() == 1024u * 8u);
    o.count = 32;
    CHECK(penumbra::makeLightSampleSets(Light{}, o).local.size() == 32u * 8u);
}

TEST_CASE("bad input: sets 0 or above 64") {
    LightSampleOptions o;
    o.sets = 0;
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "options.sets"));
    o.sets = 65;
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "got 65"));
    o.sets = 64;
    CHECK(penumbra::makeLightSampleSets(Light{}, o).sets() == 64u);
}

TEST_CASE("bad input: unknown shape or pattern") {
    Light light;
    light.shape = static_cast<LightShape>(4);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.shape"));
    LightSampleOptions o;
    o.pattern = static_cast<SamplePattern>(2);
    CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(Light{}, o); }), "options.pattern"));
}

TEST_CASE("bad input: zero radius (unlike the reference:: point light)") {
    for (LightShape shape : {LightShape::Disk, LightShape::Sphere}) {
        Light light;
        light.shape = shape;
        light.size = dvec3(0, 1, 1);
        CHECK(contains(errorOf([&] { penumbra::makeLightSampleSets(light); }), "light.size.x"));
    }
    CHECK(penumbra::reference::sphereLightSamples(dvec3(0), 0.0, 64).size() == 1);  // kept
}

TEST_CASE("bad input: negative size") {
    Light light;
    light.shape = LightShape::Rectangle;
    light.size = dvec3(1, -2, 1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.size.y"));
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "-2"));
    light.shape = LightShape::Sphere;
    light.size = dvec3(-1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.size.x"));
}

TEST_CASE("bad input: NaN or infinite size") {
    Light light;
    light.shape = LightShape::Disk;
    light.size = dvec3(NAN, 1, 1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.size.x"));
    light.shape = LightShape::Rectangle;
    light.size = dvec3(1, INFINITY, 1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.size.y"));
    light.size = dvec3(1.5e308, 1.5e308, 1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "half-diagonal"));
}

TEST_CASE("bad input: non-finite centre") {
    Light light;
    light.center = dvec3(0, INFINITY, 0);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.center"));
}

TEST_CASE("bad input: non-finite axes") {
    Light light;
    light.axis_z = dvec3(NAN, 0, 1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.axis_z"));
    light = Light{};
    light.axis_x = dvec3(1, -INFINITY, 0);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.axis_x"));
}

TEST_CASE("bad input: zero axes") {
    Light light;
    light.axis_z = dvec3(0);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.axis_z must be non-zero"));
    light = Light{};
    light.axis_x = dvec3(0);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.axis_x must be non-zero"));
}

TEST_CASE("bad input: parallel axes") {
    Light light;
    light.axis_z = dvec3(1, 2, 3);
    light.axis_x = dvec3(-2, -4, -6);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "parallel"));
    light.axis_x = dvec3(1, 2, 3 + 1e-8);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "parallel"));
    light.axis_x = dvec3(1, 2, 3.001);  // nearly parallel but clear of the threshold: accepted
    CHECK(penumbra::lightFrame(light).rotation[0].x != 0.0);
}

TEST_CASE("bad input: degenerate ellipsoid") {
    Light light;
    light.shape = LightShape::Ellipsoid;
    light.size = dvec3(1, 1, 0);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.size.z"));
    light.size = dvec3(1, -1, 1);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "light.size.y"));
    light.size = dvec3(0.5, 1, 500001);
    CHECK(contains(errorOf([&] { penumbra::lightFrame(light); }), "degenerate Ellipsoid"));
    light.size = dvec3(0.5, 1, 500000);  // ratio exactly 1e6: accepted
    CHECK(penumbra::lightFrame(light).scale == dvec3(0.5, 1, 500000));
}

}  // TEST_SUITE
