// Tests of the transmittance oracle (reference/transmittance.hpp): hand-computed stacks of
// semi-transparent layers (open segment, endpoints on layers, coplanar receivers), shared edges
// flagged as ties, the homogeneous medium's exp(-sigma_t L), colour, filters, the ray's step
// function, BVH vs brute force bit for bit, an independent Moller-Trumbore brute force on every
// tie-free segment, thread-count determinism and bad input.
//
// Random inputs come from support/test_support.hpp's testSeed(): fixed by default and printed;
// PENUMBRA_SEED=<n> replays a run, PENUMBRA_SEED=random draws fresh ones.
#include <penumbra/reference/transmittance.hpp>

#include "support/splitmix.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace {

using glm::dvec3;
using penumbra::reference::ColourTransmittanceOracle;
using penumbra::reference::FilterTap;
using penumbra::reference::FilteredTransmittance;
using penumbra::reference::HomogeneousMedium;
using penumbra::reference::RayTransmittance;
using penumbra::reference::TransmittanceBatch;
using penumbra::reference::TransmittanceOptions;
using penumbra::reference::TransmittanceOracle;
using penumbra::reference::TransmittanceResult;
using penumbra::reference::TransmittanceSegment;
using penumbra::test::contains;
using penumbra::test::errorOf;
using Rng = penumbra::test::SplitMix64;

struct Mesh {
    std::vector<dvec3> positions;
    std::vector<uint32_t> indices;

    void triangle(const dvec3& a, const dvec3& b, const dvec3& c) {
        for (const dvec3& p : {a, b, c}) {
            indices.push_back(static_cast<uint32_t>(positions.size()));
            positions.push_back(p);
        }
    }
    /// Quad [x0, x1] x [y0, y1] at height z as triangles (a, b, c), (a, c, d) with a = (x0, y0),
    /// b = (x1, y0), c = (x1, y1), d = (x0, y1): the diagonal is a-c, and a point with
    /// (y - y0)(x1 - x0) < (x - x0)(y1 - y0) lies in the first triangle.
    void layer(double z, double x0 = -1, double x1 = 1, double y0 = -1, double y1 = 1) {
        const dvec3 a(x0, y0, z), b(x1, y0, z), c(x1, y1, z), d(x0, y1, z);
        triangle(a, b, c);
        triangle(a, c, d);
    }
    size_t triangleCount() const { return indices.size() / 3; }
    dvec3 vertex(size_t t, int k) const { return positions[indices[3 * t + k]]; }
};

/// Triangles of random size and orientation around random centres in [-1, 1]^3.
Mesh randomSoup(Rng& rng, size_t count) {
    Mesh mesh;
    const double size_max = 0.6 * std::min(1.0, std::sqrt(200.0 / std::max<double>(1.0, count)));
    for (size_t i = 0; i < count; ++i) {
        const dvec3 centre = rng.point(-1.0, 1.0);
        const double size = size_max * std::exp(rng.uniform(std::log(1.0 / 30.0), 0.0));
        mesh.triangle(centre + size * rng.point(-1, 1), centre + size * rng.point(-1, 1), centre + size * rng.point(-1, 1));
    }
    return mesh;
}

/// Random opacities with exact 0 and 1 mixed in.
std::vector<double> randomOpacities(Rng& rng, size_t count) {
    std::vector<double> opacity(count);
    for (double& a : opacity) {
        const uint32_t kind = rng.below(10);
        a = kind == 0 ? 0.0 : kind == 1 ? 1.0 : rng.uniform();
    }
    return opacity;
}

/// Every field, exactly.
template <typename Value>
bool same(const TransmittanceResult<Value>& a, const TransmittanceResult<Value>& b) {
    return a.transmittance == b.transmittance && a.surfaces == b.surfaces && a.medium == b.medium &&
           a.medium_length == b.medium_length && a.hits == b.hits && a.fragile_triangles == b.fragile_triangles &&
           a.tie == b.tie;
}

template <typename Value>
void checkSameBatch(const TransmittanceBatch<Value>& a, const TransmittanceBatch<Value>& b, const std::string& what) {
    INFO(what);
    REQUIRE(a.results.size() == b.results.size());
    size_t differ = 0, first = a.results.size();
    for (size_t i = 0; i < a.results.size(); ++i) {
        if (same(a.results[i], b.results[i])) continue;
        if (differ++ == 0) first = i;
    }
    INFO("first difference at segment " << first);
    CHECK(differ == 0);
    CHECK(a.tie_count == b.tie_count);
}

/// Independent brute force: Moller-Trumbore on the open segment (0 < t < 1), no BVH, no tie rules.
/// Another rounding than the watertight test: it must agree wherever the oracle reports no tie.
std::vector<uint32_t> mollerTrumboreHits(const Mesh& mesh, const dvec3& p, const dvec3& q) {
    std::vector<uint32_t> hits;
    const dvec3 d = q - p;
    for (size_t t = 0; t < mesh.triangleCount(); ++t) {
        const dvec3 v0 = mesh.vertex(t, 0), e1 = mesh.vertex(t, 1) - v0, e2 = mesh.vertex(t, 2) - v0;
        const dvec3 pvec = glm::cross(d, e2);
        const double det = glm::dot(e1, pvec);
        if (det == 0.0) continue;
        const double inv = 1.0 / det;
        const dvec3 tvec = p - v0;
        const double u = glm::dot(tvec, pvec) * inv;
        if (u < 0.0 || u > 1.0) continue;
        const dvec3 qvec = glm::cross(tvec, e1);
        const double v = glm::dot(d, qvec) * inv;
        if (v < 0.0 || u + v > 1.0) continue;
        const double s = glm::dot(e2, qvec) * inv;
        if (s > 0.0 && s < 1.0) hits.push_back(static_cast<uint32_t>(t));
    }
    return hits;
}

