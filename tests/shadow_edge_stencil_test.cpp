// shadow_edge_stencil.hpp (galoppo2010) on the CPU: sub-sample patterns, sub-samples on the pixel's
// plane, the provable stencil's soundness (every pixel it leaves unflagged has K = N + 1 points in
// one state under the hard pipeline's exact CPU twin — so --aa edge equals --aa full bit for bit —
// and under the double-precision oracle: 0 missed edge pixels), the Chebyshev stencil's misses
// counted, the conservative moment map's bound, the resolve, bad input.
//
// Truth comes from independent code: the hard pipeline's CPU twin (aliasFreeHardCpu) run on every
// sub-sample, and reference::VisibilityOracle; primary visibility by a brute-force ray cast here.
// Scenes: the built-in ones (small), random triangle soups with slivers and triangles crossing the
// ground (contact shadows), far from the origin, point and directional lights.
#include "penumbra/shadow_edge_stencil.hpp"
#include "penumbra/reference/compare.hpp"
#include "penumbra/reference/visibility.hpp"
#include "penumbra/scene/scene.hpp"

#include "support/splitmix.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace {

using glm::dvec3;
using glm::vec2;
using glm::vec3;
using glm::vec4;

struct View {
    uint32_t width = 0, height = 0;
    glm::mat4 view_projection{1.0f};
    penumbra::SampleListsView lists_view() const {
        penumbra::SampleListsView v;
        v.width = width;
        v.height = height;
        v.inverse_view_projection = glm::inverse(view_projection);
        return v;
    }
};

struct Soup {
    std::vector<vec3> positions;
    std::vector<uint32_t> indices;
    std::vector<uint8_t> closed;  // per triangle
    penumbra::AfhCasters casters() const { return {&positions, &indices, &closed}; }
    void add(const penumbra::scene::Mesh& m, const vec3& offset = vec3(0.0f)) {
        const uint32_t base = uint32_t(positions.size());
        for (const vec3& p : m.positions) positions.push_back(p + offset);
        for (uint32_t i : m.indices) indices.push_back(base + i);
        closed.insert(closed.end(), m.indices.size() / 3, m.closed ? 1 : 0);
    }
};

/// Brute-force closest hit of each pixel centre's eye ray (double), the hit rounded to float; face
/// normal per pixel. Background: w = 0.
void castCentres(const Soup& s, const View& v, std::vector<vec4>& centres, std::vector<vec4>& normals) {
    const glm::dmat4 inverse(glm::inverse(v.view_projection));
    centres.assign(size_t(v.width) * v.height, vec4(0.0f));
    normals.assign(centres.size(), vec4(0.0f));
    for (uint32_t y = 0; y < v.height; ++y) {
        for (uint32_t x = 0; x < v.width; ++x) {
            const double nx = (x + 0.5) / v.width * 2 - 1, ny = (y + 0.5) / v.height * 2 - 1;
            glm::dvec4 a = inverse * glm::dvec4(nx, ny, -1, 1), b = inverse * glm::dvec4(nx, ny, 1, 1);
            const dvec3 o = dvec3(a) / a.w, d = dvec3(b) / b.w - o;
            double best = 2.0;
            dvec3 best_n(0.0);
            for (size_t t = 0; t < s.indices.size(); t += 3) {
                const dvec3 p0(s.positions[s.indices[t]]), p1(s.positions[s.indices[t + 1]]), p2(s.positions[s.indices[t + 2]]);
                const dvec3 e1 = p1 - p0, e2 = p2 - p0, q = glm::cross(d, e2);
                const double det = glm::dot(e1, q);
                if (std::abs(det) < 1e-300) continue;
                const dvec3 so = o - p0;
                const double u = glm::dot(so, q) / det;
                if (u < 0 || u > 1) continue;
                const dvec3 r = glm::cross(so, e1);
                const double w = glm::dot(d, r) / det;
                if (w < 0 || u + w > 1) continue;
                const double hit = glm::dot(e2, r) / det;
                if (hit > 0 && hit < best) {
                    best = hit;
                    best_n = glm::cross(e1, e2);
                }
            }
            if (best < 2.0) {
                const size_t i = size_t(y) * v.width + x;
                centres[i] = vec4(vec3(o + best * d), 1.0f);
                normals[i] = vec4(vec3(glm::normalize(best_n)), 0.0f);
            }
        }
    }
}

struct Outcome {
    size_t surface = 0, flagged = 0, edge_truth = 0, missed_exact = 0, missed_oracle = 0, chebyshev_flagged = 0,
           chebyshev_missed = 0, inner_flagged = 0, inner_missed = 0, resolve_mismatch = 0, verdict_mismatch = 0;
};

