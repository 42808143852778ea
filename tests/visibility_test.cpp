// Tests of the visibility oracle (reference/visibility.hpp) and the light-sample sets
// (reference/light_samples.hpp): closed forms, BVH vs brute force bit for bit, translations far
// from the origin, watertight closed meshes, thread-count determinism, closest hits, bad input.
//
// Random inputs come from support/test_support.hpp's testSeed(): fixed by default and printed;
// PENUMBRA_SEED=<n> replays a run, PENUMBRA_SEED=random draws fresh ones. Heavier sweeps live in test suite "stress" and are skipped unless PENUMBRA_STRESS=1
// (as ctest's stress entry sets) or --no-skip is given:
//     PENUMBRA_STRESS=1 visibility_test --test-suite=stress
#include <penumbra/reference/light_samples.hpp>
#include <penumbra/reference/visibility.hpp>

#include "support/splitmix.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace {

using glm::dvec3;
using penumbra::reference::diskLightSamples;
using penumbra::reference::Hit;
using penumbra::reference::rectLightSamples;
using penumbra::reference::sphereLightSamples;
using penumbra::reference::VisibilityOptions;
using penumbra::reference::VisibilityOracle;
using penumbra::reference::VisibilityResult;
using penumbra::test::contains;
using penumbra::test::errorOf;

// ------------------------------------------------------------------------------------------------
// Helpers

/// The stress suite runs only when asked for (ctest -L stress sets PENUMBRA_STRESS=1).
bool stressRequested() {
    const char* env = std::getenv("PENUMBRA_STRESS");
    return env && std::strcmp(env, "1") == 0;
}

using Rng = penumbra::test::SplitMix64;

struct Mesh {
    std::vector<dvec3> positions;
    std::vector<uint32_t> indices;

    uint32_t add(const dvec3& p) {
        positions.push_back(p);
        return static_cast<uint32_t>(positions.size() - 1);
    }
    void triangle(const dvec3& a, const dvec3& b, const dvec3& c) {
        indices.push_back(add(a));
        indices.push_back(add(b));
        indices.push_back(add(c));
    }
    /// a b c d in order around the quad; `other_diagonal` splits along b-d instead of a-c.
    void quad(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& d, bool other_diagonal = false) {
        if (other_diagonal) {
            triangle(a, b, d);
            triangle(b, c, d);
        } else {
            triangle(a, b, c);
            triangle(a, c, d);
        }
    }
    /// z = const grid of nx x ny quads over [x0, x1] x [y0, y1], alternating diagonals.
    void gridZ(double x0, double x1, double y0, double y1, double z, int nx, int ny) {
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const double xa = x0 + (x1 - x0) * i / nx, xb = x0 + (x1 - x0) * (i + 1) / nx;
                const double ya = y0 + (y1 - y0) * j / ny, yb = y0 + (y1 - y0) * (j + 1) / ny;
                quad({xa, ya, z}, {xb, ya, z}, {xb, yb, z}, {xa, yb, z}, (i + j) % 2 == 1);
            }
    }
    size_t triangleCount() const { return indices.size() / 3; }
    dvec3 vertex(size_t triangle, int k) const { return positions[indices[3 * triangle + k]]; }
    void translate(const dvec3& offset) {
        for (dvec3& p : positions) p += offset;
    }
};

/// Triangles of random size and orientation around random centres in [-1, 1]^3.
Mesh randomSoup(Rng& rng, size_t count) {
    Mesh mesh;
    const double size_max = 0.6 * std::min(1.0, std::sqrt(200.0 / std::max<double>(1.0, count)));
    for (size_t i = 0; i < count; ++i) {
        const dvec3 centre = rng.point(-1.0, 1.0);
        const double size = size_max * std::exp(rng.uniform(std::log(1.0 / 30.0), 0.0));
        mesh.triangle(centre + size * rng.point(-1, 1), centre + size * rng.point(-1, 1),
                      centre + size * rng.point(-1, 1));
    }
    return mesh;
}

/// A point on a random triangle of the mesh (barycentric, so it lies on the surface up to rounding).
dvec3 pointOnMesh(Rng& rng, const Mesh& mesh) {
    const size_t t = rng.below(static_cast<uint32_t>(mesh.triangleCount()));
    double a = rng.uniform(), b = rng.uniform();
    if (a + b > 1.0) {
        a = 1.0 - a;
        b = 1.0 - b;
    }
    return mesh.vertex(t, 0) + a * (mesh.vertex(t, 1) - mesh.vertex(t, 0)) + b * (mesh.vertex(t, 2) - mesh.vertex(t, 0));
}

/// Receivers: mostly in space, a third on the mesh (exercising the coplanar rule).
std::vector<dvec3> randomReceivers(Rng& rng, const Mesh& mesh, size_t count) {
    std::vector<dvec3> points;
    for (size_t i = 0; i < count; ++i)
        points.push_back(mesh.triangleCount() > 0 && i % 3 == 2 ? pointOnMesh(rng, mesh) : rng.point(-1.3, 1.3));
    return points;
}

/// Light samples: a ball light somewhere around the soup plus a few samples on the mesh.
std::vector<dvec3> randomSamples(Rng& rng, const Mesh& mesh, uint32_t count) {
    std::vector<dvec3> samples =
        sphereLightSamples(rng.point(-1.5, 1.5), rng.uniform(0.05, 0.5), count, static_cast<uint32_t>(rng.next()));
    for (size_t i = 0; i < samples.size(); i += 7)
        if (mesh.triangleCount() > 0) samples[i] = pointOnMesh(rng, mesh);
    return samples;
}

/// Integer-lattice soup: vertices, receivers and samples on a 1/2 lattice, so many segments pass
/// exactly through vertices, along edges and through planes: the tie and coplanar paths.
Mesh latticeSoup(Rng& rng, size_t count, int n) {
    Mesh mesh;
    const auto lattice = [&] {
        return dvec3(rng.below(n + 1), rng.below(n + 1), rng.below(n + 1));
    };
    for (size_t i = 0; i < count; ++i) mesh.triangle(lattice(), lattice(), lattice());
    return mesh;
}

std::vector<dvec3> latticePoints(Rng& rng, size_t count, int n) {
    std::vector<dvec3> points;
    for (size_t i = 0; i < count; ++i)
        points.push_back(dvec3(rng.below(2 * n + 1), rng.below(2 * n + 1), rng.below(2 * n + 1)) * 0.5);
    return points;
}

uint32_t popcount(uint32_t x) {
    uint32_t c = 0;
    for (; x; x &= x - 1) ++c;
    return c;
}

/// Every bit of both masks, reporting the first difference.
void checkIdentical(const VisibilityResult& a, const VisibilityResult& b, const std::string& what) {
    INFO(what);
    REQUIRE(a.receivers == b.receivers);
    REQUIRE(a.samples == b.samples);
    REQUIRE(a.words_per_receiver == b.words_per_receiver);
    REQUIRE(a.blocked.size() == b.blocked.size());
    REQUIRE(a.ties.size() == b.ties.size());
    uint64_t blocked_diff = 0, tie_diff = 0;
    std::string first;
    for (size_t i = 0; i < a.blocked.size(); ++i) {
        const uint32_t db = a.blocked[i] ^ b.blocked[i], dt = a.ties[i] ^ b.ties[i];
        blocked_diff += popcount(db);
        tie_diff += popcount(dt);
        if ((db | dt) && first.empty()) {
            const size_t r = i / a.words_per_receiver;
            int bit = 0;
            while (!(((db | dt) >> bit) & 1u)) ++bit;
            const size_t s = (i % a.words_per_receiver) * 32 + bit;
            first = "receiver " + std::to_string(r) + " sample " + std::to_string(s) + " blocked " +
                    std::to_string(a.isBlocked(r, s)) + "/" + std::to_string(b.isBlocked(r, s)) + " tie " +
                    std::to_string(a.isTie(r, s)) + "/" + std::to_string(b.isTie(r, s));
        }
    }
    INFO("first difference: " << first);
    CHECK(blocked_diff == 0);
    CHECK(tie_diff == 0);
    CHECK(a.tie_count == b.tie_count);
}