/// Independent medium length: clip the segment's end points into the box one axis at a time.
double clippedLength(const dvec3& lo, const dvec3& hi, dvec3 a, dvec3 b) {
    for (int k = 0; k < 3; ++k) {
        if (a[k] > b[k]) std::swap(a, b);
        if (b[k] < lo[k] || a[k] > hi[k]) return 0.0;
        const dvec3 d = b - a;
        if (a[k] < lo[k]) a += d * ((lo[k] - a[k]) / d[k]);
        if (b[k] > hi[k]) b -= d * ((b[k] - hi[k]) / d[k]);
    }
    return glm::length(b - a);
}

}  // namespace

TEST_SUITE("transmittance") {

// ================================================================================================
// Hand-computed cases

TEST_CASE("stack of parallel quads: prod(1 - a_i) over the layers the open segment crosses") {
    // Layers z = 1, 2, 3, 4 over [-1, 1]^2 with opacities 1/2, 1/4, 3/4, 1/8. By hand:
    // (1/2)(3/4)(1/4)(7/8) = 21/256 = 0.08203125; every partial product is dyadic, hence exact.
    Mesh mesh;
    std::vector<double> opacity;
    for (double a : {0.5, 0.25, 0.75, 0.125}) {
        mesh.layer(static_cast<double>(mesh.triangleCount() / 2 + 1));
        opacity.insert(opacity.end(), {a, a});
    }
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, opacity);
    REQUIRE(oracle.triangleCount() == 8);
    const auto check = [&](const dvec3& p, const dvec3& q, double expected, uint32_t hits) {
        CAPTURE(p.z);
        CAPTURE(q.z);
        for (const auto& r : {oracle.transmittance(p, q), oracle.transmittance(q, p), oracle.transmittanceBruteForce(p, q)}) {
            CHECK(r.transmittance == expected);
            CHECK(r.surfaces == expected);
            CHECK(r.medium == 1.0);
            CHECK(r.hits == hits);
            CHECK(r.fragile_triangles == 0);
            CHECK_FALSE(r.tie);
        }
    };
    // Through all four, vertical and slanted (crossings stay off the diagonals x == y).
    check({0.3, 0.1, 0}, {0.3, 0.1, 5}, 0.08203125, 4);
    check({0.3, 0.1, 0}, {0.1, -0.2, 5}, 0.08203125, 4);
    // Ending before / after a layer.
    check({0.3, 0.1, 0}, {0.3, 0.1, 2.5}, 0.375, 2);       // layers 1, 2
    check({0.3, 0.1, 0}, {0.3, 0.1, 0.999}, 1.0, 0);       // before layer 1
    check({0.3, 0.1, 1.5}, {0.3, 0.1, 3.5}, 0.1875, 2);    // layers 2, 3
    check({0.3, 0.1, 4.001}, {0.3, 0.1, 9}, 1.0, 0);       // after layer 4
    // Endpoints exactly on a layer are excluded (open segment), and are not ties.
    check({0.3, 0.1, 1}, {0.3, 0.1, 3}, 0.75, 1);          // only layer 2
    check({0.3, 0.1, 1}, {0.3, 0.1, 2}, 1.0, 0);           // between two layers, on both
    check({0.3, 0.1, 1}, {-0.2, -0.6, 4}, 0.1875, 2);      // slanted, on layers 1 and 4
    check({0.3, 0.1, 0}, {0.3, 0.1, 4}, 0.09375, 3);       // ends on layer 4
    // Outside the layers' footprint.
    check({5, 5, 0}, {5, 5, 5}, 1.0, 0);
    // Empty segment.
    check({0.3, 0.1, 0.5}, {0.3, 0.1, 0.5}, 1.0, 0);

    // k layers with opacities (i + 1) / 16: the product, dyadic and exact in any order, vs the oracle.
    for (int k = 0; k <= 9; ++k) {
        CAPTURE(k);
        Mesh stack;
        std::vector<double> a;
        double expected = 1.0;
        for (int i = 0; i < k; ++i) {
            stack.layer(1.0 + i);
            const double ai = (i + 1) / 16.0;
            a.insert(a.end(), {ai, ai});
            expected *= 1.0 - ai;
        }
        const TransmittanceOracle o(stack.positions, stack.indices, a);
        const auto r = o.transmittance({0.3, 0.1, 0}, {0.2, 0.05, k + 1.0});
        CHECK(r.transmittance == expected);
        CHECK(r.hits == static_cast<uint32_t>(k));
        CHECK_FALSE(r.tie);
    }
}

TEST_CASE("coplanar receivers are not attenuated by the surface they lie on") {
    // Ground z = 0 over [-4, 4]^2 (opacity 3/4), layer z = 1 over [-1, 1]^2 (opacity 1/2).
    Mesh mesh;
    mesh.layer(0.0, -4, 4, -4, 4);
    mesh.layer(1.0);
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, std::vector<double>{0.75, 0.75, 0.5, 0.5});
    const dvec3 on_ground(0.3, 0.1, 0);
    auto r = oracle.transmittance(on_ground, {0.3, 0.1, 2});  // light above: the layer only
    CHECK(r.transmittance == 0.5);
    CHECK(r.hits == 1);
    CHECK_FALSE(r.tie);
    r = oracle.transmittance(on_ground, {0.3, 0.1, -2});  // light behind the ground: not by the ground
    CHECK(r.transmittance == 1.0);
    CHECK(r.hits == 0);
    CHECK_FALSE(r.tie);
    r = oracle.transmittance({0.3, 0.1, -1}, {0.3, 0.1, 2});  // from under the ground: both
    CHECK(r.transmittance == 0.125);
    CHECK(r.hits == 2);

    // Receivers at random points of a slanted triangle (rounded onto its plane), lights either side.
    const uint64_t seed = penumbra::test::testSeed(1100);
    Rng rng(seed);
    Mesh slanted;
    const dvec3 v0(-2, -1, 0.5), v1(2, -1.5, 0.2), v2(0, 2, 0.9);
    slanted.triangle(v0, v1, v2);
    const TransmittanceOracle one(slanted.positions, slanted.indices, 0.9);
    const dvec3 n = glm::normalize(glm::cross(v1 - v0, v2 - v0));
    for (int i = 0; i < 200; ++i) {
        double a = rng.uniform(), b = rng.uniform();
        if (a + b > 1) {
            a = 1 - a;
            b = 1 - b;
        }
        const dvec3 p = v0 + a * (v1 - v0) + b * (v2 - v0);
        const dvec3 light = p + (i % 2 ? 1.0 : -1.0) * rng.uniform(0.5, 3.0) * n + rng.point(-0.5, 0.5);
        CAPTURE(i);
        const auto s = one.transmittance(p, light);
        CHECK(s.transmittance == 1.0);
        CHECK(s.hits == 0);
        CHECK_FALSE(s.tie);
    }
}