/// Everything for one (scene, view, light): the stencils, the hard pipeline's CPU twin on the full
/// and the edge buffers, the oracle on every point.
Outcome runCase(const Soup& soup, const View& view, const vec4& light, const penumbra::AaPatternOptions& pattern,
                float reach = 0.0f, double coplanar_epsilon = 1e-7,
                double scene_extent = std::numeric_limits<double>::infinity()) {
    std::vector<vec4> centres, normals;
    castCentres(soup, view, centres, normals);
    const penumbra::AaFootprints f = penumbra::aaFootprintsCpu(view.lists_view(), centres.data(), normals.data(), pattern);
    size_t surface = 0;
    const auto [lo, hi] = penumbra::aaFootprintBounds(f, &surface);
    Outcome out;
    out.surface = surface;
    if (surface == 0) return out;
    penumbra::SampleListsLight lists_light;
    lists_light.light = light;
    lists_light.view_projection = penumbra::lightViewProjectionForBounds(light, lo, hi);
    penumbra::AliasFreeHardOptions o;
    o.grid_width = view.width;
    o.grid_height = view.height;
    o.directional_reach = reach;
    o.max_list_blocks = 64;
    o.coplanar_epsilon = coplanar_epsilon;
    o.scene_extent = scene_extent;
    const penumbra::ProvableStencilCpu stencil = penumbra::provableEdgeStencilCpu(o, lists_light, f, soup.casters());

    // Edge two ways: unflagged pixels' centres sampled (what the Chebyshev stencil needs) and
    // decided by the provable stencil's verdicts alone (AaUnflagged::Proven, the GPU default).
    std::vector<vec4> full_pos, full_nrm, edge_pos, edge_nrm, proven_pos, proven_nrm;
    penumbra::aaSampleBuffer(f, nullptr, full_pos, full_nrm);
    penumbra::aaSampleBuffer(f, stencil.flags.data(), edge_pos, edge_nrm);
    penumbra::aaSampleBuffer(f, stencil.flags.data(), proven_pos, proven_nrm, penumbra::kAaAllPixels,
                             penumbra::AaUnflagged::Proven);
    const auto full = penumbra::aliasFreeHardCpu(o, lists_light, full_pos.data(), full_nrm.data(), uint32_t(full_pos.size()),
                                                 soup.casters());
    const auto edge = penumbra::aliasFreeHardCpu(o, lists_light, edge_pos.data(), edge_nrm.data(), uint32_t(edge_pos.size()),
                                                 soup.casters());
    const std::vector<float> r_full = penumbra::aaResolve(penumbra::AaMode::Full, full, f.pixels, f.samples);
    const std::vector<float> r_edge = penumbra::aaResolve(penumbra::AaMode::Edge, edge, f.pixels, f.samples, stencil.flags.data());
    const auto proven = penumbra::aliasFreeHardCpu(o, lists_light, proven_pos.data(), proven_nrm.data(),
                                                   uint32_t(proven_pos.size()), soup.casters());
    const std::vector<float> r_proven = penumbra::aaResolve(penumbra::AaMode::Edge, proven, f.pixels, f.samples,
                                                            stencil.flags.data(), penumbra::kAaAllPixels, stencil.lit.data());
    for (uint32_t i = 0; i < f.pixels; ++i) out.resolve_mismatch += r_full[i] != r_proven[i];  // background pixels too

    // The oracle on every point (same floats, same coplanar epsilon).
    penumbra::reference::VisibilityOracle oracle(soup.positions, soup.indices);
    std::vector<uint32_t> ids;
    for (uint32_t id = 0; id < full_pos.size(); ++id)
        if (full_pos[id].w != 0.0f) ids.push_back(id);
    penumbra::reference::VisibilityOptions vo;
    vo.coplanar_epsilon = o.coplanar_epsilon;
    const penumbra::reference::HardReference ref =
        penumbra::reference::hardReference(oracle, full_pos, ids, penumbra::reference::hardLight(light, reach), vo);
    std::vector<int> oracle_state(full_pos.size(), -1);  // 0 lit, 1 not lit, 2 tie
    for (size_t r = 0; r < ids.size(); ++r) {
        const uint32_t id = ids[r];
        oracle_state[id] = full[id] == PENUMBRA_AFH_BACK_FACING ? 1 : ref.tie[r] ? 2 : ref.blocked[r] ? 1 : 0;
    }

    const penumbra::MomentMapCpu moments = penumbra::conservativeMomentMapCpu(o, lists_light, soup.casters());
    const std::vector<uint8_t> chebyshev = penumbra::chebyshevEdgeStencilCpu(moments, lists_light, f);
    penumbra::ChebyshevStencilOptions inner_options;
    inner_options.inner_shadow_proof = true;
    const std::vector<uint8_t> inner = penumbra::chebyshevEdgeStencilCpu(moments, lists_light, f, inner_options);

    const uint32_t p = f.pixels, n = f.samples;
    for (uint32_t i = 0; i < p; ++i) {
        if (f.centres[i].w == 0.0f) continue;
        out.flagged += stencil.flags[i];
        out.chebyshev_flagged += chebyshev[i];
        // The exact twin's states of the K points.
        bool agree = true;
        std::set<int> oracle_states;
        oracle_states.insert(oracle_state[i]);
        for (uint32_t k = 0; k < n; ++k) {
            agree = agree && full[p + size_t(i) * n + k] == full[i];
            oracle_states.insert(oracle_state[p + size_t(i) * n + k]);
        }
        const bool oracle_edge = !oracle_states.count(2) && oracle_states.size() > 1;
        out.edge_truth += !agree;
        out.missed_exact += !agree && !stencil.flags[i];
        out.missed_oracle += oracle_edge && !stencil.flags[i];
        out.chebyshev_missed += !agree && !chebyshev[i];
        out.inner_flagged += inner[i];
        out.inner_missed += !agree && !inner[i];
        out.resolve_mismatch += r_full[i] != r_edge[i];
        // An unflagged pixel's verdict is exactly one of lit / shadowed, and its points' state.
        if (!stencil.flags[i] && agree)
            out.verdict_mismatch += stencil.shadowed[i] == stencil.lit[i] || stencil.lit[i] != (full[i] == PENUMBRA_AFH_LIT);
    }
    return out;
}