uint64_t hashSamples(const std::vector<dvec3>& samples) {
    uint64_t h = 1469598103934665603ull;  // FNV-1a over the raw bits
    for (const dvec3& s : samples)
        for (int k = 0; k < 3; ++k) {
            uint64_t bits;
            std::memcpy(&bits, &s[k], sizeof bits);
            for (int byte = 0; byte < 8; ++byte) {
                h ^= (bits >> (8 * byte)) & 0xffu;
                h *= 1099511628211ull;
            }
        }
    return h;
}

/// Closed cube [-h, h]^3, each face an n x n grid of quads with alternating diagonals. Vertices
/// on the cube's edges are duplicated per face but bit-identical (dyadic when h, n allow).
Mesh tessellatedBox(double h, int n) {
    Mesh mesh;
    for (int axis = 0; axis < 3; ++axis)
        for (double side : {-h, h}) {
            const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
            const auto at = [&](int i, int j) {
                dvec3 p(0.0);
                p[axis] = side;
                p[ua] = -h + 2 * h * i / n;
                p[va] = -h + 2 * h * j / n;
                return p;
            };
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i)
                    mesh.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), (i + j) % 2 == 1);
        }
    return mesh;
}

/// Icosphere with shared (indexed) vertices.
Mesh icosphere(int subdivisions) {
    Mesh mesh;
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    for (const dvec3& p : {dvec3(-1, t, 0), dvec3(1, t, 0), dvec3(-1, -t, 0), dvec3(1, -t, 0), dvec3(0, -1, t),
                           dvec3(0, 1, t), dvec3(0, -1, -t), dvec3(0, 1, -t), dvec3(t, 0, -1), dvec3(t, 0, 1),
                           dvec3(-t, 0, -1), dvec3(-t, 0, 1)})
        mesh.positions.push_back(glm::normalize(p));
    mesh.indices = {0, 11, 5, 0, 5,  1,  0,  1, 7, 0,  7,  10, 0, 10, 11, 1, 5, 9, 5, 11, 4,  11, 10, 2,  10, 7, 6, 7, 1, 8,
                    3, 9,  4, 3, 4,  2,  3,  2, 6, 3,  6,  8,  3, 8,  9,  4, 9, 5, 2, 4,  11, 6,  2,  10, 8,  6, 7, 9, 8, 1};
    for (int level = 0; level < subdivisions; ++level) {
        std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
        const auto midpoint = [&](uint32_t a, uint32_t b) {
            const auto key = std::make_pair(std::min(a, b), std::max(a, b));
            const auto found = midpoints.find(key);
            if (found != midpoints.end()) return found->second;
            const uint32_t index = mesh.add(glm::normalize(mesh.positions[a] + mesh.positions[b]));
            midpoints[key] = index;
            return index;
        };
        std::vector<uint32_t> next;
        for (size_t i = 0; i < mesh.indices.size(); i += 3) {
            const uint32_t a = mesh.indices[i], b = mesh.indices[i + 1], c = mesh.indices[i + 2];
            const uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
            next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
        }
        mesh.indices = std::move(next);
    }
    return mesh;
}

/// Points exactly on (or rounded onto) the mesh's edges and vertices: every vertex, every edge
/// midpoint, and a random point on every edge.
std::vector<dvec3> edgeTargets(Rng& rng, const Mesh& mesh) {
    std::vector<dvec3> targets;
    for (size_t t = 0; t < mesh.triangleCount(); ++t)
        for (int k = 0; k < 3; ++k) {
            const dvec3 a = mesh.vertex(t, k), b = mesh.vertex(t, (k + 1) % 3);
            targets.push_back(a);
            targets.push_back((a + b) * 0.5);
            targets.push_back(a + rng.uniform() * (b - a));
        }
    return targets;
}

/// Every segment from an interior receiver p through a surface target q to 2q - p (or p + k (q - p))
/// leaves the closed convex mesh, so it must be blocked; the reverse direction too.
void checkNoLeaks(Rng& rng, const Mesh& mesh, const std::vector<dvec3>& interior, double stretch, size_t max_targets) {
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    std::vector<dvec3> targets = edgeTargets(rng, mesh);
    if (targets.size() > max_targets) {
        for (size_t i = 0; i < max_targets; ++i) std::swap(targets[i], targets[i + rng.below(uint32_t(targets.size() - i))]);
        targets.resize(max_targets);
    }
    size_t leaks = 0, pairs = 0, ties = 0;
    for (const dvec3& p : interior) {
        std::vector<dvec3> outside;
        for (const dvec3& q : targets) outside.push_back(p + stretch * (q - p));
        const VisibilityResult result = oracle.evaluate({p}, outside);
        // Brute force on a prefix only: it costs segments x triangles.
        const std::vector<dvec3> prefix(outside.begin(), outside.begin() + std::min<size_t>(outside.size(), 1000));
        checkIdentical(oracle.evaluate({p}, prefix), oracle.evaluateBruteForce({p}, prefix), "closed mesh");
        for (size_t s = 0; s < outside.size(); ++s) {
            ++pairs;
            leaks += !result.isBlocked(0, s);
        }
        ties += result.tie_count;
        // Reverse: receiver outside, light sample inside.
        for (size_t s = 0; s < outside.size(); s += 5) leaks += !oracle.segmentBlocked(outside[s], p);
    }
    MESSAGE(pairs << " segments through edges and vertices, " << ties << " ties, " << leaks << " leaks");
    CHECK(leaks == 0);
}

}  // namespace

// ================================================================================================
// Light samples