TEST_CASE("a line through a shared edge is inside both triangles: counted twice, flagged as a tie") {
    Mesh mesh;
    mesh.layer(1.0);                  // triangles 0, 1: diagonal from (-1, -1) to (1, 1), opacity 1/2
    mesh.layer(2.0, 0, 2, -1, 1);     // triangles 2, 3: diagonal y = x - 1, opacity 1/4
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, std::vector<double>{0.5, 0.5, 0.25, 0.25});
    for (const TransmittanceSegment& segment : {TransmittanceSegment{{0.5, 0.5, 0}, {0.5, 0.5, 1.5}},    // vertical
                                                TransmittanceSegment{{0.25, 0.25, 0}, {0.75, 0.75, 2}},  // slanted, dyadic
                                                TransmittanceSegment{{1, 1, 0}, {1, 1, 1.5}}}) {         // a shared vertex
        const dvec3 p = segment.p, q = segment.q;
        CAPTURE(p.x);
        const auto r = oracle.transmittance(p, q);
        CHECK(r.hits == 2);
        CHECK(r.fragile_triangles == 2);
        CHECK(r.tie);
        CHECK(r.transmittance == 0.25);  // (1 - 1/2)^2: the surface attenuates twice
        CHECK(same(r, oracle.transmittanceBruteForce(p, q)));
    }
    // One robust crossing (layer 2) does not hide the fragile ones, unlike the visibility tie bit.
    const dvec3 p(0.5, 0.5, 0), q(0.5, 0.5, 3);
    const auto r = oracle.transmittance(p, q);
    CHECK(r.hits == 3);
    CHECK(r.fragile_triangles == 2);
    CHECK(r.tie);
    CHECK(r.transmittance == 0.25 * 0.75);
    const penumbra::reference::VisibilityOracle visibility(mesh.positions, mesh.indices);
    bool visibility_tie = true;
    CHECK(visibility.segmentBlocked(p, q, &visibility_tie));
    CHECK_FALSE(visibility_tie);
    // Away from the diagonal: one triangle, no tie.
    const auto clean = oracle.transmittance({0.5, 0.25, 0}, {0.5, 0.25, 1.5});
    CHECK(clean.hits == 1);
    CHECK_FALSE(clean.tie);
    CHECK(clean.transmittance == 0.5);
}