View sceneView(const penumbra::scene::Scene& s, uint32_t w, uint32_t h, const vec3& offset = vec3(0.0f)) {
    View v;
    v.width = w;
    v.height = h;
    penumbra::scene::Camera c = s.camera;
    c.eye += offset;
    c.target += offset;
    v.view_projection = c.projection(float(w) / float(h)) * c.view();
    return v;
}

void report(const std::string& name, const Outcome& o) {
    MESSAGE(name << ": " << o.surface << " surface pixels, edge (exact twin) " << o.edge_truth << ", provable flagged "
                 << o.flagged << " (missed " << o.missed_exact << ", vs oracle " << o.missed_oracle << "), chebyshev flagged "
                 << o.chebyshev_flagged << " (missed " << o.chebyshev_missed << "), with the inner-coverage proof "
                 << o.inner_flagged << " (missed " << o.inner_missed << ")");
}

void checkSound(const Outcome& o) {
    CHECK(o.missed_exact == 0);
    CHECK(o.missed_oracle == 0);
    CHECK(o.resolve_mismatch == 0);
    CHECK(o.verdict_mismatch == 0);
    CHECK(o.flagged >= o.edge_truth);
}

}  // namespace

TEST_CASE("sub-sample patterns: rotated grid is N-rooks, 4x is RGSS, jittered stays in its stratum") {
    for (uint32_t n : {1u, 2u, 4u, 8u, 16u, 32u, 64u}) {
        penumbra::AaPatternOptions o;
        o.samples = n;
        std::set<int> xs, ys;
        for (uint32_t k = 0; k < n; ++k) {
            const vec2 off = penumbra::aaSubSampleOffset(o, 7, k);
            CHECK(off.x > -0.5f);
            CHECK(off.x < 0.5f);
            CHECK(off.y > -0.5f);
            CHECK(off.y < 0.5f);
            // Centres of the N x N sub-grid: (j + 1/2) / N - 1/2.
            const double gx = (double(off.x) + 0.5) * n - 0.5, gy = (double(off.y) + 0.5) * n - 0.5;
            CHECK(gx == std::round(gx));
            CHECK(gy == std::round(gy));
            xs.insert(int(gx));
            ys.insert(int(gy));
        }
        CHECK(xs.size() == n);
        CHECK(ys.size() == n);
    }
    penumbra::AaPatternOptions o;
    std::set<std::pair<float, float>> rgss;
    for (uint32_t k = 0; k < 4; ++k) {
        const vec2 off = penumbra::aaSubSampleOffset(o, 0, k);
        rgss.insert({off.x, off.y});
    }
    const std::set<std::pair<float, float>> want = {{-0.375f, -0.125f}, {-0.125f, 0.375f}, {0.125f, -0.375f}, {0.375f, 0.125f}};
    CHECK(rgss == want);
    o.pattern = penumbra::AaPattern::Jittered;
    o.samples = 8;  // 2 x 4 strata
    bool differs = false;
    for (uint32_t k = 0; k < 8; ++k) {
        const vec2 a = penumbra::aaSubSampleOffset(o, 3, k), b = penumbra::aaSubSampleOffset(o, 4, k);
        differs = differs || a != b;
        const uint32_t i = k / 4, j = k % 4;
        CHECK(a.x >= j / 4.0f - 0.5f);
        CHECK(a.x < (j + 1) / 4.0f - 0.5f);
        CHECK(a.y >= i / 2.0f - 0.5f);
        CHECK(a.y < (i + 1) / 2.0f - 0.5f);
    }
    CHECK(differs);
    o.samples = 0;
    CHECK_THROWS_WITH_AS(penumbra::checkAaPatternOptions(o), doctest::Contains("samples = 0"), penumbra::Error);
    o.samples = 65;
    CHECK_THROWS_WITH_AS(penumbra::checkAaPatternOptions(o), doctest::Contains("samples = 65"), penumbra::Error);
}

