// reference/compare.hpp: the one oracle-comparison loop (GPU hard-shadow states vs the oracle on
// the same positions) counts samples, mismatches and ties as documented, on a scene whose answer is
// known in closed form: a unit square at y = 1 over receivers at y = 0.
#include <penumbra/reference/compare.hpp>

#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <cmath>
#include <algorithm>
#include <random>
#include <vector>

using penumbra::reference::compareHardStates;
using penumbra::reference::HardComparison;
using penumbra::reference::hardLight;
using penumbra::reference::hardReference;
using penumbra::reference::testedSamples;
using penumbra::reference::VisibilityOracle;

namespace {

// Square [-1, 1]^2 at y = 1 (two triangles sharing the diagonal).
VisibilityOracle squareOracle() {
    const std::vector<glm::vec3> positions = {{-1, 1, -1}, {1, 1, -1}, {1, 1, 1}, {-1, 1, 1}};
    const std::vector<uint32_t> indices = {0, 1, 2, 0, 2, 3};
    return VisibilityOracle(positions, indices);
}

struct Receivers {
    std::vector<glm::vec4> positions;
    std::vector<uint32_t> truth;  // the exact answer as states
};

// Receivers at y = 0 on a grid, point light at (0, 5, 0): the segment meets y = 1 at 0.8 (x, z),
// so it is blocked iff |x| < 1.25 and |z| < 1.25. The grid (x from -2.2, z from -2.1, steps of 0.5)
// keeps every crossing at least 0.04 away from the square's edges and off its diagonal (x != z).
Receivers grid() {
    Receivers r;
    for (int i = 0; i < 10; ++i) {
        for (int k = 0; k < 10; ++k) {
            const float x = -2.2f + 0.5f * static_cast<float>(i), z = -2.1f + 0.5f * static_cast<float>(k);
            r.positions.emplace_back(x, 0.0f, z, 1.0f);
            r.truth.push_back(std::fabs(x) < 1.25f && std::fabs(z) < 1.25f ? PENUMBRA_AFH_SHADOWED : PENUMBRA_AFH_LIT);
        }
    }
    return r;
}

}  // namespace

TEST_CASE("the exact answer: 0 mismatches, every sample compared, nothing reported") {
    const VisibilityOracle oracle = squareOracle();
    const Receivers r = grid();
    const HardComparison c = compareHardStates(oracle, r.positions, r.truth, hardLight(glm::vec4(0, 5, 0, 1)));
    CHECK(c.samples == 100);
    CHECK(c.mismatched == 0);
    CHECK(c.ties == 0);
    CHECK(c.shadowed == 25);  // 5 x values and 5 z values inside (-1.25, 1.25)
    CHECK(c.blocked == 25);
    CHECK(c.first_mismatches.empty());
    CHECK(c.mismatchRate() == 0.0);
}

TEST_CASE("flipped states are counted and reported with the oracle's crossing; other states are not compared") {
    const VisibilityOracle oracle = squareOracle();
    Receivers r = grid();
    std::vector<uint32_t> states = r.truth;
    // Flip ten decided samples chosen from a printed seed; mark others back-facing, background, untested.
    std::mt19937 rng(penumbra::test::testSeed());
    std::vector<uint32_t> order(states.size());
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), rng);
    for (int i = 0; i < 10; ++i) {
        uint32_t& s = states[order[i]];
        s = s == PENUMBRA_AFH_SHADOWED ? PENUMBRA_AFH_LIT : PENUMBRA_AFH_SHADOWED;
    }
    states[order[10]] = PENUMBRA_AFH_BACK_FACING;
    states[order[11]] = PENUMBRA_AFH_NO_SAMPLE;
    states[order[12]] = PENUMBRA_AFH_UNTESTED;
    states[order[13]] = 77u;  // a broken state buffer
    const HardComparison c = compareHardStates(oracle, r.positions, states, hardLight(glm::vec4(0, 5, 0, 1)), {}, 4);
    CHECK(c.samples == 96);
    CHECK(c.mismatched == 10);
    CHECK(c.back_facing == 1);
    CHECK(c.no_sample == 1);
    CHECK(c.untested == 1);
    CHECK(c.other_state == 1);
    CHECK(c.undecided == 0);
    CHECK(c.mismatchRate() == doctest::Approx(10.0 / 96.0));
    REQUIRE(c.first_mismatches.size() == 4);  // max_reported
    for (size_t i = 0; i < c.first_mismatches.size(); ++i) {
        const auto& m = c.first_mismatches[i];
        CAPTURE(m.sample);
        if (i > 0) CHECK(m.sample > c.first_mismatches[i - 1].sample);  // sample order
        CHECK(m.shadowed != m.blocked);
        CHECK(m.shadowed == (states[m.sample] == PENUMBRA_AFH_SHADOWED));
        CHECK(m.position == glm::dvec3(glm::vec3(r.positions[m.sample])));
        CHECK(m.light_end == glm::dvec3(0, 5, 0));
        CHECK(m.crossing.hit == m.blocked);
        if (m.blocked) CHECK(m.crossing.t == doctest::Approx(0.2));  // y = 1 of the segment y = 0 .. 5
    }
}