TEST_CASE("homogeneous medium: exp(-sigma_t L) with L from the closed box") {
    HomogeneousMedium medium;
    medium.lo = dvec3(0.0);
    medium.hi = dvec3(1.0);
    medium.sigma_t = 2.0;
    const Mesh empty;
    const TransmittanceOracle oracle(empty.positions, empty.indices, 0.5, medium);
    const auto check = [&](const dvec3& p, const dvec3& q, double length) {
        CAPTURE(p.x);
        CAPTURE(p.y);
        CAPTURE(p.z);
        for (const auto& r : {oracle.transmittance(p, q), oracle.transmittance(q, p)}) {
            CHECK(r.medium_length == doctest::Approx(length).epsilon(1e-15));
            CHECK(r.medium == doctest::Approx(std::exp(-2.0 * length)).epsilon(1e-14));
            CHECK(r.transmittance == r.medium);
            CHECK(r.surfaces == 1.0);
            CHECK(r.hits == 0);
            CHECK_FALSE(r.tie);
            if (length == 0.0) CHECK(r.transmittance == 1.0);  // exactly
        }
        CHECK(oracle.mediumTransmittance(p, q) == oracle.transmittance(p, q).medium);
    };
    check({0.25, 0.5, 0.5}, {0.75, 0.5, 0.5}, 0.5);               // entirely inside
    check({0.1, 0.2, 0.3}, {0.9, 0.7, 0.6}, std::sqrt(0.64 + 0.25 + 0.09));  // inside, oblique
    check({-3, 0.5, 0.5}, {3, 0.5, 0.5}, 1.0);                    // crossing along x
    check({-1, -1, -1}, {2, 2, 2}, std::sqrt(3.0));               // crossing the main diagonal
    check({0.5, 0.5, 0.5}, {0.5, 0.5, 4}, 0.5);                   // from inside out through z = 1
    check({-1, 0.5, 0.5}, {0.5, 0.5, 0.5}, 0.5);                  // from outside to the centre
    check({-0.5, 0.25, -0.5}, {1.5, 0.25, 1.5}, std::sqrt(2.0));  // in through an edge, out through one
    check({2, 0, 0}, {3, 1, 1}, 0.0);                             // outside
    check({-1, 2, 0.5}, {2, 2, 0.5}, 0.0);                        // parallel, outside
    check({-1, 0.25, 1}, {2, 0.25, 1}, 1.0);                      // lying in the face z = 1: closed box
    check({-1, 1, 1}, {2, 1, 1}, 1.0);                            // along the edge y = z = 1
    check({-1, 0.25, 1 + 0x1p-30}, {2, 0.25, 1 + 0x1p-30}, 0.0);  // just above the face
    check({-1, 0.5, 0}, {1, 0.5, 2}, 0.0);                        // touches the edge x = 0, z = 1 only
    check({-1, 0, 2}, {1, 0, 0}, std::sqrt(2.0));                 // in the face y = 0, across its diagonal
    check({0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, 0.0);                 // empty segment

    // Medium and layers multiply: a layer at z = 1/2 inside the box.
    Mesh layer;
    layer.layer(0.5);
    const TransmittanceOracle both(layer.positions, layer.indices, 0.5, medium);
    const auto r = both.transmittance({0.3, 0.1, 0}, {0.3, 0.1, 1});
    CHECK(r.surfaces == 0.5);
    CHECK(r.medium_length == 1.0);
    CHECK(r.medium == doctest::Approx(std::exp(-2.0)).epsilon(1e-15));
    CHECK(r.transmittance == 0.5 * r.medium);
    // No medium (value-initialised): exactly 1.
    const TransmittanceOracle none(layer.positions, layer.indices, 0.5);
    CHECK(none.transmittance({0.3, 0.1, 0}, {0.3, 0.1, 1}).transmittance == 0.5);
    CHECK(none.mediumTransmittance({-5, -5, -5}, {5, 5, 5}) == 1.0);
    // A flat box (lo.z == hi.z): only segments lying in its plane see it.
    HomogeneousMedium flat = medium;
    flat.lo.z = flat.hi.z = 0.5;
    const TransmittanceOracle sheet(empty.positions, empty.indices, 0.0, flat);
    CHECK(sheet.transmittance({0.5, 0.5, 0}, {0.5, 0.5, 1}).medium_length == 0.0);
    CHECK(sheet.transmittance({-1, 0.5, 0.5}, {2, 0.5, 0.5}).medium_length == 1.0);
}

TEST_CASE("colour: RGB opacities multiply per channel") {
    Mesh mesh;
    mesh.layer(1.0);
    mesh.layer(2.0);
    const std::vector<dvec3> opacity = {{0.5, 0.25, 1.0}, {0.5, 0.25, 1.0}, {0.5, 0.75, 0.0}, {0.5, 0.75, 0.0}};
    const ColourTransmittanceOracle oracle(mesh.positions, mesh.indices, opacity);
    const auto r = oracle.transmittance({0.3, 0.1, 0}, {0.3, 0.1, 3});
    CHECK(r.transmittance == dvec3(0.25, 0.1875, 0.0));  // (1/2 1/2, 3/4 1/4, 0 1)
    CHECK(r.hits == 2);
    const auto half = oracle.transmittance({0.3, 0.1, 0}, {0.3, 0.1, 1.5});
    CHECK(half.transmittance == dvec3(0.5, 0.75, 0.0));
    // One colour for all, with a medium: the medium is grey.
    HomogeneousMedium medium;
    medium.lo = dvec3(-1, -1, 0);
    medium.hi = dvec3(1, 1, 3);
    medium.sigma_t = 0.5;
    const ColourTransmittanceOracle tinted(mesh.positions, mesh.indices, dvec3(0.5, 0.0, 0.25), medium);
    const auto t = tinted.transmittance({0.3, 0.1, 0}, {0.3, 0.1, 3});
    CHECK(t.surfaces == dvec3(0.25, 1.0, 0.5625));
    CHECK(t.medium == doctest::Approx(std::exp(-1.5)).epsilon(1e-15));
    CHECK(t.transmittance == t.surfaces * t.medium);
    CHECK(tinted.opacity(3) == dvec3(0.5, 0.0, 0.25));
    // glm::vec3 opacities convert exactly.
    const std::vector<glm::vec3> opacity_f = {{0.5f, 0.25f, 1.0f}, {0.5f, 0.25f, 1.0f}, {0.5f, 0.75f, 0.0f}, {0.5f, 0.75f, 0.0f}};
    CHECK(same(ColourTransmittanceOracle(mesh.positions, mesh.indices, opacity_f).transmittance({0.3, 0.1, 0}, {0.3, 0.1, 3}), r));
}

TEST_CASE("glm::vec3 positions and float opacities give the double results") {
    Mesh mesh;
    mesh.layer(1.0);
    mesh.layer(2.0, -0.5, 1.5, -1, 1);
    const std::vector<glm::vec3> positions(mesh.positions.begin(), mesh.positions.end());  // dyadic: exact
    const std::vector<float> opacity_f = {0.5f, 0.5f, 0.25f, 0.25f};
    const TransmittanceOracle a(positions, mesh.indices, opacity_f);
    const TransmittanceOracle b(mesh.positions, mesh.indices, std::vector<double>{0.5, 0.5, 0.25, 0.25});
    for (const dvec3& p : {dvec3(0.3, 0.1, 0), dvec3(0.5, 0.5, 0), dvec3(-0.9, 0.7, 0.5)}) {
        const dvec3 q = p + dvec3(0.1, -0.05, 3);
        CHECK(same(a.transmittance(p, q), b.transmittance(p, q)));
    }
    CHECK(a.transmittance({0.3, 0.1, 0}, {0.3, 0.1, 3}).transmittance == 0.375);
    CHECK(a.opacity(2) == 0.25);
}

TEST_CASE("filtered transmittance: weighted average, tie weight fraction") {
    Mesh mesh;
    mesh.layer(1.0);
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, 0.5);
    // A: through one triangle (T = 1/2), B: missing (T = 1), C: through the diagonal (T = 1/4, tie).
    const FilterTap a{{0.3, 0.1, 0}, {0.3, 0.1, 2}, 1.0};
    const FilterTap b{{5, 5, 0}, {5, 5, 2}, 3.0};
    const FilterTap c{{0.5, 0.5, 0}, {0.5, 0.5, 2}, 4.0};
    auto f = oracle.filteredTransmittance({a, b});
    CHECK(f.transmittance == 0.875);  // (1/2 + 3) / 4
    CHECK_FALSE(f.tie);
    CHECK(f.tie_taps == 0);
    CHECK(f.tie_weight_fraction == 0.0);
    f = oracle.filteredTransmittance({a, b, c});
    CHECK(f.transmittance == 0.5625);  // (1/2 + 3 + 1) / 8
    CHECK(f.tie);
    CHECK(f.tie_taps == 1);
    CHECK(f.tie_weight_fraction == 0.5);
    // One tap: its own transmittance, whatever the weight.
    CHECK(oracle.filteredTransmittance({FilterTap{a.p, a.q, 1e-300}}).transmittance == 0.5);
    // Colour.
    const ColourTransmittanceOracle colour(mesh.positions, mesh.indices, dvec3(0.5, 1.0, 0.0));
    const FilteredTransmittance<dvec3> fc = colour.filteredTransmittance({a, b});
    CHECK(fc.transmittance == dvec3(0.875, 0.75, 1.0));
    // Many taps, threads: the same bits as a serial sum of the single queries.
    const uint64_t seed = penumbra::test::testSeed(1200);
    Rng rng(seed);
    std::vector<FilterTap> taps;
    for (int i = 0; i < 500; ++i) taps.push_back({rng.point(-1.5, 1.5) - dvec3(0, 0, 1), rng.point(-1.5, 1.5) + dvec3(0, 0, 2), rng.uniform(0.1, 2.0)});
    double sum = 0, weights = 0;
    for (const FilterTap& tap : taps) {
        sum += tap.weight * oracle.transmittance(tap.p, tap.q).transmittance;
        weights += tap.weight;
    }
    TransmittanceOptions one, four;
    one.threads = 1;
    four.threads = 4;
    const auto f1 = oracle.filteredTransmittance(taps, one), f4 = oracle.filteredTransmittance(taps, four);
    CHECK(f1.transmittance == f4.transmittance);
    CHECK(f1.tie_weight_fraction == f4.tie_weight_fraction);
    CHECK(f1.transmittance == doctest::Approx(sum / weights).epsilon(1e-14));
}