TEST_SUITE("visibility") {

TEST_CASE("light samples: ball light is uniform, stratified, deterministic") {
    const uint64_t seed = penumbra::test::testSeed(100);
    Rng rng(seed);
    const dvec3 centre = rng.point(-10, 10);
    const double radius = rng.uniform(0.1, 3.0);
    const uint32_t light_seed = static_cast<uint32_t>(rng.next());
    for (uint32_t count : {1u, 2u, 31u, 32u, 33u, 1000u}) {
        CAPTURE(count);
        const std::vector<dvec3> samples = sphereLightSamples(centre, radius, count, light_seed);
        REQUIRE(samples.size() == count);
        CHECK(hashSamples(samples) == hashSamples(sphereLightSamples(centre, radius, count, light_seed)));
        // Stratum i of radius^3 holds sample i exactly (equal-volume shells).
        for (uint32_t i = 0; i < count; ++i) {
            const double volume = std::pow(glm::length(samples[i] - centre) / radius, 3.0);
            CHECK(volume >= static_cast<double>(i) / count - 1e-9);
            CHECK(volume <= static_cast<double>(i + 1) / count + 1e-9);
        }
    }
    const std::vector<dvec3> samples = sphereLightSamples(centre, radius, 4096, light_seed);
    dvec3 mean(0.0);
    size_t upper = 0, positive_x = 0;
    for (const dvec3& s : samples) {
        mean += (s - centre) / radius;
        upper += s.z > centre.z;
        positive_x += s.x > centre.x;
    }
    mean /= 4096.0;
    CHECK(glm::length(mean) < 0.01);
    CHECK(std::abs(static_cast<double>(upper) / 4096 - 0.5) < 0.01);
    CHECK(std::abs(static_cast<double>(positive_x) / 4096 - 0.5) < 0.01);
    CHECK(hashSamples(samples) != hashSamples(sphereLightSamples(centre, radius, 4096, light_seed + 1)));
}

TEST_CASE("light samples: disk light lies in its plane and is stratified in radius^2") {
    const uint64_t seed = penumbra::test::testSeed(200);
    Rng rng(seed);
    const dvec3 centre = rng.point(-10, 10);
    const dvec3 normal = rng.point(-1, 1) + dvec3(0, 0, 0.1);
    const dvec3 n = glm::normalize(normal);
    const double radius = rng.uniform(0.1, 3.0);
    for (uint32_t count : {1u, 7u, 64u, 1000u}) {
        CAPTURE(count);
        const std::vector<dvec3> samples = diskLightSamples(centre, normal, radius, count, 3);
        REQUIRE(samples.size() == count);
        for (uint32_t i = 0; i < count; ++i) {
            CHECK(std::abs(glm::dot(samples[i] - centre, n)) < 1e-12 * (1.0 + glm::length(centre)));
            const double area = glm::dot(samples[i] - centre, samples[i] - centre) / (radius * radius);
            CHECK(area >= static_cast<double>(i) / count - 1e-9);
            CHECK(area <= static_cast<double>(i + 1) / count + 1e-9);
        }
    }
    // Axis-aligned normals, including the -z branch of the orthonormal basis.
    for (const dvec3& axis : {dvec3(0, 0, 1), dvec3(0, 0, -1), dvec3(1, 0, 0), dvec3(0, -1, 0)}) {
        for (const dvec3& s : diskLightSamples(dvec3(0), axis, 1.0, 100)) {
            CHECK(glm::dot(s, axis) == doctest::Approx(0.0).epsilon(1e-15));
            CHECK(glm::length(s) <= 1.0 + 1e-15);
        }
    }
}

TEST_CASE("light samples: rect light is the exact grid of cell centres, u fastest") {
    const std::vector<dvec3> samples = rectLightSamples(dvec3(-1, -1, 2), dvec3(2, 0, 0), dvec3(0, 4, 0), 4, 8);
    REQUIRE(samples.size() == 32);
    for (uint32_t j = 0; j < 8; ++j)
        for (uint32_t i = 0; i < 4; ++i) {
            const dvec3 expected(-1 + 0.5 * i + 0.25, -1 + 0.5 * j + 0.25, 2);
            CHECK(samples[j * 4 + i] == expected);  // dyadic: exact
        }
    const std::vector<dvec3> one = rectLightSamples(dvec3(1, 2, 3), dvec3(1, 0, 0), dvec3(0, 1, 0), 1, 1);
    REQUIRE(one.size() == 1);
    CHECK(one[0] == dvec3(1.5, 2.5, 3));
    // Degenerate rectangles are allowed and give coincident samples.
    CHECK(rectLightSamples(dvec3(0), dvec3(0), dvec3(0), 3, 3).size() == 9);
}

TEST_CASE("light samples: bit-identical on every platform (golden values)") {
    // Computed once on x86-64 (glibc); any IEEE-754 platform must reproduce them, which is the
    // point of the library-independent sin/cos/cbrt and explicit fma in light_samples.hpp.
    const std::vector<dvec3> ball = sphereLightSamples(dvec3(1, 2, 3), 0.5, 1000, 42);
    const std::vector<dvec3> disk = diskLightSamples(dvec3(-1, 0.5, 2), dvec3(0.3, -0.2, 1), 0.75, 1000, 7);
    const std::vector<dvec3> rect = rectLightSamples(dvec3(0.1, 0.2, 0.3), dvec3(1.1, 0.1, 0), dvec3(0, 0.3, 0.9), 13, 7);
    CHECK(hashSamples(ball) == 14597371172150713114ull);
    CHECK(hashSamples(disk) == 9113573180030293137ull);
    CHECK(hashSamples(rect) == 1170552091459373326ull);
    // A few coordinates in the clear, for whoever has to debug a mismatch.
    CHECK(ball[0].x == 0x1.ffb88c159b4b4p-1);
    CHECK(disk[999].z == 0x1.02c19eff34eb3p+1);
}

TEST_CASE("light samples: bad input") {
    const double nan = std::nan("");
    const double inf = INFINITY;
    // count 0 throws, even with radius 0.
    CHECK(contains(errorOf([] { sphereLightSamples(dvec3(0), 1.0, 0); }), "count"));
    CHECK(contains(errorOf([] { sphereLightSamples(dvec3(0), 0.0, 0); }), "count"));
    CHECK(contains(errorOf([] { diskLightSamples(dvec3(0), dvec3(0, 0, 1), 1.0, 0); }), "count"));
    CHECK(contains(errorOf([] { rectLightSamples(dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0), 0, 4); }), "nu"));
    CHECK(contains(errorOf([] { rectLightSamples(dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0), 4, 0); }), "nv"));
    // Negative, NaN or infinite radius throws.
    CHECK(contains(errorOf([] { sphereLightSamples(dvec3(0), -1.0, 4); }), "radius"));
    CHECK(contains(errorOf([&] { sphereLightSamples(dvec3(0), nan, 4); }), "radius"));
    CHECK(contains(errorOf([&] { diskLightSamples(dvec3(0), dvec3(0, 0, 1), inf, 4); }), "radius"));
    CHECK(contains(errorOf([] { diskLightSamples(dvec3(0), dvec3(0, 0, 1), -0.5, 4); }), "radius"));
    // Non-finite positions, zero normal.
    CHECK(contains(errorOf([&] { sphereLightSamples(dvec3(0, nan, 0), 1.0, 4); }), "center"));
    CHECK(contains(errorOf([&] { diskLightSamples(dvec3(0), dvec3(0, 0, nan), 1.0, 4); }), "normal"));
    CHECK(contains(errorOf([] { diskLightSamples(dvec3(0), dvec3(0), 1.0, 4); }), "normal"));
    CHECK(contains(errorOf([&] { rectLightSamples(dvec3(inf, 0, 0), dvec3(1, 0, 0), dvec3(0, 1, 0), 2, 2); }), "corner"));
    CHECK(contains(errorOf([&] { rectLightSamples(dvec3(0), dvec3(nan, 0, 0), dvec3(0, 1, 0), 2, 2); }), "edge_u"));
    // Radius 0: exactly one sample at the centre whatever the count.
    for (uint32_t count : {1u, 2u, 100u}) {
        const std::vector<dvec3> ball = sphereLightSamples(dvec3(1, 2, 3), 0.0, count, 9);
        REQUIRE(ball.size() == 1);
        CHECK(ball[0] == dvec3(1, 2, 3));
        const std::vector<dvec3> disk = diskLightSamples(dvec3(1, 2, 3), dvec3(0, 1, 0), 0.0, count);
        REQUIRE(disk.size() == 1);
        CHECK(disk[0] == dvec3(1, 2, 3));
    }
}

// ================================================================================================
// Closed forms