TEST_CASE("sub-samples lie on the pixel's plane and project to their sub-pixel positions") {
    // A tilted plane seen by a perspective camera: every pixel covered.
    View v;
    v.width = 24;
    v.height = 16;
    v.view_projection = glm::perspective(glm::radians(50.0f), 1.5f, 0.1f, 100.0f) *
                        glm::lookAt(vec3(0.3f, 4.0f, 2.0f), vec3(0.0f, 0.0f, 0.0f), vec3(0, 1, 0));
    Soup s;
    const float e = 50.0f;
    s.positions = {{-e, -0.3f * e, -e}, {e, 0.3f * e, -e}, {e, 0.3f * e, e}, {-e, -0.3f * e, e}};
    s.indices = {0, 2, 1, 0, 3, 2};
    s.closed = {0, 0};
    std::vector<vec4> centres, normals;
    castCentres(s, v, centres, normals);
    penumbra::AaPatternOptions pattern;
    pattern.samples = 16;
    const penumbra::AaFootprints f = penumbra::aaFootprintsCpu(v.lists_view(), centres.data(), normals.data(), pattern);
    const dvec3 plane_n = glm::normalize(glm::cross(dvec3(s.positions[2] - s.positions[0]), dvec3(s.positions[1] - s.positions[0])));
    double worst_plane = 0, worst_pixel = 0;
    for (uint32_t i = 0; i < f.pixels; ++i) {
        REQUIRE(f.centres[i].w == 1.0f);
        for (uint32_t k = 0; k < f.samples; ++k) {
            const vec4 q = f.subSamples(i)[k];
            REQUIRE(q.w == 1.0f);
            worst_plane = std::max(worst_plane, std::abs(glm::dot(plane_n, dvec3(q) - dvec3(s.positions[0]))));
            const glm::dvec4 c = glm::dmat4(v.view_projection) * glm::dvec4(dvec3(q), 1.0);
            const double px = (c.x / c.w * 0.5 + 0.5) * v.width, py = (c.y / c.w * 0.5 + 0.5) * v.height;
            const vec2 off = penumbra::aaSubSampleOffset(pattern, i, k);
            worst_pixel = std::max(worst_pixel, std::abs(px - (i % v.width + 0.5 + off.x)));
            worst_pixel = std::max(worst_pixel, std::abs(py - (i / v.width + 0.5 + off.y)));
        }
    }
    MESSAGE("sub-samples: plane distance <= " << worst_plane << ", pixel error <= " << worst_pixel);
    CHECK(worst_plane < 1e-4);  // float rounding of positions ~10 units from the origin
    CHECK(worst_pixel < 1e-3);
    CHECK(f.stretched == 0);
    CHECK(f.fallbacks == 0);

    // Background keeps no sub-samples; a grazing plane is limited to kAaMaxStretch pixel widths.
    std::vector<vec4> one(1, vec4(0.0f)), up(1, vec4(0, 1, 0, 0));
    penumbra::SampleListsView lv = v.lists_view();
    lv.width = lv.height = 1;
    const penumbra::AaFootprints empty = penumbra::aaFootprintsCpu(lv, one.data(), up.data(), pattern);
    for (const vec4& q : empty.sub_samples) CHECK(q.w == 0.0f);
    one[0] = vec4(0.0f, 0.0f, 0.0f, 1.0f);
    const glm::dvec4 eye4 = glm::inverse(glm::dmat4(v.view_projection)) * glm::dvec4(0, 0, -1, 1);
    const vec3 to_eye = glm::normalize(vec3(dvec3(eye4) / eye4.w));
    const vec3 grazing = glm::normalize(glm::cross(to_eye, vec3(1, 0, 0)));  // plane containing the view ray
    std::vector<vec4> nrm(1, vec4(grazing, 0.0f));
    lv.width = 1;
    lv.height = 1;
    const penumbra::AaFootprints g = penumbra::aaFootprintsCpu(lv, one.data(), nrm.data(), pattern);
    CHECK(g.stretched + g.fallbacks > 0);
    penumbra::SampleListsView bad = lv;
    bad.width = 0;
    CHECK_THROWS_WITH_AS(penumbra::aaFootprintsCpu(bad, one.data(), nrm.data(), pattern), doctest::Contains("empty view"),
                         penumbra::Error);
    bad = lv;
    bad.inverse_view_projection[1][2] = std::nanf("");
    CHECK_THROWS_WITH_AS(penumbra::aaFootprintsCpu(bad, one.data(), nrm.data(), pattern), doctest::Contains("not finite"),
                         penumbra::Error);
}