TEST_CASE("along a ray: every crossing sorted by t, the step function of a deep shadow map") {
    // Layers z = 3, 1, 4, 2 in triangle order (so index order != t order), opacities by layer.
    Mesh mesh;
    std::vector<double> opacity;
    for (const auto& [z, a] : {std::pair<double, double>{3, 0.75}, {1, 0.5}, {4, 0.125}, {2, 0.25}}) {
        mesh.layer(z);
        opacity.insert(opacity.end(), {a, a});
    }
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, opacity);
    // (0.3, 0.1) lies in each quad's first triangle: indices 0 (z 3), 2 (z 1), 4 (z 4), 6 (z 2).
    const RayTransmittance<double> up = oracle.transmittanceAlongRay({0.3, 0.1, 0}, {0, 0, 0.5}, 7.0);  // z < 3.5
    REQUIRE(up.steps.size() == 3);
    CHECK_FALSE(up.tie);
    const double t_up[] = {2, 4, 6};
    const uint32_t tri_up[] = {2, 6, 0};
    const double a_up[] = {0.5, 0.25, 0.75}, cum_up[] = {0.5, 0.375, 0.09375};
    for (int i = 0; i < 3; ++i) {
        CAPTURE(i);
        CHECK(up.steps[i].t == doctest::Approx(t_up[i]).epsilon(1e-15));
        CHECK(up.steps[i].triangle == tri_up[i]);
        CHECK(up.steps[i].opacity == a_up[i]);
        CHECK_FALSE(up.steps[i].fragile);
        CHECK(up.steps[i].transmittance == cum_up[i]);
    }
    CHECK(up.end == dvec3(0.3, 0.1, 3.5));
    // The same hits as transmittance(origin, end).
    const auto segment = oracle.transmittance({0.3, 0.1, 0}, up.end);
    CHECK(segment.hits == up.steps.size());
    CHECK(segment.surfaces == up.steps.back().transmittance);  // dyadic: order-independent here
    // Downwards from z = 10: z 4, 3, 2, 1 at t 6, 7, 8, 9.
    const auto down = oracle.transmittanceAlongRay({0.3, 0.1, 10}, {0, 0, -1}, 20.0);
    REQUIRE(down.steps.size() == 4);
    const uint32_t tri_down[] = {4, 0, 6, 2};
    for (int i = 0; i < 4; ++i) {
        CHECK(down.steps[i].t == doctest::Approx(6.0 + i).epsilon(1e-15));  // t_max * segment parameter, rounded
        CHECK(down.steps[i].triangle == tri_down[i]);
    }
    CHECK(down.steps.back().transmittance == 0.08203125);
    // Ending exactly on a layer: excluded.
    CHECK(oracle.transmittanceAlongRay({0.3, 0.1, 0}, {0, 0, 1}, 3.0).steps.size() == 2);
    // Through the diagonals (x == y): two steps of equal t per layer, by triangle index, fragile.
    const auto diagonal = oracle.transmittanceAlongRay({0.5, 0.5, 0}, {0, 0, 1}, 2.5);
    REQUIRE(diagonal.steps.size() == 4);
    CHECK(diagonal.tie);
    CHECK(diagonal.fragile_triangles == 4);
    const uint32_t tri_diag[] = {2, 3, 6, 7};
    for (int i = 0; i < 4; ++i) {
        CHECK(diagonal.steps[i].triangle == tri_diag[i]);
        CHECK(diagonal.steps[i].fragile);
    }
    CHECK(diagonal.steps[0].t == diagonal.steps[1].t);
    CHECK(diagonal.steps[2].t == diagonal.steps[3].t);
    // Missing everything; a random oblique ray against transmittance() on the same segment.
    CHECK(oracle.transmittanceAlongRay({5, 5, 0}, {0, 0, 1}, 10).steps.empty());
    const uint64_t seed = penumbra::test::testSeed(1300);
    Rng rng(seed);
    for (int i = 0; i < 50; ++i) {
        const dvec3 o = rng.point(-1, 1) - dvec3(0, 0, 1), d = rng.point(-0.3, 0.3) + dvec3(0, 0, 1);
        const auto ray = oracle.transmittanceAlongRay(o, d, 6.0);
        const auto seg = oracle.transmittance(o, ray.end);
        CAPTURE(i);
        CHECK(seg.hits == ray.steps.size());
        CHECK(seg.tie == ray.tie);
        for (size_t s = 1; s < ray.steps.size(); ++s) CHECK(ray.steps[s - 1].t <= ray.steps[s].t);
        for (const auto& step : ray.steps) CHECK((step.t > 0 && step.t <= 6.0));
        if (!ray.steps.empty()) CHECK(ray.steps.back().transmittance == doctest::Approx(seg.surfaces).epsilon(1e-15));
    }
}