TEST_CASE("closed form: square occluder between a ground plane and a parallel square light") {
    // Ground z = 0 (receivers lie on it), occluder [-1/2, 1/2]^2 at z = 1 tessellated 4 x 4 with
    // alternating diagonals (so crossings through interior edges are exercised), emitter quad
    // [-1, 1]^2 at z = 2 carrying the n x n samples. The segment p -> s crosses z = 1 at
    // (p + s) / 2, so sample (i, j) is blocked iff |px + sx_i| < 1 and |py + sy_j| < 1: the
    // central projection of the occluder is an axis-aligned square, counted per axis.
    const uint64_t seed = penumbra::test::testSeed(300);
    Rng rng(seed);
    Mesh mesh;
    mesh.gridZ(-4, 4, -4, 4, 0.0, 1, 1);
    mesh.gridZ(-0.5, 0.5, -0.5, 0.5, 1.0, 4, 4);
    mesh.gridZ(-1, 1, -1, 1, 2.0, 1, 1);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const uint32_t n = 16;
    const std::vector<dvec3> samples = rectLightSamples(dvec3(-1, -1, 2), dvec3(2, 0, 0), dvec3(0, 2, 0), n, n);
    std::vector<double> centres(n);
    for (uint32_t i = 0; i < n; ++i) centres[i] = samples[i].x;  // == samples[i * n].y

    // Random receivers, receivers on the ground's diagonal edge (x == y) and receivers whose
    // crossings land exactly on the occluder's interior grid lines (dyadic, exact).
    std::vector<dvec3> receivers;
    for (int i = 0; i < 400; ++i) receivers.push_back({rng.uniform(-2.5, 2.5), rng.uniform(-2.5, 2.5), 0.0});
    for (int i = 0; i < 50; ++i) {
        const double x = rng.uniform(-2.0, 2.0);
        receivers.push_back({x, x, 0.0});
    }
    for (double line : {-0.25, 0.0, 0.25})
        for (uint32_t i = 0; i < n; i += 3) {
            receivers.push_back({2 * line - centres[i], rng.uniform(-0.3, 0.3), 0.0});
            receivers.push_back({rng.uniform(-0.3, 0.3), 2 * line - centres[i], 0.0});
            receivers.push_back({2 * line - centres[i], 2 * line - centres[(i + 5) % n], 0.0});
        }

    const VisibilityResult result = oracle.evaluate(receivers, samples);
    const auto axisCount = [&](double p, bool& near_boundary) {
        uint32_t count = 0;
        for (double s : centres) {
            const double q = std::abs(p + s);
            near_boundary |= std::abs(q - 1.0) < 1e-6;
            count += q < 1.0;
        }
        return count;
    };
    size_t checked = 0;
    for (size_t r = 0; r < receivers.size(); ++r) {
        bool near_boundary = false;
        const uint32_t expected = axisCount(receivers[r].x, near_boundary) * axisCount(receivers[r].y, near_boundary);
        if (near_boundary) continue;
        ++checked;
        CAPTURE(r);
        CAPTURE(receivers[r].x);
        CAPTURE(receivers[r].y);
        CHECK(result.blockedCount(r) == expected);
        CHECK(std::abs(result.visibleFraction(r) - (1.0 - expected / double(n * n))) <= 1e-12);
    }
    CHECK(checked > 400);

    // Receivers whose crossings land exactly on the occluder's OUTER boundary: those pairs are
    // ties; every other pair still follows the closed form.
    for (uint32_t i = 0; i < n; i += 2) {
        const dvec3 p(1.0 - centres[i], rng.uniform(-0.2, 0.2), 0.0);  // px + sx_i == 1 exactly
        const VisibilityResult one = oracle.evaluate({p}, samples);
        for (uint32_t j = 0; j < n; ++j)
            for (uint32_t k = 0; k < n; ++k) {
                const double qx = std::abs(p.x + centres[k]), qy = std::abs(p.y + centres[j]);
                const size_t s = j * n + k;
                if (qx == 1.0 && qy < 1.0) {
                    CHECK(one.isTie(0, s));
                } else if (std::abs(qy - 1.0) > 1e-6) {
                    CHECK(one.isBlocked(0, s) == (qx < 1.0 && qy < 1.0));
                }
            }
    }
}

TEST_CASE("closed form: point light hard shadow") {
    const uint64_t seed = penumbra::test::testSeed(400);
    Rng rng(seed);
    Mesh mesh;
    mesh.gridZ(-6, 6, -6, 6, 0.0, 3, 3);
    mesh.gridZ(-0.5, 0.5, -0.5, 0.5, 1.0, 2, 2);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const dvec3 light(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 2.0);
    const std::vector<dvec3> samples = sphereLightSamples(light, 0.0, 64);  // radius 0: one sample
    REQUIRE(samples.size() == 1);
    std::vector<dvec3> receivers;
    for (int i = 0; i < 3000; ++i) receivers.push_back({rng.uniform(-3, 3), rng.uniform(-3, 3), 0.0});
    const VisibilityResult result = oracle.evaluate(receivers, samples);
    size_t shadowed = 0;
    for (size_t r = 0; r < receivers.size(); ++r) {
        const double qx = std::abs(receivers[r].x + light.x), qy = std::abs(receivers[r].y + light.y);
        if (std::abs(qx - 1.0) < 1e-9 || std::abs(qy - 1.0) < 1e-9) continue;
        const bool expected = qx < 1.0 && qy < 1.0;
        shadowed += expected;
        CAPTURE(r);
        CHECK(result.isBlocked(r, 0) == expected);
        CHECK(result.visibleFraction(r) == (expected ? 0.0 : 1.0));
    }
    CHECK(shadowed > 100);
}

TEST_CASE("closed form: disk light behind a half-plane occluder") {
    // Disk light (radius 1, z = 2) facing down; occluder = half-plane x < c at z = 1. For a
    // receiver (px, py, 0) sample s is blocked iff px + sx < 2c, so the visible fraction tends to
    // the area of the disk cap x > a = 2c - px: (acos(a) - a sqrt(1 - a^2)) / pi. The count over
    // the actual samples is checked exactly; the stratified set must match the area closely.
    const uint64_t seed = penumbra::test::testSeed(500);
    Rng rng(seed);
    const double c = 0.1;
    Mesh mesh;
    mesh.quad({-20, -20, 1}, {c, -20, 1}, {c, 20, 1}, {-20, 20, 1});
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const uint32_t count = 4096;
    const std::vector<dvec3> samples = diskLightSamples(dvec3(0, 0, 2), dvec3(0, 0, -1), 1.0, count,
                                                        static_cast<uint32_t>(rng.next()));
    std::vector<dvec3> receivers;
    for (int i = 0; i < 40; ++i) receivers.push_back({rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 0.0});
    const VisibilityResult result = oracle.evaluate(receivers, samples);
    double worst = 0;
    for (size_t r = 0; r < receivers.size(); ++r) {
        CAPTURE(r);
        const double a = 2 * c - receivers[r].x;
        uint32_t expected = 0;
        bool near_boundary = false;
        for (const dvec3& s : samples) {
            expected += receivers[r].x + s.x < 2 * c;
            near_boundary |= std::abs(receivers[r].x + s.x - 2 * c) < 1e-9;
        }
        if (!near_boundary) CHECK(result.blockedCount(r) == expected);
        const double analytic = (std::acos(a) - a * std::sqrt(1 - a * a)) / M_PI;
        worst = std::max(worst, std::abs(result.visibleFraction(r) - analytic));
    }
    // Stratified: ~2e-3 worst case over many seeds, where i.i.d. samples would give ~8e-3 per sigma.
    MESSAGE("worst |visible fraction - analytic| = " << worst);
    CHECK(worst < 3e-3);
}