TEST_CASE("provable stencil: built-in scenes, three lights, 4x/8x/16x — 0 missed edge pixels, edge == full") {
    struct Named {
        std::string name;
        penumbra::scene::Scene scene;
    };
    const std::vector<Named> scenes = {{"columns", penumbra::scene::columns(5)},
                                       {"torus_knot", penumbra::scene::torusKnot(24)},
                                       {"hairball", penumbra::scene::hairball(1500)},
                                       {"grass", penumbra::scene::grass(150)}};
    const uint32_t samples[3] = {4, 8, 16};
    int round = 0;
    for (const Named& s : scenes) {
        Soup soup;
        for (const auto& m : s.scene.meshes) soup.add(m);
        const vec3 base = s.scene.light.position;
        const vec3 lights[3] = {base, vec3(-base.x, base.y * 0.7f, base.z + 1.0f), vec3(base.x + 2.0f, base.y * 1.5f, -base.z)};
        for (int l = 0; l < 3; ++l, ++round) {
            penumbra::AaPatternOptions pattern;
            pattern.samples = samples[round % 3];
            const Outcome o = runCase(soup, sceneView(s.scene, 40, 30), vec4(lights[l], 1.0f), pattern);
            report(s.name + " light " + std::to_string(l) + " " + std::to_string(pattern.samples) + "x", o);
            checkSound(o);
            CHECK(o.surface > 0);
        }
    }
}

TEST_CASE("provable stencil: random soups with slivers and ground contacts, far from the origin, directional lights") {
    penumbra::test::SplitMix64 rng(penumbra::test::testSeed(31));
    Outcome total;
    for (int c = 0; c < 8; ++c) {
        penumbra::scene::Scene s = penumbra::scene::columns(1);
        const vec3 offset = c >= 6 ? vec3(1.0e4f, 0.0f, -2.0e4f) : vec3(0.0f);
        Soup soup;
        soup.add(s.meshes[0], offset);  // the ground only
        for (int t = 0; t < 40; ++t) {
            const dvec3 centre(rng.uniform(-1.5, 1.5), rng.uniform(-0.2, 1.2), rng.uniform(-1.5, 1.5));
            dvec3 p[3];
            const int kind = int(rng.below(4));
            for (int k = 0; k < 3; ++k) p[k] = centre + rng.point(-0.4, 0.4);
            if (kind == 1) p[2] = p[0] + (p[1] - p[0]) * rng.uniform(0.1, 0.9) + rng.point(-1e-3, 1e-3);  // sliver
            if (kind == 2) p[0].y = -0.3, p[1].y = 0.4;  // crosses the ground: a contact line
            const uint32_t base = uint32_t(soup.positions.size());
            for (int k = 0; k < 3; ++k) soup.positions.push_back(vec3(p[k]) + offset);
            soup.indices.insert(soup.indices.end(), {base, base + 1, base + 2});
            soup.closed.push_back(0);
        }
        penumbra::AaPatternOptions pattern;
        pattern.samples = c % 2 ? 8 : 4;
        pattern.pattern = c % 3 == 0 ? penumbra::AaPattern::Jittered : penumbra::AaPattern::RotatedGrid;
        pattern.seed = uint32_t(c);
        const bool directional = c % 4 == 3;
        const vec4 light = directional ? vec4(glm::normalize(vec3(0.4f, 1.0f, 0.3f)), 0.0f)
                                       : vec4(vec3(rng.uniform(-2, 2), rng.uniform(2.5, 4), rng.uniform(-2, 2)) + offset, 1.0f);
        const Outcome o = runCase(soup, sceneView(s, 40, 30, offset), light, pattern, directional ? 20.0f : 0.0f);
        report("soup " + std::to_string(c), o);
        checkSound(o);
        total.edge_truth += o.edge_truth;
        total.flagged += o.flagged;
    }
    CHECK(total.edge_truth > 0);  // the cases do have edges
}