TEST_CASE("an oracle tie is counted, never a mismatch") {
    const VisibilityOracle oracle = squareOracle();
    // Receiver (1.25, 0, 0): the segment to (0, 5, 0) meets y = 1 at x = 1, on the square's edge.
    const std::vector<glm::vec4> positions = {{1.25f, 0, 0, 1}, {0.3f, 0, -0.2f, 1}, {3, 0, 0, 1}};
    for (uint32_t edge_state : {PENUMBRA_AFH_LIT, PENUMBRA_AFH_SHADOWED}) {
        const std::vector<uint32_t> states = {edge_state, PENUMBRA_AFH_SHADOWED, PENUMBRA_AFH_LIT};
        const HardComparison c = compareHardStates(oracle, positions, states, hardLight(glm::vec4(0, 5, 0, 1)));
        CHECK(c.samples == 3);
        CHECK(c.ties == 1);
        CHECK(c.mismatched == 0);
    }
}

TEST_CASE("directional light: segments of the given reach toward the light") {
    const VisibilityOracle oracle = squareOracle();
    const std::vector<glm::vec4> positions = {{0.5f, 0, -0.25f, 1}, {2, 0, 0, 1}, {-0.3f, 0, 0.1f, 1}};
    const std::vector<uint32_t> states = {PENUMBRA_AFH_SHADOWED, PENUMBRA_AFH_LIT, PENUMBRA_AFH_SHADOWED};
    // Straight up: receivers under the square are blocked when the reach passes y = 1.
    HardComparison c = compareHardStates(oracle, positions, states, hardLight(glm::vec4(0, 1, 0, 0), 10.0f));
    CHECK(c.samples == 3);
    CHECK(c.mismatched == 0);
    // A reach that stops below the square: nothing is blocked, the two SHADOWED states mismatch.
    c = compareHardStates(oracle, positions, states, hardLight(glm::vec4(0, 1, 0, 0), 0.5f));
    CHECK(c.mismatched == 2);
    REQUIRE(!c.first_mismatches.empty());
    CHECK(c.first_mismatches[0].light_end == glm::dvec3(0.5, 0.5, -0.25));
    CHECK(!c.first_mismatches[0].crossing.hit);
}

TEST_CASE("two steps: one reference, several methods' states (the benchmark's form)") {
    const VisibilityOracle oracle = squareOracle();
    const Receivers r = grid();
    const auto light = hardLight(glm::vec4(0, 5, 0, 1));
    const auto reference = hardReference(oracle, r.positions, testedSamples(r.truth), light);
    CHECK(reference.ids.size() == 100);
    CHECK(compareHardStates(reference, r.truth).mismatched == 0);
    std::vector<uint32_t> all_lit(r.truth.size(), PENUMBRA_AFH_LIT);
    CHECK(compareHardStates(reference, all_lit).mismatched == 25);
    std::vector<uint32_t> undecided = r.truth;
    undecided[0] = PENUMBRA_AFH_UNTESTED;  // lit by the truth: reads as not shadowed, no mismatch
    const HardComparison c = compareHardStates(reference, undecided);
    CHECK(c.undecided == 1);
    CHECK(c.untested == 1);
    CHECK(c.mismatched == 0);
    CHECK(c.samples == 100);
}

TEST_CASE("bad input names the problem") {
    const VisibilityOracle oracle = squareOracle();
    using penumbra::test::contains;
    using penumbra::test::errorOf;
    CHECK(contains(errorOf([] { hardLight(glm::vec4(0, 1, 0, 0.5f)); }), "light.w"));
    CHECK(contains(errorOf([] { hardLight(glm::vec4(0, 1, 0, 0)); }), "reach"));
    const std::vector<glm::vec4> one = {{0, 0, 0, 1}};
    const std::vector<uint32_t> two = {PENUMBRA_AFH_LIT, PENUMBRA_AFH_LIT};
    CHECK(contains(errorOf([&] { compareHardStates(oracle, one, two, hardLight(glm::vec4(0, 5, 0, 1))); }), "positions"));
    CHECK(contains(errorOf([&] { hardReference(oracle, one, {3}, hardLight(glm::vec4(0, 5, 0, 1))); }), "ids[0] = 3"));
    const auto reference = hardReference(oracle, one, {0}, hardLight(glm::vec4(0, 5, 0, 1)));
    CHECK(contains(errorOf([&] { compareHardStates(reference, std::vector<uint32_t>{}); }), "outside"));
}