// ================================================================================================
// Random scenes

TEST_CASE("random soups: BVH == brute force bit for bit, == an independent brute force off ties") {
    const uint64_t seed = penumbra::test::testSeed(1400);
    Rng rng(seed);
    for (size_t count : {size_t(0), size_t(1), size_t(7), size_t(300), size_t(3000)}) {
        CAPTURE(count);
        const Mesh mesh = randomSoup(rng, count);
        const std::vector<double> opacity = randomOpacities(rng, count);
        HomogeneousMedium medium;
        medium.lo = rng.point(-1.2, 0.0);
        medium.hi = medium.lo + rng.point(0.2, 1.5);
        medium.sigma_t = rng.uniform(0.1, 3.0);
        const TransmittanceOracle oracle(mesh.positions, mesh.indices, opacity, medium);
        REQUIRE(oracle.degenerateTriangleCount() == 0);
        std::vector<TransmittanceSegment> segments;
        for (int i = 0; i < 1000; ++i) segments.push_back({rng.point(-1.3, 1.3), rng.point(-1.3, 1.3)});
        const TransmittanceBatch<double> bvh = oracle.evaluate(segments);
        const TransmittanceBatch<double> brute = oracle.evaluateBruteForce(segments);
        checkSameBatch(bvh, brute, "soup of " + std::to_string(count));

        // Grey colour (a, a, a) and a tinted one (a, a / 2, 1 - a): channel x equals the grey bits.
        std::vector<dvec3> tint(count);
        for (size_t i = 0; i < count; ++i) tint[i] = dvec3(opacity[i], opacity[i] * 0.5, 1.0 - opacity[i]);
        const ColourTransmittanceOracle colour(mesh.positions, mesh.indices, tint, medium);
        const TransmittanceBatch<dvec3> cbatch = colour.evaluate(segments);

        size_t robust = 0, hits = 0;
        for (size_t i = 0; i < segments.size(); ++i) {
            CAPTURE(i);
            const TransmittanceResult<double>& r = bvh.results[i];
            CHECK(cbatch.results[i].transmittance.x == r.transmittance);
            CHECK(cbatch.results[i].hits == r.hits);
            CHECK(cbatch.results[i].tie == r.tie);
            CHECK(r.medium_length == doctest::Approx(clippedLength(medium.lo, medium.hi, segments[i].p, segments[i].q)).epsilon(1e-12));
            if (r.tie) continue;
            ++robust;
            const std::vector<uint32_t> mt = mollerTrumboreHits(mesh, segments[i].p, segments[i].q);
            double surfaces = 1.0;
            for (uint32_t t : mt) surfaces *= 1.0 - opacity[t];  // ascending index, as the oracle
            hits += mt.size();
            CHECK(r.hits == mt.size());
            CHECK(r.surfaces == surfaces);
            CHECK(r.transmittance == surfaces * r.medium);
        }
        MESSAGE(count << " triangles: " << robust << " of " << segments.size() << " segments tie-free, " << hits
                      << " crossings, tests/segment " << double(bvh.triangle_tests) / segments.size() << " (brute "
                      << double(brute.triangle_tests) / segments.size() << ")");
        CHECK(robust >= segments.size() * 99 / 100);
        if (count >= 300) CHECK(hits > 0);
        if (count == 3000) CHECK(bvh.triangle_tests < brute.triangle_tests / 4);
        // Single queries agree with the batch.
        for (int k = 0; k < 10; ++k) {
            const size_t i = rng.below(static_cast<uint32_t>(segments.size()));
            CHECK(same(oracle.transmittance(segments[i].p, segments[i].q), bvh.results[i]));
        }
    }
}

TEST_CASE("lattice soups full of ties: BVH == brute force, threads 1 == 4 == default") {
    const uint64_t seed = penumbra::test::testSeed(1500);
    Rng rng(seed);
    const int n = 4;
    Mesh mesh;
    const auto lattice = [&] { return dvec3(rng.below(n + 1), rng.below(n + 1), rng.below(n + 1)); };
    for (int i = 0; i < 400; ++i) mesh.triangle(lattice(), lattice(), lattice());
    std::vector<float> opacity(mesh.triangleCount());
    for (float& a : opacity) a = static_cast<float>(rng.below(9)) / 8.0f;
    HomogeneousMedium medium;
    medium.lo = dvec3(1, 1, 1);
    medium.hi = dvec3(3, 2, 4);
    medium.sigma_t = 0.25;
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, opacity, medium);
    std::vector<TransmittanceSegment> segments;
    for (int i = 0; i < 2000; ++i) {
        const auto point = [&] { return dvec3(rng.below(2 * n + 1), rng.below(2 * n + 1), rng.below(2 * n + 1)) * 0.5; };
        segments.push_back({point(), point()});
    }
    TransmittanceOptions one, four;
    one.threads = 1;
    four.threads = 4;
    const TransmittanceBatch<double> a = oracle.evaluate(segments, one);
    const TransmittanceBatch<double> b = oracle.evaluate(segments, four);
    const TransmittanceBatch<double> c = oracle.evaluate(segments);
    checkSameBatch(a, b, "threads 1 vs 4");
    checkSameBatch(a, c, "threads 1 vs default");
    CHECK(a.nodes_visited == b.nodes_visited);
    CHECK(a.triangle_tests == b.triangle_tests);
    checkSameBatch(a, oracle.evaluateBruteForce(segments, four), "BVH vs brute force");
    MESSAGE(a.tie_count << " of " << segments.size() << " lattice segments are ties");
    CHECK(a.tie_count > 0);
    CHECK(oracle.evaluate({}).results.empty());
}

// ================================================================================================
// Bad input