TEST_CASE("provable stencil: far lights with scene_extent = the oracle's E, 0 missed edge pixels (issue 41)") {
    // The ground and an occluder quad 0.5 above it; a point light 1e5 and 1e6 away at the depth
    // input's epsilon 2e-5: uncapped, its coplanar reach (2, 20) swallows the occluder and the
    // stencil flags none of the edges the oracle (capped at E) sees.
    const penumbra::scene::Scene s = penumbra::scene::columns(1);
    Soup soup;
    soup.add(s.meshes[0]);  // the ground only
    penumbra::scene::Mesh quad;
    quad.positions = {{-0.3f, 0.5f, -0.2f}, {-0.3f, 0.5f, 0.2f}, {0.3f, 0.5f, 0.2f}, {0.3f, 0.5f, -0.2f}};
    quad.normals.assign(4, vec3(0, 1, 0));
    quad.indices = {0, 1, 2, 0, 2, 3};
    soup.add(quad);
    const double extent = penumbra::reference::VisibilityOracle(soup.positions, soup.indices).sceneExtent();
    const dvec3 u = glm::normalize(dvec3(0.3, 1.0, -0.2));
    for (double distance : {1e5, 1e6}) {
        CAPTURE(distance);
        penumbra::AaPatternOptions pattern;
        pattern.samples = 8;
        const Outcome o = runCase(soup, sceneView(s, 40, 30), vec4(vec3(distance * u), 1.0f), pattern, 0.0f, 2e-5, extent);
        report("far light " + std::to_string(distance), o);
        checkSound(o);
        CHECK(o.edge_truth > 10);
    }
}

TEST_CASE("conservative moment map: every texel's depth is at most the depth of any caster point over it") {
    penumbra::test::SplitMix64 rng(penumbra::test::testSeed(32));
    Soup soup;
    for (int t = 0; t < 30; ++t) {
        const dvec3 centre = rng.point(-1, 1);
        const uint32_t base = uint32_t(soup.positions.size());
        for (int k = 0; k < 3; ++k) soup.positions.push_back(vec3(centre + rng.point(-0.5, 0.5)));
        soup.indices.insert(soup.indices.end(), {base, base + 1, base + 2});
        soup.closed.push_back(0);
    }
    for (const vec4 light : {vec4(0.3f, 6.0f, 0.2f, 1.0f), vec4(0.0f, 1.0f, 0.0f, 0.0f)}) {
        penumbra::AliasFreeHardOptions o;
        o.grid_width = 37;
        o.grid_height = 23;
        o.directional_reach = 20.0f;
        penumbra::SampleListsLight l;
        l.light = light;
        l.view_projection = penumbra::lightViewProjectionForBounds(light, vec3(-2.0f), vec3(2.0f));
        const penumbra::MomentMapCpu m = penumbra::conservativeMomentMapCpu(o, l, soup.casters());
        REQUIRE(m.levels.size() == 6);  // 37x23, 18x11, 9x5, 4x2, 2x1, 1x1
        size_t checked = 0, empty = 0;
        for (size_t t = 0; t < soup.indices.size(); t += 3) {
            for (int s = 0; s < 400; ++s) {
                double u = rng.uniform(), v = rng.uniform();
                if (u + v > 1) u = 1 - u, v = 1 - v;
                const dvec3 p = dvec3(soup.positions[soup.indices[t]]) * (1 - u - v) + dvec3(soup.positions[soup.indices[t + 1]]) * u +
                                dvec3(soup.positions[soup.indices[t + 2]]) * v;
                const glm::dvec4 c = glm::dmat4(l.view_projection) * glm::dvec4(p, 1.0);
                const int x = int(std::floor((c.x / c.w * 0.5 + 0.5) * m.width)), y = int(std::floor((c.y / c.w * 0.5 + 0.5) * m.height));
                if (x < 0 || y < 0 || x >= int(m.width) || y >= int(m.height)) continue;
                const double d = m.perspective ? -1.0 / c.w : c.z / c.w;
                CHECK(double(m.levels[0][size_t(y) * m.width + x].x) <= d);
                ++checked;
            }
        }
        for (const vec2& t : m.levels[0]) empty += t.x == m.d_far;
        CHECK(checked > 1000);
        CHECK(empty > 0);
        // Level 1 texel (0, 0) is the mean of level 0's 2x2.
        const auto& l0 = m.levels[0];
        const double mean = (double(l0[0].x) + l0[1].x + l0[m.width].x + l0[m.width + 1].x) / 4.0;
        CHECK(m.levels[1][0].x == doctest::Approx(mean).epsilon(1e-6));
    }
}