TEST_CASE("closed form: far lights keep their shadows (light at 1e2 ... 1e49)") {
    // Issue 41 item 3. Floor z = 0 over [-2, 2]^2 (16 x 16 cells) and an occluder quad
    // [-0.5, 0.5] x [-0.25, 0.25] at z = h; lights along the fixed direction u, of fixed angular
    // size: a centre D u and four samples D (u + 0.02 (+-1, +-1, 0)). The open segment p -> s
    // is blocked iff it crosses z = h inside the quad, at t = (h - pz) / (sz - pz): the closed
    // form, in long double. Receivers lie on the floor, 1e-3 above it and in the air (z = 0.2).
    // The tolerances must follow the scene's scale, not the segment's length: the blocked set is
    // the closed form at every D, no pair is a tie, and the work stays that of a near light.
    Mesh mesh;
    mesh.gridZ(-2, 2, -2, 2, 0.0, 16, 16);
    const double h = 0.5;
    mesh.gridZ(-0.5, 0.5, -0.25, 0.25, h, 2, 1);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const dvec3 u(0.3, -0.2, 1.0);
    std::vector<dvec3> receivers;
    for (double z : {0.0, 1e-3, 0.2})
        for (int i = 0; i < 24; ++i)
            for (int j = 0; j < 24; ++j) receivers.push_back({-1.9 + 0.16 * i + 0.0071, -1.9 + 0.16 * j + 0.0037, z});
    const std::vector<dvec3> offsets{dvec3(0), dvec3(1, 1, 0), dvec3(1, -1, 0), dvec3(-1, 1, 0), dvec3(-1, -1, 0)};

    uint64_t near_tests = 0;
    for (double distance : {1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e15, 1e20, 1e30, 1e40, 1e49}) {
        CAPTURE(distance);
        std::vector<dvec3> samples;
        for (const dvec3& o : offsets) samples.push_back(distance * (u + 0.02 * o));
        const VisibilityResult result = oracle.evaluate(receivers, samples);
        size_t checked = 0, shadowed = 0, wrong = 0;
        for (size_t r = 0; r < receivers.size(); ++r)
            for (size_t s = 0; s < samples.size(); ++s) {
                using L = long double;
                const dvec3& p = receivers[r];
                const dvec3& q = samples[s];
                const L t = (L(h) - L(p.z)) / (L(q.z) - L(p.z));
                const L x = L(p.x) + t * (L(q.x) - L(p.x)), y = L(p.y) + t * (L(q.y) - L(p.y));
                const L margin = std::min(std::fabs(std::fabs(x) - 0.5L), std::fabs(std::fabs(y) - 0.25L));
                if (margin < 1e-6L) continue;  // too close to the shadow's edge for a closed form
                const bool expected = t > 0 && t < 1 && std::fabs(x) < 0.5L && std::fabs(y) < 0.25L;
                ++checked;
                shadowed += expected;
                wrong += result.isBlocked(r, s) != expected;
            }
        MESSAGE("D = " << distance << ": " << shadowed << " of " << checked << " pairs in shadow, " << wrong
                       << " wrong, ties " << result.tie_count << ", tests/segment "
                       << double(result.triangle_tests) / double(receivers.size() * samples.size()));
        CHECK(checked == receivers.size() * samples.size());
        CHECK(shadowed > 300);
        CHECK(wrong == 0);
        CHECK(result.tie_count == 0);
        if (distance == 1e2) near_tests = result.triangle_tests;
        CHECK(result.triangle_tests <= 2 * near_tests);
        if (distance == 1e2 || distance == 1e10 || distance == 1e49)
            checkIdentical(result, oracle.evaluateBruteForce(receivers, samples), "far light");
        bool tie = true;
        CHECK(oracle.segmentBlocked(dvec3(0.0071, 0.0037, 0.0), samples[0], &tie));  // under the quad's centre
        CHECK_FALSE(tie);
        // A vertical segment exactly through the quad's edge x = 0.5 is a tie; 1e-7 inside it
        // (>> tie_epsilon * the scene's extent 4) is a robust hit.
        CHECK(oracle.segmentBlocked(dvec3(0.5 - 1e-7, 0.1, 0.0), dvec3(0.5 - 1e-7, 0.1, distance), &tie));
        CHECK_FALSE(tie);
        oracle.segmentBlocked(dvec3(0.5, 0.1, 0.0), dvec3(0.5, 0.1, distance), &tie);
        CHECK(tie);
    }
    // Beyond the coordinate limit the oracle refuses, naming the value and the limit.
    const std::string message = errorOf([&] { oracle.evaluate(receivers, {2e50 * u}); });
    CHECK(contains(message, "light_samples[0]"));
    CHECK(contains(message, "1e+50"));
}

// ================================================================================================
// BVH vs brute force

TEST_CASE("BVH vs brute force: random triangle soups, bit for bit") {
    const uint64_t seed = penumbra::test::testSeed(600);
    Rng rng(seed);
    for (size_t count : {size_t(0), size_t(1), size_t(2), size_t(7), size_t(1000), size_t(20000)}) {
        CAPTURE(count);
        const Mesh mesh = randomSoup(rng, count);
        const VisibilityOracle oracle(mesh.positions, mesh.indices);
        REQUIRE(oracle.triangleCount() == count);
        const size_t receivers_n = count >= 20000 ? 16 : 40;
        const std::vector<dvec3> receivers = randomReceivers(rng, mesh, receivers_n);
        const std::vector<dvec3> samples = randomSamples(rng, mesh, count >= 20000 ? 33 : 70);
        const VisibilityResult bvh = oracle.evaluate(receivers, samples);
        const VisibilityResult brute = oracle.evaluateBruteForce(receivers, samples);
        checkIdentical(bvh, brute, "soup of " + std::to_string(count));
        size_t blocked = 0;
        for (size_t r = 0; r < receivers.size(); ++r) blocked += bvh.blockedCount(r);
        MESSAGE(count << " triangles: " << blocked << " of " << receivers.size() * samples.size()
                      << " pairs blocked, ties " << bvh.tie_count << ", nodes/segment "
                      << double(bvh.nodes_visited) / double(receivers.size() * samples.size()) << ", tests/segment "
                      << double(bvh.triangle_tests) / double(receivers.size() * samples.size()));
        if (count == 0) CHECK(blocked == 0);
        // segmentBlocked answers the same for a few pairs.
        for (int k = 0; k < 20; ++k) {
            const size_t r = rng.below(static_cast<uint32_t>(receivers.size()));
            const size_t s = rng.below(static_cast<uint32_t>(samples.size()));
            bool tie = false;
            CHECK(oracle.segmentBlocked(receivers[r], samples[s], &tie) == bvh.isBlocked(r, s));
            CHECK(tie == bvh.isTie(r, s));
        }
    }
}

TEST_CASE("BVH vs brute force: lattice soups full of exact ties") {
    const uint64_t seed = penumbra::test::testSeed(700);
    Rng rng(seed);
    uint64_t ties = 0;
    for (size_t count : {size_t(1), size_t(10), size_t(200), size_t(1500)}) {
        CAPTURE(count);
        const Mesh mesh = latticeSoup(rng, count, 4);
        const VisibilityOracle oracle(mesh.positions, mesh.indices);
        const std::vector<dvec3> receivers = latticePoints(rng, 48, 4);
        const std::vector<dvec3> samples = latticePoints(rng, 80, 4);
        for (const VisibilityOptions& options : {VisibilityOptions{}, VisibilityOptions{0, 0.0, 0.0},
                                                 VisibilityOptions{0, 1e-3, 1e-6}}) {
            const VisibilityResult bvh = oracle.evaluate(receivers, samples, options);
            checkIdentical(bvh, oracle.evaluateBruteForce(receivers, samples, options),
                           "lattice soup of " + std::to_string(count) + " eps " + std::to_string(options.tie_epsilon));
            ties += bvh.tie_count;
        }
    }
    MESSAGE("lattice ties: " << ties);
    CHECK(ties > 0);  // the point of this input
}

TEST_CASE("ties are rare on generic inputs") {
    const uint64_t seed = penumbra::test::testSeed(800);
    Rng rng(seed);
    const Mesh mesh = randomSoup(rng, 2000);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const std::vector<dvec3> receivers = randomReceivers(rng, mesh, 150);
    const std::vector<dvec3> samples = sphereLightSamples(dvec3(0.3, 2.0, 0.1), 0.4, 256, 5);
    const VisibilityResult result = oracle.evaluate(receivers, samples);
    const double pairs = double(receivers.size() * samples.size());
    MESSAGE("ties " << result.tie_count << " of " << pairs << " pairs");
    CHECK(double(result.tie_count) <= 1e-4 * pairs);
}

// ================================================================================================
// Far from the origin

TEST_CASE("far from origin: exactly representable translations give identical bits") {
    // Dyadic coordinates (multiples of 2^-20 within [-2, 2]) stay exact after adding 1e5 or 1e7,
    // and the oracle only works on differences to the receiver: the bits must not change at all.
    const uint64_t seed = penumbra::test::testSeed(900);
    Rng rng(seed);
    const auto dyadic = [](dvec3 p) { return glm::round(p * 1048576.0) / 1048576.0; };
    Mesh mesh = randomSoup(rng, 800);
    for (dvec3& p : mesh.positions) p = dyadic(p * 2.0);
    std::vector<dvec3> receivers = randomReceivers(rng, mesh, 40);
    std::vector<dvec3> samples = randomSamples(rng, mesh, 64);
    for (dvec3& p : receivers) p = dyadic(p);
    for (dvec3& p : samples) p = dyadic(p);
    const VisibilityResult base = VisibilityOracle(mesh.positions, mesh.indices).evaluate(receivers, samples);
    for (const dvec3& offset : {dvec3(1e5, -1e5, 1e5), dvec3(1e7, 1e7, -1e7), dvec3(-3e7, 0, 1e7)}) {
        CAPTURE(offset.x);
        Mesh moved = mesh;
        moved.translate(offset);
        std::vector<dvec3> moved_receivers = receivers, moved_samples = samples;
        for (dvec3& p : moved_receivers) p += offset;
        for (dvec3& p : moved_samples) p += offset;
        const VisibilityOracle oracle(moved.positions, moved.indices);
        const VisibilityResult result = oracle.evaluate(moved_receivers, moved_samples);
        checkIdentical(base, result, "translated by " + std::to_string(offset.x));
        checkIdentical(result, oracle.evaluateBruteForce(moved_receivers, moved_samples), "brute force far away");
    }
}