TEST_CASE("bad input throws penumbra::Error naming the value") {
    Mesh mesh;
    mesh.layer(1.0);
    mesh.layer(2.0);
    const auto& P = mesh.positions;
    const auto& I = mesh.indices;
    const double nan = std::nan("");
    const double inf = INFINITY;
    using O = TransmittanceOracle;
    using C = ColourTransmittanceOracle;
    // Opacities.
    std::string e = errorOf([&] { O(P, I, nan); });
    CHECK(contains(e, "opacity"));
    CHECK(contains(e, "nan"));
    CHECK(contains(errorOf([&] { O(P, I, 1.5); }), "1.5"));
    CHECK(contains(errorOf([&] { O(P, I, -0.1); }), "-0.1"));
    e = errorOf([&] { O(P, I, std::vector<double>{0.5, 0.5, 0.5, 1.5}); });
    CHECK(contains(e, "triangle 3"));
    CHECK(contains(e, "1.5"));
    e = errorOf([&] { O(P, I, std::vector<float>{-0.1f, 0.5f, 0.5f, 0.5f}); });
    CHECK(contains(e, "triangle 0"));
    CHECK(contains(e, "-0.1"));
    e = errorOf([&] { O(P, I, std::vector<double>{0.5, nan, 0.5, 0.5}); });
    CHECK(contains(e, "triangle 1"));
    CHECK(contains(e, "nan"));
    CHECK(contains(errorOf([&] { O(P, I, std::vector<double>{0.5, inf, 0.5, 0.5}); }), "inf"));
    CHECK(contains(errorOf([&] { O(P, I, std::vector<double>{0.5, 0.5}); }), "2 opacities for 4 triangles"));
    e = errorOf([&] { C(P, I, std::vector<dvec3>{dvec3(0.5), dvec3(0.5), dvec3(0.5, nan, 0.2), dvec3(0.5)}); });
    CHECK(contains(e, "triangle 2 (channel 1)"));
    CHECK(contains(e, "nan"));
    CHECK(contains(errorOf([&] { C(P, I, dvec3(0.5, 0.5, 1.25)); }), "1.25"));
    // Valid edges of the range.
    CHECK(O(P, I, 0.0).transmittance({0.3, 0.1, 0}, {0.3, 0.1, 3}).transmittance == 1.0);
    CHECK(O(P, I, 1.0).transmittance({0.3, 0.1, 0}, {0.3, 0.1, 3}).transmittance == 0.0);
    // Medium.
    HomogeneousMedium medium;
    medium.hi = dvec3(1.0);
    medium.sigma_t = -1.0;
    e = errorOf([&] { O(P, I, 0.5, medium); });
    CHECK(contains(e, "sigma_t"));
    CHECK(contains(e, "-1"));
    medium.sigma_t = nan;
    CHECK(contains(errorOf([&] { O(P, I, 0.5, medium); }), "nan"));
    medium.sigma_t = inf;
    CHECK(contains(errorOf([&] { O(P, I, 0.5, medium); }), "inf"));
    medium.sigma_t = 1.0;
    medium.lo = dvec3(0, 2, 0);
    CHECK(contains(errorOf([&] { O(P, I, 0.5, medium); }), "medium.lo[1] = 2"));
    medium.lo = dvec3(nan, 0, 0);
    CHECK(contains(errorOf([&] { O(P, I, 0.5, medium); }), "medium.lo"));
    // Mesh: VisibilityOracle's rules.
    std::vector<dvec3> bad = P;
    bad[2].y = nan;
    e = errorOf([&] { O(bad, I, 0.5); });
    CHECK(contains(e, "vertex 2"));
    CHECK(contains(e, "nan"));
    CHECK(contains(errorOf([&] { O(P, std::vector<uint32_t>{0, 1}, 0.5); }), "multiple of 3"));
    CHECK(contains(errorOf([&] { O(P, std::vector<uint32_t>{0, 1, 99}, 0.5); }), "99"));
    // Queries.
    const O oracle(P, I, 0.5);
    e = errorOf([&] { oracle.transmittance({0, nan, 0}, {0, 0, 1}); });
    CHECK(contains(e, "transmittance: p"));
    CHECK(contains(e, "nan"));
    CHECK(contains(errorOf([&] { oracle.transmittance({0, 0, 0}, {inf, 0, 1}); }), "inf"));
    e = errorOf([&] { oracle.evaluate({{dvec3(0), dvec3(1)}, {dvec3(0), dvec3(0, 0, nan)}}); });
    CHECK(contains(e, "segments[1].q"));
    CHECK(contains(e, "nan"));
    TransmittanceOptions options;
    options.tie_epsilon = 0.5;
    CHECK(contains(errorOf([&] { oracle.transmittance(dvec3(0), dvec3(1), options); }), "0.5"));
    // Filter weights.
    const FilterTap good{{0.3, 0.1, 0}, {0.3, 0.1, 3}, 1.0};
    e = errorOf([&] { oracle.filteredTransmittance({good, FilterTap{good.p, good.q, 0.0}}); });
    CHECK(contains(e, "taps[1].weight"));
    CHECK(contains(e, "got 0)"));
    CHECK(contains(errorOf([&] { oracle.filteredTransmittance({FilterTap{good.p, good.q, -2.0}}); }), "-2"));
    CHECK(contains(errorOf([&] { oracle.filteredTransmittance({FilterTap{good.p, good.q, nan}}); }), "nan"));
    CHECK(contains(errorOf([&] { oracle.filteredTransmittance({FilterTap{good.p, good.q, inf}}); }), "inf"));
    CHECK(contains(errorOf([&] { oracle.filteredTransmittance({}); }), "no taps"));
    CHECK(contains(errorOf([&] { oracle.filteredTransmittance({FilterTap{good.p, good.q, 1e308}, FilterTap{good.p, good.q, 1e308}}); }),
                   "overflows"));
    CHECK(contains(errorOf([&] { oracle.filteredTransmittance({FilterTap{dvec3(nan), good.q, 1.0}}); }), "taps[0].p"));
    // Rays.
    CHECK(contains(errorOf([&] { oracle.transmittanceAlongRay(dvec3(0), dvec3(0), 1.0); }), "direction"));
    CHECK(contains(errorOf([&] { oracle.transmittanceAlongRay(dvec3(0), dvec3(0, 0, 1), 0.0); }), "got 0"));
    CHECK(contains(errorOf([&] { oracle.transmittanceAlongRay(dvec3(0), dvec3(0, 0, 1), -3.0); }), "-3"));
    CHECK(contains(errorOf([&] { oracle.transmittanceAlongRay(dvec3(0), dvec3(0, 0, 1), nan); }), "nan"));
    CHECK(contains(errorOf([&] { oracle.transmittanceAlongRay(dvec3(0), dvec3(0, 0, 1e30), 1e30); }), "t_max * direction"));
    // The empty mesh is valid.
    const Mesh empty;
    CHECK(O(empty.positions, empty.indices, 0.5).transmittance(dvec3(0), dvec3(1)).transmittance == 1.0);
}

}  // TEST_SUITE