TEST_CASE("resolve and bad input") {
    // 2 pixels, 4 sub-samples: pixel 0 lit with one shadowed sub-sample, pixel 1 shadowed.
    const std::vector<uint32_t> states = {PENUMBRA_AFH_LIT, PENUMBRA_AFH_SHADOWED, PENUMBRA_AFH_LIT, PENUMBRA_AFH_SHADOWED,
                                          PENUMBRA_AFH_LIT, PENUMBRA_AFH_LIT, PENUMBRA_AFH_SHADOWED, PENUMBRA_AFH_SHADOWED,
                                          PENUMBRA_AFH_BACK_FACING, PENUMBRA_AFH_SHADOWED};
    const uint8_t flags[2] = {1, 0};
    CHECK(penumbra::aaResolve(penumbra::AaMode::Off, states, 2, 4) == std::vector<float>{1.0f, 0.0f});
    CHECK(penumbra::aaResolve(penumbra::AaMode::Full, states, 2, 4) == std::vector<float>{0.75f, 0.0f});
    CHECK(penumbra::aaResolve(penumbra::AaMode::Edge, states, 2, 4, flags) == std::vector<float>{0.75f, 0.0f});
    CHECK_THROWS_WITH_AS(penumbra::aaResolve(penumbra::AaMode::Full, states, 2, 8), doctest::Contains("10 states"), penumbra::Error);
    CHECK_THROWS_WITH_AS(penumbra::aaResolve(penumbra::AaMode::Edge, states, 2, 4), doctest::Contains("needs the stencil"),
                         penumbra::Error);

    // The packed edge layout: 3 pixels, 2 sub-samples, pixels 0 and 2 flagged. Every pixel held:
    // pixel 2 (rank 1) at 3 + 2, the held pixels' centres w == 0; a budget of 1 pixel: 3 + 2
    // samples, pixel 2 single-sampled (its centre kept).
    {
        penumbra::AaFootprints g;
        g.pixels = 3;
        g.samples = 2;
        for (int i = 0; i < 3; ++i) {
            g.centres.emplace_back(float(i), 0.0f, 0.0f, 1.0f);
            g.normals.emplace_back(0.0f, 1.0f, 0.0f, 0.0f);
            g.sub_samples.emplace_back(float(i), 1.0f, 0.0f, 1.0f);
            g.sub_samples.emplace_back(float(i), 2.0f, 0.0f, 1.0f);
        }
        const uint8_t g_flags[3] = {1, 0, 1};
        std::vector<vec4> pos, nrm;
        penumbra::aaSampleBuffer(g, g_flags, pos, nrm);
        REQUIRE(pos.size() == 9);
        CHECK(pos[0] == vec4(0.0f));  // held: the lists skip the centre
        CHECK(nrm[0] == vec4(0.0f));
        CHECK(pos[1] == vec4(1, 0, 0, 1));
        CHECK(nrm[1] == vec4(0, 1, 0, 0));
        CHECK(pos[2] == vec4(0.0f));
        CHECK(pos[3] == vec4(0, 1, 0, 1));
        CHECK(pos[5] == vec4(2, 1, 0, 1));
        CHECK(pos[6] == vec4(2, 2, 0, 1));
        CHECK(pos[7].w == 0.0f);  // unused blocks of the budget
        CHECK(pos[8].w == 0.0f);
        penumbra::aaSampleBuffer(g, g_flags, pos, nrm, 1);
        REQUIRE(pos.size() == 5);
        CHECK(pos[0] == vec4(0.0f));
        CHECK(pos[2] == vec4(2, 0, 0, 1));  // past the budget: single-sampled
        CHECK(pos[4] == vec4(0, 2, 0, 1));
        CHECK(penumbra::aaSampleCount(penumbra::AaMode::Edge, 3, 2, 1) == 5);
        CHECK(penumbra::aaSampleCount(penumbra::AaMode::Full, 3, 2, 1) == 9);
        CHECK(penumbra::aaBudgetOverflow(g_flags, 3, 1) == 1);
        CHECK(penumbra::aaBudgetOverflow(g_flags, 3, 2) == 0);
        const uint32_t L = PENUMBRA_AFH_LIT, S = PENUMBRA_AFH_SHADOWED;
        const std::vector<uint32_t> held = {S, L, L, L, S, S, L, S, S};  // centres, ranks 0 and 1, an unused block
        CHECK(penumbra::aaResolve(penumbra::AaMode::Edge, held, 3, 2, g_flags) == std::vector<float>{0.5f, 1.0f, 0.5f});
        const std::vector<uint32_t> budget_one = {S, L, L, L, S};
        CHECK(penumbra::aaResolve(penumbra::AaMode::Edge, budget_one, 3, 2, g_flags, 1) == std::vector<float>{0.5f, 1.0f, 1.0f});
        CHECK_THROWS_WITH_AS(penumbra::aaResolve(penumbra::AaMode::Edge, budget_one, 3, 2, g_flags), doctest::Contains("5 states"),
                             penumbra::Error);

        // AaUnflagged::Proven: the unflagged pixel 1 is no sample either, the resolve takes the
        // stencil's verdict (lit or not) whatever its slot says; flagged pixels as before.
        penumbra::aaSampleBuffer(g, g_flags, pos, nrm, penumbra::kAaAllPixels, penumbra::AaUnflagged::Proven);
        REQUIRE(pos.size() == 9);
        CHECK(pos[0] == vec4(0.0f));
        CHECK(pos[1] == vec4(0.0f));
        CHECK(nrm[1] == vec4(0.0f));
        CHECK(pos[3] == vec4(0, 1, 0, 1));
        CHECK(pos[6] == vec4(2, 2, 0, 1));
        penumbra::aaSampleBuffer(g, g_flags, pos, nrm, 1, penumbra::AaUnflagged::Proven);
        REQUIRE(pos.size() == 5);
        CHECK(pos[1] == vec4(0.0f));
        CHECK(pos[2] == vec4(2, 0, 0, 1));  // flagged past the budget: its centre is still a sample
        const uint32_t N = PENUMBRA_AFH_NO_SAMPLE;
        const uint8_t dark[3] = {0, 0, 0}, lit_one[3] = {0, 1, 0};
        const std::vector<uint32_t> proven = {N, N, N, L, S, S, L, S, S};
        CHECK(penumbra::aaResolve(penumbra::AaMode::Edge, proven, 3, 2, g_flags, penumbra::kAaAllPixels, dark) ==
              std::vector<float>{0.5f, 0.0f, 0.5f});
        CHECK(penumbra::aaResolve(penumbra::AaMode::Edge, proven, 3, 2, g_flags, penumbra::kAaAllPixels, lit_one) ==
              std::vector<float>{0.5f, 1.0f, 0.5f});
        const std::vector<uint32_t> proven_budget_one = {N, N, L, L, S};
        CHECK(penumbra::aaResolve(penumbra::AaMode::Edge, proven_budget_one, 3, 2, g_flags, 1, lit_one) ==
              std::vector<float>{0.5f, 1.0f, 1.0f});
    }

    penumbra::AaFootprints f;
    f.pixels = 1;
    f.samples = 4;
    f.centres.assign(1, vec4(0.0f));
    f.normals.assign(1, vec4(0.0f));
    f.sub_samples.assign(4, vec4(0.0f));
    Soup soup;
    penumbra::SampleListsLight l;
    penumbra::AliasFreeHardOptions o;
    o.grid_width = o.grid_height = 4;
    o.precision = penumbra::AfhPrecision::Fast;
    CHECK_THROWS_WITH_AS(penumbra::provableEdgeStencilCpu(o, l, f, soup.casters()), doctest::Contains("exact hard pipeline"),
                         penumbra::Error);
    o.precision = penumbra::AfhPrecision::Exact;
    f.sub_samples.resize(3);
    CHECK_THROWS_WITH_AS(penumbra::provableEdgeStencilCpu(o, l, f, soup.casters()), doctest::Contains("inconsistent"),
                         penumbra::Error);
    penumbra::MomentMapCpu m;
    penumbra::ChebyshevStencilOptions c;
    c.threshold = 1.5f;
    CHECK_THROWS_WITH_AS(penumbra::chebyshevEdgeStencilCpu(m, l, f, c), doctest::Contains("threshold 1.5"), penumbra::Error);
}