TEST_CASE("far from origin: rounded translations differ only on ties") {
    // Arbitrary coordinates are rounded when translated (by up to ulp(offset) / 2), so a pair may
    // flip only if it is a tie in one of the two runs, given tie_epsilon * scale above that:
    // the documented tolerance (1e-9 at 1e5, 1e-7 at 1e7 for a scene of size ~1).
    const uint64_t seed = penumbra::test::testSeed(1000);
    Rng rng(seed);
    const Mesh mesh = randomSoup(rng, 800);
    const std::vector<dvec3> receivers = randomReceivers(rng, mesh, 45);
    const std::vector<dvec3> samples = randomSamples(rng, mesh, 64);
    struct Case {
        dvec3 offset;
        double epsilon;
    };
    for (const Case& c : {Case{dvec3(1e5, 1e5, -1e5), 1e-9}, Case{dvec3(-1e7, 1e7, 1e7), 1e-7}}) {
        CAPTURE(c.offset.x);
        const VisibilityOptions options{0, c.epsilon, c.epsilon};
        const VisibilityResult base = VisibilityOracle(mesh.positions, mesh.indices).evaluate(receivers, samples, options);
        Mesh moved = mesh;
        moved.translate(c.offset);
        std::vector<dvec3> moved_receivers = receivers, moved_samples = samples;
        for (dvec3& p : moved_receivers) p += c.offset;
        for (dvec3& p : moved_samples) p += c.offset;
        const VisibilityResult result =
            VisibilityOracle(moved.positions, moved.indices).evaluate(moved_receivers, moved_samples, options);
        size_t flips = 0, unexplained = 0;
        for (size_t r = 0; r < receivers.size(); ++r)
            for (size_t s = 0; s < samples.size(); ++s) {
                if (base.isBlocked(r, s) == result.isBlocked(r, s)) continue;
                ++flips;
                if (!base.isTie(r, s) && !result.isTie(r, s)) ++unexplained;
            }
        MESSAGE("offset " << c.offset.x << ": " << flips << " flips, ties " << base.tie_count << " / "
                          << result.tie_count);
        CHECK(unexplained == 0);
    }
}

// ================================================================================================
// Watertightness


TEST_CASE("watertight: segments through shared edges and vertices of closed meshes never leak") {
    const uint64_t seed = penumbra::test::testSeed(1100);
    Rng rng(seed);
    SUBCASE("tessellated box, dyadic receivers (segments exactly through edges and vertices)") {
        std::vector<dvec3> interior;
        for (int i = 0; i < 6; ++i) interior.push_back(glm::round(rng.point(-3.9, 3.9) * 16.0) / 16.0);
        interior.push_back(dvec3(0.0));
        checkNoLeaks(rng, tessellatedBox(4.0, 8), interior, 2.0, 4000);
    }
    SUBCASE("tessellated box, arbitrary receivers") {
        std::vector<dvec3> interior;
        for (int i = 0; i < 6; ++i) interior.push_back(rng.point(-3.99, 3.99));
        checkNoLeaks(rng, tessellatedBox(4.0, 8), interior, 3.0, 4000);
    }
    SUBCASE("icosphere") {
        std::vector<dvec3> interior{dvec3(0.0)};
        for (int i = 0; i < 6; ++i) interior.push_back(rng.point(-0.5, 0.5));
        checkNoLeaks(rng, icosphere(3), interior, 2.0, 4000);
    }
}

// ================================================================================================
// Threads, closest hits, special rules

TEST_CASE("thread count does not change the bits or the counters") {
    const uint64_t seed = penumbra::test::testSeed(1200);
    Rng rng(seed);
    const Mesh mesh = randomSoup(rng, 3000);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const std::vector<dvec3> receivers = randomReceivers(rng, mesh, 101);
    const std::vector<dvec3> samples = randomSamples(rng, mesh, 45);
    const VisibilityResult one = oracle.evaluate(receivers, samples, VisibilityOptions{1});
    for (unsigned threads : {2u, 7u, 0u}) {
        CAPTURE(threads);
        const VisibilityResult many = oracle.evaluate(receivers, samples, VisibilityOptions{threads});
        checkIdentical(one, many, "threads " + std::to_string(threads));
        CHECK(one.nodes_visited == many.nodes_visited);
        CHECK(one.triangle_tests == many.triangle_tests);
    }
    checkIdentical(one, oracle.evaluateBruteForce(receivers, samples, VisibilityOptions{7}), "brute force, 7 threads");
}

TEST_CASE("closestHit matches brute force") {
    const uint64_t seed = penumbra::test::testSeed(1300);
    Rng rng(seed);
    const auto same = [](const Hit& a, const Hit& b) {
        return a.hit == b.hit && a.t == b.t && a.triangle == b.triangle && a.u == b.u && a.v == b.v;
    };
    for (int scene = 0; scene < 3; ++scene) {
        CAPTURE(scene);
        const Mesh mesh = scene == 0 ? randomSoup(rng, 2000) : scene == 1 ? latticeSoup(rng, 300, 4) : tessellatedBox(4.0, 8);
        const VisibilityOracle oracle(mesh.positions, mesh.indices);
        size_t hits = 0, mismatches = 0;
        for (int i = 0; i < 3000; ++i) {
            dvec3 origin, direction;
            if (scene == 1) {
                origin = latticePoints(rng, 1, 4)[0];
                direction = latticePoints(rng, 1, 4)[0] - origin;
                if (direction == dvec3(0.0)) continue;
            } else {
                origin = rng.point(-2, 2);
                direction = rng.point(-1, 1);
            }
            const double t_min = i % 4 == 0 ? -INFINITY : 0.0;
            const double t_max = i % 3 == 0 ? INFINITY : rng.uniform(0.5, 3.0);
            const Hit bvh = oracle.closestHit(origin, direction, t_min, t_max);
            const Hit brute = oracle.closestHitBruteForce(origin, direction, t_min, t_max);
            hits += bvh.hit;
            if (!same(bvh, brute)) {
                ++mismatches;
                INFO("ray " << i << " t " << bvh.t << " vs " << brute.t << " triangle " << bvh.triangle << " vs "
                            << brute.triangle);
                CHECK(same(bvh, brute));
            }
            if (bvh.hit) {
                // The reported point lies on the reported triangle, at origin + t * direction.
                const size_t t = bvh.triangle;
                const dvec3 point = (1 - bvh.u - bvh.v) * mesh.vertex(t, 0) + bvh.u * mesh.vertex(t, 1) +
                                    bvh.v * mesh.vertex(t, 2);
                CHECK(glm::length(point - (origin + bvh.t * direction)) < 1e-9 * (1 + glm::length(direction) * std::abs(bvh.t)));
                CHECK(bvh.t > t_min);
                CHECK(bvh.t < t_max);
            }
        }
        MESSAGE("scene " << scene << ": " << hits << " hits");
        CHECK(mismatches == 0);
        CHECK(hits > 100);
    }
    // Rays from inside the closed box always hit it (watertight closest hit too).
    const Mesh box = tessellatedBox(4.0, 8);
    const VisibilityOracle oracle(box.positions, box.indices);
    for (const dvec3& q : edgeTargets(rng, box)) {
        const dvec3 origin = glm::round(rng.point(-3, 3) * 8.0) / 8.0;
        CHECK(oracle.closestHit(origin, q - origin, 0.0, INFINITY).hit);
    }
}