TEST_CASE("far light: the layers' closed form at 1e2 .. 1e40, the work of a near light (issue 41)") {
    // A floor z = 0 (8 x 8 cells, opacity 1/8: receivers lie on it) and two occluders, z = 0.5
    // (opacity 1/2) and z = 1 (1/4), partly overlapping; light points D u along a fixed u. The
    // tolerances scale with the scene's extent E = 4, not with |q - p| (VisibilityOracle's rule):
    // uncapped, the coplanar reach 1e-7 |q - p| swallowed both occluders past D ~ 1e7. Products
    // are dyadic, hence exact; crossings within 1e-6 of an edge or diagonal are skipped.
    Mesh mesh;
    std::vector<double> opacity;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) {
            mesh.layer(0.0, -2.0 + 0.5 * i, -1.5 + 0.5 * i, -2.0 + 0.5 * j, -1.5 + 0.5 * j);
            opacity.insert(opacity.end(), {0.125, 0.125});
        }
    struct Occluder {
        double z, x0, x1, y0, y1, a;
    };
    const Occluder occluders[2] = {{0.5, -0.5, 0.5, -0.25, 0.25, 0.5}, {1.0, -0.25, 0.75, -0.5, 0.0, 0.25}};
    for (const Occluder& o : occluders) {
        mesh.layer(o.z, o.x0, o.x1, o.y0, o.y1);
        opacity.insert(opacity.end(), {o.a, o.a});
    }
    const TransmittanceOracle oracle(mesh.positions, mesh.indices, opacity);
    CHECK(oracle.sceneExtent() == 4.0);
    std::vector<dvec3> receivers;
    for (double z : {0.0, 1e-3, 0.2})
        for (int i = 0; i < 24; ++i)
            for (int j = 0; j < 24; ++j) receivers.push_back({-1.9 + 0.16 * i + 0.0071, -1.9 + 0.16 * j + 0.0037, z});
    const dvec3 u(0.3, -0.2, 1.0);
    uint64_t near_tests = 0;
    for (double distance : {1e2, 1e6, 1e10, 1e20, 1e40}) {
        CAPTURE(distance);
        const dvec3 q = distance * u;
        std::vector<TransmittanceSegment> segments;
        std::vector<double> expected;
        for (const dvec3& p : receivers) {
            using L = long double;
            double product = 1.0;
            bool near_edge = false;
            for (const Occluder& o : occluders) {
                const L t = (L(o.z) - L(p.z)) / (L(q.z) - L(p.z));
                const L x = L(p.x) + t * (L(q.x) - L(p.x)), y = L(p.y) + t * (L(q.y) - L(p.y));
                // The diagonal (x0, y0)-(x1, y1): (y - y0)(x1 - x0) - (x - x0)(y1 - y0), normalised.
                const L dx = L(o.x1 - o.x0), dy = L(o.y1 - o.y0);
                const L diagonal = std::fabs((y - L(o.y0)) * dx - (x - L(o.x0)) * dy) / std::sqrt(dx * dx + dy * dy);
                const L margin = std::min({std::fabs(x - L(o.x0)), std::fabs(x - L(o.x1)), std::fabs(y - L(o.y0)),
                                           std::fabs(y - L(o.y1)), diagonal});
                near_edge |= margin < 1e-6L;
                if (t > 0 && t < 1 && x > L(o.x0) && x < L(o.x1) && y > L(o.y0) && y < L(o.y1)) product *= 1.0 - o.a;
            }
            if (near_edge) continue;
            segments.push_back({p, q});
            expected.push_back(product);
        }
        const TransmittanceBatch<double> batch = oracle.evaluate(segments);
        const TransmittanceBatch<double> brute = oracle.evaluateBruteForce(segments);
        size_t wrong = 0, attenuated = 0, both = 0;
        for (size_t i = 0; i < segments.size(); ++i) {
            wrong += batch.results[i].transmittance != expected[i] || batch.results[i].tie;
            wrong += brute.results[i].transmittance != batch.results[i].transmittance;
            attenuated += expected[i] < 1.0;
            both += expected[i] == 0.375;
        }
        MESSAGE("D = ", distance, ": ", segments.size(), " segments, ", attenuated, " attenuated (", both,
                " by both occluders), ", wrong, " wrong, ties ", batch.tie_count, ", nodes ", batch.nodes_visited,
                ", tests/segment ", double(batch.triangle_tests) / double(segments.size()));
        CHECK(segments.size() > receivers.size() * 9 / 10);
        CHECK(attenuated > 80);
        CHECK(both > 30);
        CHECK(wrong == 0);
        CHECK(batch.tie_count == 0);
        if (distance == 1e2) near_tests = batch.triangle_tests;
        CHECK(batch.triangle_tests <= 2 * near_tests);
        // One ray: the step function has the closed form's crossings.
        const RayTransmittance<double> ray = oracle.transmittanceAlongRay(dvec3(0.0071, 0.0037, 0.0), u, distance);
        CHECK_FALSE(ray.tie);
        CHECK(ray.steps.size() == 2);
    }
}