TEST_CASE("afhGridSideForSamples: about one texel per sample, a quarter octave finer") {
    // 2^e for 2^(2e - 1.5) <= samples < 2^(2e + 0.5), within [16, kSampleListsMaxGridSide].
    CHECK(penumbra::afhGridSideForSamples(0) == 16);
    CHECK(penumbra::afhGridSideForSamples(1) == 16);
    CHECK(penumbra::afhGridSideForSamples(512u * 384u) == 512);       // the demo's view: its own size
    CHECK(penumbra::afhGridSideForSamples(512u * 512u) == 512);
    CHECK(penumbra::afhGridSideForSamples(512u * 512u * 5u) == 1024);  // full, N = 4
    CHECK(penumbra::afhGridSideForSamples(21368) == 128);              // edge runs of BM_ShadowEdgeStencil
    CHECK(penumbra::afhGridSideForSamples(28732) == 256);
    CHECK(penumbra::afhGridSideForSamples(68772) == 256);
    // The boundaries: 2^14.5 = 23170.5 and 2^16.5 = 92681.9 between 128, 256 and 512.
    CHECK(penumbra::afhGridSideForSamples(23170) == 128);
    CHECK(penumbra::afhGridSideForSamples(23171) == 256);
    CHECK(penumbra::afhGridSideForSamples(92681) == 256);
    CHECK(penumbra::afhGridSideForSamples(92682) == 512);
    CHECK(penumbra::afhGridSideForSamples(uint64_t(1) << 40) == penumbra::kSampleListsMaxGridSide);
    CHECK(penumbra::afhGridSideForSamples(~uint64_t(0)) == penumbra::kSampleListsMaxGridSide);
}