TEST_CASE("coplanar rule: receivers on surfaces and samples on emitters are not self-shadowed") {
    const uint64_t seed = penumbra::test::testSeed(1400);
    Rng rng(seed);
    // A tessellated floor (receivers on it, including exactly on shared edges and vertices) and a
    // tessellated emitter above it (samples on it). Nothing else: nothing may block, no ties.
    Mesh mesh;
    mesh.gridZ(-2, 2, -2, 2, 0.0, 8, 8);
    mesh.gridZ(-0.5, 0.5, -0.5, 0.5, 3.0, 4, 4);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    std::vector<dvec3> receivers;
    for (int i = 0; i < 40; ++i) receivers.push_back({rng.uniform(-2, 2), rng.uniform(-2, 2), 0.0});
    for (int i = 0; i <= 8; i += 2)
        for (int j = 0; j <= 8; j += 4) receivers.push_back({-2 + 0.5 * i, -2 + 0.5 * j, 0.0});  // vertices
    for (int i = 0; i < 8; ++i) receivers.push_back({-2 + 0.5 * i + 0.25, -2 + 0.5 * i + 0.25, 0.0});  // diagonals
    for (int i = 0; i < 8; ++i) receivers.push_back({-2 + 0.5 * i + 0.125, -1.0, 0.0});  // grid lines
    std::vector<dvec3> samples = rectLightSamples(dvec3(-0.5, -0.5, 3), dvec3(1, 0, 0), dvec3(0, 1, 0), 8, 8);
    samples.push_back(dvec3(0, 0, 3));      // a vertex of the emitter grid
    samples.push_back(dvec3(0.25, 0, 3));   // an edge
    samples.push_back(dvec3(0, 0, -1.0));   // below the floor: the receiver's own plane does not block
    const VisibilityResult result = oracle.evaluate(receivers, samples);
    checkIdentical(result, oracle.evaluateBruteForce(receivers, samples), "coplanar");
    for (size_t r = 0; r < receivers.size(); ++r) CHECK(result.blockedCount(r) == 0);
    CHECK(result.tie_count == 0);

    // Receivers slightly above the floor (1e-3) with the light below ARE blocked by the floor;
    // receivers within coplanar_epsilon are not.
    const std::vector<dvec3> below{dvec3(0.1, 0.2, -1.0)};
    CHECK(oracle.segmentBlocked(dvec3(0.3, 0.7, 1e-3), below[0]));
    CHECK_FALSE(oracle.segmentBlocked(dvec3(0.3, 0.7, 1e-12), below[0]));
    VisibilityOptions strict;
    strict.coplanar_epsilon = 0.0;
    CHECK(oracle.segmentBlocked(dvec3(0.3, 0.7, 1e-12), below[0], strict));

    // A blocker between a floor receiver and the emitter still blocks.
    Mesh with_blocker = mesh;
    with_blocker.gridZ(-3, 3, -3, 3, 1.5, 2, 2);
    const VisibilityOracle blocked_oracle(with_blocker.positions, with_blocker.indices);
    const VisibilityResult all = blocked_oracle.evaluate(receivers, samples);
    for (size_t r = 0; r < receivers.size(); ++r) CHECK(all.blockedCount(r) == samples.size() - 1);  // all but "below"
}

TEST_CASE("degenerate triangles never block, empty meshes block nothing") {
    const uint64_t seed = penumbra::test::testSeed(1500);
    Rng rng(seed);
    Mesh mesh;
    // Zero area: repeated vertex, collinear (exactly and up to rounding), all three equal.
    mesh.triangle({-1, 0, 1}, {1, 0, 1}, {1, 0, 1});
    mesh.triangle({-1, -1, 1}, {0, 0, 1}, {1, 1, 1});
    mesh.triangle({-0.3, -0.1, 1}, {0.1, 0.7 / 3.0, 1}, {0.3, 0.4, 1});
    mesh.triangle({0, 0, 1}, {0, 0, 1}, {0, 0, 1});
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    CHECK(oracle.triangleCount() == 4);
    CHECK(oracle.degenerateTriangleCount() == 4);
    // Segments straight through those lines and points.
    std::vector<dvec3> receivers{dvec3(0, 0, 0), dvec3(0.5, 0, 0), dvec3(0.5, 0.5, 0), dvec3(0.1, 0.7 / 3.0, 0)};
    std::vector<dvec3> samples{dvec3(0, 0, 2), dvec3(0.5, 0, 2), dvec3(0.5, 0.5, 2), dvec3(0.1, 0.7 / 3.0, 2)};
    const VisibilityResult result = oracle.evaluate(receivers, samples);
    for (size_t r = 0; r < receivers.size(); ++r) CHECK(result.blockedCount(r) == 0);
    CHECK(result.tie_count == 0);
    CHECK_FALSE(oracle.closestHit(dvec3(0, 0, 0), dvec3(0, 0, 1), 0, INFINITY).hit);

    // A degenerate triangle next to a real one: ids still refer to the caller's list.
    mesh.triangle({-1, -1, 1.5}, {1, -1, 1.5}, {0, 1, 1.5});
    const VisibilityOracle mixed(mesh.positions, mesh.indices);
    CHECK(mixed.degenerateTriangleCount() == 4);
    const Hit hit = mixed.closestHit(dvec3(0, 0, 0), dvec3(0, 0, 1), 0, INFINITY);
    CHECK(hit.hit);
    CHECK(hit.triangle == 4);
    CHECK(hit.t == 1.5);

    // Empty mesh: valid, nothing blocks; empty receiver / sample lists are valid too.
    const VisibilityOracle empty(std::vector<dvec3>{}, std::vector<uint32_t>{});
    CHECK(empty.triangleCount() == 0);
    const std::vector<dvec3> points = randomReceivers(rng, Mesh{}, 10);
    const VisibilityResult none = empty.evaluate(points, points);
    for (size_t r = 0; r < points.size(); ++r) CHECK(none.visibleFraction(r) == 1.0);
    CHECK(none.tie_count == 0);
    CHECK_FALSE(empty.closestHit(dvec3(0), dvec3(1, 0, 0), 0, INFINITY).hit);
    const VisibilityResult no_samples = oracle.evaluate(points, {});
    CHECK(no_samples.words_per_receiver == 0);
    CHECK(no_samples.visibleFraction(3) == 1.0);
    CHECK(oracle.evaluate({}, points).blocked.empty());
    // Positions given as float convert exactly.
    const VisibilityOracle from_float(std::vector<glm::vec3>{{-1, -1, 1}, {1, -1, 1}, {0, 1, 1}}, {0, 1, 2});
    CHECK(from_float.segmentBlocked(dvec3(0, 0, 0), dvec3(0, 0, 2)));
    // An empty segment (receiver == sample) is never blocked.
    bool tie = true;
    CHECK_FALSE(from_float.segmentBlocked(dvec3(0, 0, 1), dvec3(0, 0, 1), &tie));
    CHECK_FALSE(tie);
}

TEST_CASE("result layout: bit s % 32 of word r * wpr + s / 32, unused bits zero") {
    Mesh mesh;
    mesh.gridZ(-10, 10, -10, 10, 1.0, 1, 1);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    for (size_t count : {size_t(1), size_t(31), size_t(32), size_t(33), size_t(65)}) {
        CAPTURE(count);
        std::vector<dvec3> samples;
        for (size_t s = 0; s < count; ++s) samples.push_back({0.0, 0.0, s % 3 == 0 ? 0.5 : 2.0});  // every third visible
        const VisibilityResult result = oracle.evaluate({dvec3(0, 0, 0), dvec3(1, 1, 0)}, samples);
        CHECK(result.words_per_receiver == (count + 31) / 32);
        CHECK(result.blocked.size() == 2 * result.words_per_receiver);
        for (size_t r = 0; r < 2; ++r) {
            for (size_t s = 0; s < count; ++s) {
                const bool expected = s % 3 != 0;
                CHECK(result.isBlocked(r, s) == expected);
                CHECK(((result.blocked[r * result.words_per_receiver + s / 32] >> (s % 32)) & 1u) == expected);
            }
            const uint32_t used = count % 32;
            if (used) CHECK((result.blocked[(r + 1) * result.words_per_receiver - 1] >> used) == 0u);
        }
    }
}

// ================================================================================================
// Bad input

TEST_CASE("bad input: mesh") {
    const double nan = std::nan("");
    const std::vector<uint32_t> one{0, 1, 2};
    std::string message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{dvec3(0), dvec3(1, 0, 0), dvec3(0, nan, 0)}, one); });
    CHECK(contains(message, "vertex 2"));
    message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{dvec3(0), dvec3(INFINITY, 0, 0), dvec3(0, 1, 0)}, one); });
    CHECK(contains(message, "vertex 1"));
    message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0), dvec3(-INFINITY)}, one); });
    CHECK(contains(message, "vertex 3"));  // unreferenced positions are checked too
    message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{dvec3(0), dvec3(1, 0, 0), dvec3(0, 0, 1e60)}, one); });
    CHECK(contains(message, "vertex 2"));
    message = errorOf([&] { VisibilityOracle(std::vector<glm::vec3>{glm::vec3(0), glm::vec3(NAN), glm::vec3(1)}, one); });
    CHECK(contains(message, "vertex 1"));
    message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0)}, {0, 1, 3}); });
    CHECK(contains(message, "indices[2] = 3"));
    message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{dvec3(0), dvec3(1, 0, 0), dvec3(0, 1, 0)}, {0, 1, 2, 0}); });
    CHECK(contains(message, "multiple of 3"));
    message = errorOf([&] { VisibilityOracle(std::vector<dvec3>{}, {0, 0, 0}); });
    CHECK(contains(message, "out of range"));
}

TEST_CASE("bad input: queries") {
    const double nan = std::nan("");
    Mesh mesh;
    mesh.gridZ(-1, 1, -1, 1, 1.0, 1, 1);
    const VisibilityOracle oracle(mesh.positions, mesh.indices);
    const std::vector<dvec3> good{dvec3(0), dvec3(0, 0, 2)};
    std::vector<dvec3> bad = good;
    bad.push_back(dvec3(0, nan, 0));
    CHECK(contains(errorOf([&] { oracle.evaluate(bad, good); }), "receivers[2]"));
    CHECK(contains(errorOf([&] { oracle.evaluate(good, bad); }), "light_samples[2]"));
    CHECK(contains(errorOf([&] { oracle.evaluateBruteForce(bad, good); }), "receivers[2]"));
    bad[2] = dvec3(INFINITY, 0, 0);
    CHECK(contains(errorOf([&] { oracle.evaluateBruteForce(good, bad); }), "light_samples[2]"));
    CHECK(contains(errorOf([&] { oracle.segmentBlocked(dvec3(nan), dvec3(0)); }), "receiver"));
    CHECK(contains(errorOf([&] { oracle.segmentBlocked(dvec3(0), dvec3(0, 0, INFINITY)); }), "light_sample"));
    VisibilityOptions options;
    options.tie_epsilon = -1e-9;
    CHECK(contains(errorOf([&] { oracle.evaluate(good, good, options); }), "tie_epsilon"));
    options.tie_epsilon = nan;
    CHECK(contains(errorOf([&] { oracle.evaluate(good, good, options); }), "tie_epsilon"));
    options = VisibilityOptions{};
    options.coplanar_epsilon = 0.5;
    CHECK(contains(errorOf([&] { oracle.segmentBlocked(dvec3(0), dvec3(1), options); }), "coplanar_epsilon"));
    CHECK(contains(errorOf([&] { oracle.closestHit(dvec3(nan), dvec3(0, 0, 1), 0, 1); }), "origin"));
    CHECK(contains(errorOf([&] { oracle.closestHit(dvec3(0), dvec3(0), 0, 1); }), "direction"));
    CHECK(contains(errorOf([&] { oracle.closestHit(dvec3(0), dvec3(0, 0, 1), 1, 1); }), "t_min < t_max"));
    CHECK(contains(errorOf([&] { oracle.closestHit(dvec3(0), dvec3(0, 0, 1), nan, 1); }), "t_min < t_max"));
    // Valid calls do not throw.
    CHECK_NOTHROW(oracle.evaluate(good, good));
    CHECK(oracle.closestHit(dvec3(0), dvec3(0, 0, 1), 0, INFINITY).hit);
}

}  // TEST_SUITE("visibility")

// ================================================================================================
// Heavier sweeps: PENUMBRA_STRESS=1 visibility_test --test-suite=stress (about a minute on 2 cores)

TEST_SUITE("stress") {

TEST_CASE("stress: BVH vs brute force over many seeds, sizes and tolerances" * doctest::skip(!stressRequested())) {
    const uint64_t seed = penumbra::test::testSeed(1600);
    Rng rng(seed);
    for (int round = 0; round < 12; ++round) {
        CAPTURE(round);
        for (size_t count : {size_t(3), size_t(255), size_t(256), size_t(257), size_t(5000), size_t(50000)}) {
            CAPTURE(count);
            const bool lattice = round % 3 == 2;
            const Mesh mesh = lattice ? latticeSoup(rng, count, 6) : randomSoup(rng, count);
            const VisibilityOracle oracle(mesh.positions, mesh.indices);
            const std::vector<dvec3> receivers = lattice ? latticePoints(rng, 24, 6) : randomReceivers(rng, mesh, 24);
            const std::vector<dvec3> samples = lattice ? latticePoints(rng, 97, 6) : randomSamples(rng, mesh, 97);
            const VisibilityOptions options{0, round % 2 ? 1e-9 : 1e-5, round % 4 == 1 ? 0.0 : 1e-9};
            checkIdentical(oracle.evaluate(receivers, samples, options),
                           oracle.evaluateBruteForce(receivers, samples, options), "stress soup");
        }
    }
}

TEST_CASE("stress: watertight fine meshes" * doctest::skip(!stressRequested())) {
    const uint64_t seed = penumbra::test::testSeed(1700);
    Rng rng(seed);
    std::vector<dvec3> interior{dvec3(0.0)};
    while (interior.size() < 13) {  // strictly inside the icosphere (inradius > 0.99)
        const dvec3 p = rng.point(-0.9, 0.9);
        if (glm::length(p) < 0.9) interior.push_back(p);
    }
    checkNoLeaks(rng, icosphere(5), interior, 2.0, 40000);
    std::vector<dvec3> box_interior;
    for (int i = 0; i < 12; ++i) box_interior.push_back(glm::round(rng.point(-3.9, 3.9) * 64.0) / 64.0);
    checkNoLeaks(rng, tessellatedBox(4.0, 32), box_interior, 2.0, 40000);
}

TEST_CASE("stress: translations far from the origin" * doctest::skip(!stressRequested())) {
    for (int round = 0; round < 10; ++round) {
        const uint64_t seed = penumbra::test::testSeed(5000 + round);
        Rng rng(seed);
        const Mesh mesh = randomSoup(rng, 3000);
        const std::vector<dvec3> receivers = randomReceivers(rng, mesh, 60);
        const std::vector<dvec3> samples = randomSamples(rng, mesh, 128);
        const VisibilityResult base = VisibilityOracle(mesh.positions, mesh.indices).evaluate(receivers, samples);
        const dvec3 offset = rng.point(-1e5, 1e5);
        Mesh moved = mesh;
        moved.translate(offset);
        std::vector<dvec3> moved_receivers = receivers, moved_samples = samples;
        for (dvec3& p : moved_receivers) p += offset;
        for (dvec3& p : moved_samples) p += offset;
        const VisibilityResult result =
            VisibilityOracle(moved.positions, moved.indices).evaluate(moved_receivers, moved_samples);
        size_t unexplained = 0;
        for (size_t r = 0; r < receivers.size(); ++r)
            for (size_t s = 0; s < samples.size(); ++s)
                unexplained += base.isBlocked(r, s) != result.isBlocked(r, s) && !base.isTie(r, s) && !result.isTie(r, s);
        CHECK(unexplained == 0);
    }
}

}  // TEST_SUITE("stress")
