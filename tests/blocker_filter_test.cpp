// The float filter in front of the exact blocker test (penumbra/detail/blocker_filter.hpp, the
// GLSL penumbraAfhBlocksFilter): wherever it says "certain", its verdict equals the double test
// (afhBlocks<double>, the fp64-only path's CPU twin), and every sign it certifies equals the
// double sign and, on a subset, the exact sign (GMP rationals) — on > 10^6 random and adversarial
// cases: near-coplanar samples, samples on edges and vertices, lines through edges and vertices,
// slivers and degenerate triangles, tiny and huge triangles, far from the origin (1e3 .. 1e6),
// samples at the coplanar epsilon, lights on the caster's plane, directional lights, offsets.
// Then the GPU: the filtered GLSL and the fp64-only GLSL on the same inputs in a compute shader
// give identical verdicts, and the GPU's filter states equal the CPU model's.
#include <penumbra/detail/blocker_filter.hpp>
#include <penumbra/gl/shader.hpp>
#include <penumbra/gl/objects.hpp>
#include <penumbra/gl/pipelines/alias_free_hard.hpp>
#include <penumbra/scene/scene.hpp>

#include "support/gl_test_support.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>
#include <gmpxx.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

using penumbra::detail::BlockerFilterState;

struct Case {
    glm::vec3 a, b, c, p;
    glm::vec4 light;  // w = 1 point, w = 0 directional (unit xyz)
    float reach = 0;
    double eps = 1e-7, offset = 0;
    double extent = std::numeric_limits<double>::infinity();  // E of the coplanar scale (+inf: uncapped)
};

enum Kind {
    kRandom,
    kOnPlane,
    kOnEdge,
    kOnVertex,
    kLineThroughEdge,
    kLineThroughVertex,
    kSliver,
    kDegenerate,
    kEpsilonTie,
    kLightOnPlane,
    kOffsetTie,
    kKinds
};
const char* const kKindNames[kKinds] = {"random",         "on plane",  "on edge",    "on vertex",      "line via edge",
                                        "line via vertex", "sliver",   "degenerate", "at epsilon",     "light on plane",
                                        "at offset"};

struct Generator {
    std::mt19937 rng;
    const Case* fixed = nullptr;  // when set: its light, reach, eps and offset for every case
    explicit Generator(uint32_t seed) : rng(seed) {}
    float uni(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); }
    int pick(int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
    glm::vec3 vec(float r) { return glm::vec3(uni(-r, r), uni(-r, r), uni(-r, r)); }
    glm::vec3 unit() {
        glm::vec3 v;
        do v = vec(1.0f);
        while (glm::length(v) < 0.1f || glm::length(v) > 1.0f);
        return glm::normalize(v);
    }

    Case make(Kind kind) {
        static const float kCenters[] = {0.0f, 1e3f, 1e5f, 1e6f};
        static const float kSizes[] = {1e-3f, 1.0f, 30.0f, 1e3f};
        static const double kEpsilons[] = {1e-7, 1e-9, 0.0, 1e-4};
        const float center_r = kCenters[pick(4)];
        const glm::vec3 center = center_r == 0.0f ? glm::vec3(0.0f) : vec(center_r);
        const float size = kSizes[pick(4)];
        // Triangle size relative to the scene: tiny (1e-5) .. huge (10x the scene).
        static const float kTriangle[] = {1e-5f, 1e-2f, 0.3f, 1.0f, 10.0f};
        const float tri = size * kTriangle[pick(5)];
        Case k;
        k.eps = kEpsilons[pick(4)];
        const glm::vec3 base = center + vec(size);
        k.a = base;
        k.b = base + vec(tri);
        k.c = base + vec(tri);
        const bool directional_pick = pick(4) == 0;
        const glm::vec3 above = center + glm::vec3(uni(-size, size), 3.0f * size, uni(-size, size));
        if (directional_pick) {
            k.light = glm::vec4(unit(), 0.0f);
            k.reach = 4.0f * size;
        } else {
            k.light = glm::vec4(pick(2) ? above : center + vec(3.0f * size), 1.0f);
        }
        if (pick(8) == 0) k.offset = double(size) * 1e-3;
        if (kind == kOffsetTie) k.offset = double(size) * 1e-3;
        if (fixed) {
            k.light = fixed->light, k.reach = fixed->reach, k.eps = fixed->eps, k.offset = fixed->offset;
        }
        const bool directional = k.light.w == 0.0f;
        const auto point = [&](float u, float v) { return k.a + u * (k.b - k.a) + v * (k.c - k.a); };
        const glm::vec3 n = glm::cross(k.b - k.a, k.c - k.a);
        const glm::vec3 nhat = glm::length(n) > 0 ? glm::normalize(n) : glm::vec3(0, 1, 0);
        const glm::vec3 l = glm::vec3(k.light);
        switch (kind) {
        case kRandom:
            k.p = center + vec(size);
            break;
        case kOnPlane:  // on the triangle's plane, inside or outside it, up to a few ulps off
            k.p = point(uni(-0.5f, 1.5f), uni(-0.5f, 1.5f));
            if (pick(2)) k.p += nhat * (float(pick(5) - 2) * std::max(1e-7f * glm::length(k.p), 1e-30f));
            break;
        case kOnEdge: {
            const float s = uni(0.0f, 1.0f);
            const int e = pick(3);
            k.p = e == 0 ? k.a + s * (k.b - k.a) : e == 1 ? k.b + s * (k.c - k.b) : k.c + s * (k.a - k.c);
            if (pick(2)) k.p += vec(1e-6f * tri);
            break;
        }
        case kOnVertex:
            k.p = pick(3) == 0 ? k.a : pick(2) ? k.b : k.c;
            if (pick(2)) k.p += vec(1e-6f * tri);
            break;
        case kLineThroughEdge:
        case kLineThroughVertex: {
            // p beyond (or before) an edge point seen from the light: the line through l and p
            // grazes the edge (e_i ~ 0).
            const float s = kind == kLineThroughVertex ? 0.0f : uni(0.0f, 1.0f);
            const int e = pick(3);
            const glm::vec3 q = e == 0 ? k.a + s * (k.b - k.a) : e == 1 ? k.b + s * (k.c - k.b) : k.c + s * (k.a - k.c);
            const glm::vec3 from = directional ? q + glm::vec3(k.light) * k.reach : l;
            k.p = from + uni(0.2f, 3.0f) * (q - from);
            if (directional) k.p = q - glm::vec3(k.light) * (uni(0.1f, 2.0f) * size);
            break;
        }
        case kSliver: {
            const float s = uni(0.0f, 1.0f);
            k.c = k.a + s * (k.b - k.a) + vec(tri * std::pow(10.0f, -float(pick(6) + 2)));
            k.p = pick(2) ? center + vec(size) : point(uni(0.0f, 1.0f), uni(0.0f, 1.0f));
            break;
        }
        case kDegenerate:
            if (pick(2)) k.c = k.a;
            else k.c = k.a + 2.0f * (k.b - k.a);
            k.p = pick(2) ? center + vec(size) : point(uni(0.0f, 1.0f), 0.0f);
            break;
        case kEpsilonTie: {
            // At (1 +- 1e-3) * eps * scale from the plane, inside the triangle: the coplanar rule's
            // threshold itself.
            const glm::vec3 q = point(uni(0.05f, 0.45f), uni(0.05f, 0.45f));
            const float scale = std::max(glm::length(l - q), tri);
            k.p = q + nhat * (float(k.eps) * scale * (pick(2) ? 1.001f : 0.999f) * (pick(2) ? 1.0f : -1.0f));
            break;
        }
        case kLightOnPlane:
            if (fixed) {  // the batch's light: put the triangle's plane through it instead
                k.c = glm::vec3(k.light) + uni(-1.0f, 2.0f) * (k.a - glm::vec3(k.light)) + uni(-1.0f, 2.0f) * (k.b - glm::vec3(k.light));
            } else {
                k.light = glm::vec4(point(uni(-1.0f, 2.0f), uni(-1.0f, 2.0f)), 1.0f);
            }
            k.p = center + vec(size);
            break;
        case kOffsetTie: {
            const glm::vec3 q = point(uni(0.05f, 0.45f), uni(0.05f, 0.45f));
            const float side = glm::dot(nhat, l - q) > 0 ? -1.0f : 1.0f;  // behind the plane, seen from the light
            k.p = q + nhat * (side * float(k.offset) * uni(0.99f, 1.01f));
            break;
        }
        default:
            break;
        }
        return k;
    }
};

bool exactTest(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c, const glm::dvec3& p, const glm::dvec3& l,
               double eps, double offset, double extent) {
    return penumbra::afhBlocks<double>(a, b, c, p, l, eps, offset, extent);
}

int sign(double x) { return x > 0 ? 1 : (x < 0 ? -1 : 0); }

mpq_class exactDet(const std::array<mpq_class, 3>& u, const std::array<mpq_class, 3>& v, const std::array<mpq_class, 3>& w) {
    const mpq_class cx = u[1] * v[2] - u[2] * v[1], cy = u[2] * v[0] - u[0] * v[2], cz = u[0] * v[1] - u[1] * v[0];
    return cx * w[0] + cy * w[1] + cz * w[2];
}

// |computed - exact| / bound: how much of the proven bound an evaluation used.
double usedBound(double computed, const mpq_class& exact, float bound) {
    if (!(bound > 0)) return 0.0;
    return std::abs(mpq_class(mpq_class(computed) - exact).get_d()) / double(bound);
}

std::array<mpq_class, 3> rational(const glm::dvec3& v) { return {mpq_class(v.x), mpq_class(v.y), mpq_class(v.z)}; }
std::array<mpq_class, 3> minus(const std::array<mpq_class, 3>& x, const std::array<mpq_class, 3>& y) {
    return {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
}

struct Tally {
    uint64_t cases[kKinds] = {}, uncertain[kKinds] = {};
    uint64_t verdict_mismatch = 0, double_sign_mismatch = 0, exact_sign_mismatch = 0, exact_checked = 0;
    uint64_t why_plane = 0, why_edge = 0, why_coplanar = 0;  // first reason of each fallback
    double used_float = 0, used_double = 0;  // largest share of the bound the float / double errors used
    uint64_t coplanar_mismatch = 0, offset_mismatch = 0, filtered_mismatch = 0;
    uint64_t total() const {
        uint64_t n = 0;
        for (uint64_t c : cases) n += c;
        return n;
    }
};

// One case on the CPU: the filter's certificates against the double values (and exact signs when
// `exact`), its verdict against afhBlocks<double>.
void check(const Case& k, Kind kind, bool exact, Tally& tally) {
    glm::vec3 lf;
    float l_error;
    penumbra::detail::blockerFilterLightPoint(k.p, k.light, k.reach, lf, l_error);
    penumbra::detail::BlockerFilterTrace t;
    const BlockerFilterState state = penumbra::detail::blockerFilter(k.a, k.b, k.c, k.p, lf, l_error, k.eps, k.offset, k.extent, &t);
    const bool point_light = k.light.w != 0.0f;
    const glm::dvec3 a(k.a), b(k.b), c(k.c), p(k.p);
    const glm::dvec3 l = penumbra::detail::blockerLightPoint(p, glm::dvec3(glm::vec3(k.light)), double(k.reach), point_light);
    const bool expected = exactTest(a, b, c, p, l, k.eps, k.offset, k.extent);
    ++tally.cases[kind];
    if (state == BlockerFilterState::Uncertain) {
        ++tally.uncertain[kind];
        if (t.sp == 0 || t.sl == 0) ++tally.why_plane;
        else if (t.se[0] == 0 || t.se[1] == 0 || t.se[2] == 0) ++tally.why_edge;
        else ++tally.why_coplanar;
    }
    else if ((state == BlockerFilterState::True) != expected) {
        if (++tally.verdict_mismatch <= 5)
            MESSAGE("verdict mismatch (", std::string(kKindNames[kind]), "): filter ", int(state), " double ", expected);
    }
    const bool filtered = penumbra::detail::blockerFiltered(k.a, k.b, k.c, k.p, k.light, k.reach, k.eps, k.offset, k.extent,
                                                            exactTest);
    tally.filtered_mismatch += filtered != expected;

    // The double values the fp64 path compares (afhBlocks<double>, same operations).
    const glm::dvec3 ab = b - a, ac = c - a, ap = p - a, al = l - a;
    const double nx = ab.y * ac.z - ab.z * ac.y, ny = ab.z * ac.x - ab.x * ac.z, nz = ab.x * ac.y - ab.y * ac.x;
    const double dp = nx * ap.x + ny * ap.y + nz * ap.z, dl = nx * al.x + ny * al.y + nz * al.z;
    const glm::dvec3 bp = p - b, cp = p - c, lp = p - l;  // e_i taken at p, as afhBlocks
    const double e[3] = {penumbra::detail::afhDet(ap, bp, lp), penumbra::detail::afhDet(bp, cp, lp),
                         penumbra::detail::afhDet(cp, ap, lp)};
    uint64_t bad = 0;
    if (t.sp != 0) bad += sign(dp) != t.sp;
    if (t.sl != 0) bad += sign(dl) != t.sl;
    for (int i = 0; i < 3; ++i) {
        if (t.se[i] != 0) bad += sign(e[i]) != t.se[i];
    }
    if (bad && ++tally.double_sign_mismatch <= 5) MESSAGE("double sign mismatch (", std::string(kKindNames[kind]), ")");
    if (t.coplanar_certified || t.offset_certified) {
        const double nn = nx * nx + ny * ny + nz * nz;
        const double scale = std::max(std::max(penumbra::detail::afhMaxAbs<double>(a - p), penumbra::detail::afhMaxAbs<double>(b - p)),
                                      std::max(penumbra::detail::afhMaxAbs<double>(c - p),
                                               std::min(penumbra::detail::afhMaxAbs<double>(l - p), k.extent)));
        const double tol = k.eps * scale, threshold = tol * tol * nn;
        if (t.coplanar_certified) tally.coplanar_mismatch += !(dp * dp > threshold && dl * dl > threshold);
        if (t.offset_certified) tally.offset_mismatch += (dp * dp <= k.offset * k.offset * nn) != (t.offset_certified < 0);
    }
    if (exact) {
        ++tally.exact_checked;
        const auto A = rational(a), B = rational(b), C = rational(c), P = rational(p), L = rational(l);
        const auto AB = minus(B, A), AC = minus(C, A);
        const auto LA = minus(A, L), LB = minus(B, L), LC = minus(C, L), LP = minus(P, L);
        const mpq_class X[5] = {exactDet(AB, AC, minus(P, A)), exactDet(AB, AC, minus(L, A)), exactDet(LA, LB, LP),
                                exactDet(LB, LC, LP), exactDet(LC, LA, LP)};
        const int certified[5] = {t.sp, t.sl, t.se[0], t.se[1], t.se[2]};
        const float xf[5] = {t.dp, t.dl, t.e[0], t.e[1], t.e[2]};
        const double xd[5] = {dp, dl, e[0], e[1], e[2]};
        const float bound[5] = {t.b_dp, t.b_dl, t.be[0], t.be[1], t.be[2]};
        uint64_t wrong = 0;
        for (int i = 0; i < 5; ++i) {
            if (certified[i] != 0) wrong += sgn(X[i]) != certified[i];
            if (i >= 2 && !t.edges_reached) continue;
            // Point lights only: a directional light's float point differs from the double one,
            // the bound's l_error term covers that and would flatter the ratio.
            if (!point_light) continue;
            tally.used_float = std::max(tally.used_float, usedBound(xf[i], X[i], bound[i]));
            tally.used_double = std::max(tally.used_double, usedBound(xd[i], X[i], bound[i]));
        }
        if (wrong && ++tally.exact_sign_mismatch <= 5) MESSAGE("exact sign mismatch (", std::string(kKindNames[kind]), ")");
    }
}

void report(const Tally& tally, const char* what) {
    for (int kind = 0; kind < kKinds; ++kind) {
        if (!tally.cases[kind]) continue;
        MESSAGE(std::string(what), " ", std::string(kKindNames[kind]), ": ", tally.cases[kind], " cases, fallback ",
                100.0 * double(tally.uncertain[kind]) / double(tally.cases[kind]), " %");
    }
}

// Realistic pairs: view samples on the surfaces of a built-in scene (float barycentric points),
// its light, and for every sample the triangles whose bounding sphere the light ray passes (the
// light pass's conservative coverage, roughly). `max_pairs` caps the count.
struct ScenePairs {
    std::vector<glm::vec3> triangles;  // 3 per triangle
    std::vector<uint32_t> pair_triangle;
    std::vector<glm::vec3> pair_sample;
    glm::vec4 light;
};

ScenePairs scenePairs(const std::string& name, uint32_t samples, size_t max_pairs, uint32_t seed) {
    const penumbra::scene::Scene scene = penumbra::scene::builtin(name);
    const penumbra::scene::Mesh mesh = scene.merged();
    ScenePairs out;
    out.light = glm::vec4(scene.light.position, 1.0f);
    const size_t n = mesh.triangleCount();
    std::vector<glm::vec3> centers(n);
    std::vector<float> radii(n);
    std::vector<float> areas(n);
    for (size_t t = 0; t < n; ++t) {
        const glm::vec3 v[3] = {mesh.positions[mesh.indices[3 * t]], mesh.positions[mesh.indices[3 * t + 1]],
                                mesh.positions[mesh.indices[3 * t + 2]]};
        for (const auto& x : v) out.triangles.push_back(x);
        centers[t] = (v[0] + v[1] + v[2]) / 3.0f;
        radii[t] = std::max(glm::length(v[0] - centers[t]), std::max(glm::length(v[1] - centers[t]), glm::length(v[2] - centers[t])));
        areas[t] = glm::length(glm::cross(v[1] - v[0], v[2] - v[0])) + (t ? areas[t - 1] : 0.0f);
    }
    std::mt19937 rng(seed);
    const glm::vec3 light(out.light);
    for (uint32_t s = 0; s < samples && out.pair_sample.size() < max_pairs; ++s) {
        const float pick = std::uniform_real_distribution<float>(0.0f, areas.back())(rng);
        const size_t t = std::min(size_t(std::lower_bound(areas.begin(), areas.end(), pick) - areas.begin()), n - 1);
        float u = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng), v = std::uniform_real_distribution<float>(0.0f, 1.0f)(rng);
        if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
        const glm::vec3 a = out.triangles[3 * t], b = out.triangles[3 * t + 1], c = out.triangles[3 * t + 2];
        const glm::vec3 p = a + u * (b - a) + v * (c - a);
        const glm::vec3 d = glm::normalize(p - light);
        const float reach = glm::length(p - light);
        for (size_t k = 0; k < n; ++k) {
            const glm::vec3 w = centers[k] - light;
            const float along = glm::dot(w, d);
            if (along < -radii[k] || along > reach + radii[k]) continue;
            if (glm::length(w - along * d) > radii[k] * 1.05f + 1e-3f * along) continue;
            out.pair_triangle.push_back(uint32_t(k));
            out.pair_sample.push_back(p);
        }
    }
    return out;
}

}  // namespace

TEST_CASE("filter certificates equal the double test (and exact signs) on 10^6 adversarial cases") {
    Generator gen(penumbra::test::testSeed());
    Tally tally;
    const uint64_t per_kind = 100000;
    for (int kind = 0; kind < kKinds; ++kind) {
        for (uint64_t i = 0; i < per_kind; ++i) check(gen.make(Kind(kind)), Kind(kind), i % 8 == 0, tally);
    }
    report(tally, "adversarial");
    MESSAGE("exact (GMP) checks: ", tally.exact_checked, "; largest |float - exact| / bound ", tally.used_float,
            ", largest |double - exact| / bound ", tally.used_double, " (their sum must stay below 1)");
    CHECK(tally.used_float + tally.used_double < 1.0);
    CHECK(tally.total() >= 1000000);
    CHECK(tally.verdict_mismatch == 0);
    CHECK(tally.filtered_mismatch == 0);
    CHECK(tally.double_sign_mismatch == 0);
    CHECK(tally.exact_sign_mismatch == 0);
    CHECK(tally.coplanar_mismatch == 0);
    CHECK(tally.offset_mismatch == 0);
}

TEST_CASE("filter certificates equal the double test with a capped scene extent E (far lights, issue 41)") {
    // The coplanar certificate takes min(|l - p| + l_error, fl(min(E, 1e38)) + 1e-36) for the
    // segment's term: an upper bound of the double test's min(|l - p|, E) for every E > 0, tiny or
    // huge. Lights moved 1e3-1e6 further out along their direction, E from 1e-30 to +inf.
    Generator gen(penumbra::test::testSeed() + 41);
    Tally tally;
    static const double kExtents[] = {1e-30, 1e-3, 0.5, 1.0, 2.0, 1e6, 1e38, 1e300, std::numeric_limits<double>::infinity()};
    static const float kFar[] = {1.0f, 1e3f, 1e4f, 1e6f};
    uint64_t coplanar_certified_capped = 0;
    for (int kind = 0; kind < kKinds; ++kind) {
        for (uint64_t i = 0; i < 20000; ++i) {
            Case k = gen.make(Kind(kind));
            const float far = kFar[gen.pick(4)];
            if (k.light.w != 0.0f) k.light = glm::vec4(k.a + far * (glm::vec3(k.light) - k.a), 1.0f);
            else k.reach *= far;
            const double tri = std::max(penumbra::detail::afhMaxAbs<double>(glm::dvec3(k.b) - glm::dvec3(k.a)),
                                        penumbra::detail::afhMaxAbs<double>(glm::dvec3(k.c) - glm::dvec3(k.a)));
            k.extent = gen.pick(3) == 0 ? tri * double(gen.uni(0.5f, 4.0f)) : kExtents[gen.pick(9)];
            if (!(k.extent > 0)) k.extent = 1e-30;  // a degenerate triangle's zero size
            penumbra::detail::BlockerFilterTrace t;
            glm::vec3 lf;
            float l_error;
            penumbra::detail::blockerFilterLightPoint(k.p, k.light, k.reach, lf, l_error);
            penumbra::detail::blockerFilter(k.a, k.b, k.c, k.p, lf, l_error, k.eps, k.offset, k.extent, &t);
            coplanar_certified_capped += t.coplanar_certified && k.extent < 1e38;
            check(k, Kind(kind), i % 16 == 0, tally);
        }
    }
    report(tally, "far lights, capped E");
    MESSAGE(tally.total(), " cases, ", coplanar_certified_capped, " coplanar certificates under a finite E");
    CHECK(coplanar_certified_capped > 1000);  // the capped certificate is exercised
    CHECK(tally.verdict_mismatch == 0);
    CHECK(tally.filtered_mismatch == 0);
    CHECK(tally.double_sign_mismatch == 0);
    CHECK(tally.exact_sign_mismatch == 0);
    CHECK(tally.coplanar_mismatch == 0);
    CHECK(tally.offset_mismatch == 0);
}

TEST_CASE("filter: non-finite and overflowing inputs are never certain") {
    const glm::vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
    const float big = 1e30f;
    CHECK(penumbra::detail::blockerFilter(a, b, c, glm::vec3(0.2f, 0.2f, -big), glm::vec3(0.2f, 0.2f, big), 0.0f, 1e-7, 0.0) ==
          BlockerFilterState::Uncertain);
    const float inf = std::numeric_limits<float>::infinity();
    CHECK(penumbra::detail::blockerFilter(a, b, c, glm::vec3(0.2f, 0.2f, -1), glm::vec3(0.2f, 0.2f, inf), 0.0f, 1e-7, 0.0) ==
          BlockerFilterState::Uncertain);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    CHECK(penumbra::detail::blockerFilter(a, b, c, glm::vec3(nan, 0.2f, -1), glm::vec3(0.2f, 0.2f, 1), 0.0f, 1e-7, 0.0) ==
          BlockerFilterState::Uncertain);
    // A plain crossing is certain (the filter is not vacuous).
    CHECK(penumbra::detail::blockerFilter(a, b, c, glm::vec3(0.2f, 0.2f, -1), glm::vec3(0.2f, 0.2f, 1), 0.0f, 1e-7, 0.0) ==
          BlockerFilterState::True);
}

TEST_CASE("filter fallback rate on realistic pairs (built-in scenes)") {
    for (const char* name : {"torus_knot", "columns", "hairball"}) {
        const ScenePairs pairs = scenePairs(name, 3000, 400000, penumbra::test::testSeed(1));
        Tally tally;
        for (size_t i = 0; i < pairs.pair_sample.size(); ++i) {
            Case k;
            const uint32_t t = pairs.pair_triangle[i];
            k.a = pairs.triangles[3 * t], k.b = pairs.triangles[3 * t + 1], k.c = pairs.triangles[3 * t + 2];
            k.p = pairs.pair_sample[i];
            k.light = pairs.light;
            check(k, kRandom, i % 16 == 0, tally);
        }
        MESSAGE(std::string(name), ": ", tally.total(), " pairs, fallback ", 100.0 * double(tally.uncertain[kRandom]) / double(tally.total()),
                " % (sample or light within float noise of the plane: ", tally.why_plane, ", line near an edge: ", tally.why_edge,
                ", coplanar band: ", tally.why_coplanar, ")");
        CHECK(tally.verdict_mismatch == 0);
        CHECK(tally.double_sign_mismatch == 0);
        CHECK(tally.exact_sign_mismatch == 0);
        CHECK(tally.coplanar_mismatch == 0);
    }
}

TEST_CASE("GPU: filtered GLSL == fp64-only GLSL on the same inputs; GPU filter states == CPU model") {
    penumbra::test::context();
    penumbra::ShaderLibrary lib = penumbra::ShaderLibrary::embedded();
    lib.addDirectory(penumbra::test::testShaderDir());
    penumbra::gl::Program program = penumbra::gl::buildComputeProgram(
        "alias_free_hard/blocker_filter_test.comp.glsl", {{"PENUMBRA_AFH_FILTER_TEST_MODE", "0"}}, lib);
    penumbra::gl::Program deferred = penumbra::gl::buildComputeProgram(
        "alias_free_hard/blocker_filter_test.comp.glsl", {{"PENUMBRA_AFH_FILTER_TEST_MODE", "2"}}, lib);
    Generator gen(penumbra::test::testSeed(2));
    // Batches share light, reach, eps and offset (uniforms): each batch draws one case's settings
    // and then many cases' geometry with them.
    uint64_t total = 0, mismatched = 0, state_mismatched = 0, uncertain = 0, cpu_mismatched = 0;
    const int batches = 220;
    const uint32_t per_batch = 1024;
    for (int batch = 0; batch < batches; ++batch) {
        const Kind kind = Kind(batch % kKinds);
        const Case settings = gen.make(kind);
        std::vector<glm::vec4> triangles, samples;
        std::vector<glm::uvec4> fragments;
        std::vector<Case> cases;
        gen.fixed = &settings;
        for (uint32_t i = 0; i < per_batch; ++i) {
            const Case k = gen.make(kind);
            cases.push_back(k);
            fragments.push_back(glm::uvec4(i, i, 1u, 0u));
            triangles.push_back(glm::vec4(k.a, 1.0f));
            triangles.push_back(glm::vec4(k.b, 1.0f));
            triangles.push_back(glm::vec4(k.c, 1.0f));
            samples.push_back(glm::vec4(k.p, 1.0f));
        }
        gen.fixed = nullptr;
        const auto tri_buffer = penumbra::gl::Buffer::fromVector(triangles);
        const auto fragment_buffer = penumbra::gl::Buffer::fromVector(fragments);
        const auto sample_buffer = penumbra::gl::Buffer::fromVector(samples);
        penumbra::gl::Buffer results(per_batch * 4), results_deferred(per_batch * 4);
        results.fill(0xFFFFFFFFu);
        results_deferred.fill(0xFFFFFFFFu);
        for (const penumbra::gl::Program* prog : {&program, &deferred}) {
        glUseProgram(prog->id());
        glUniform4fv(0, 1, &settings.light.x);
        glUniform1f(1, settings.reach);
        glUniform1d(2, settings.eps);
        glUniform1d(3, settings.offset);
        glUniform1ui(4, per_batch);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, tri_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, fragment_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, sample_buffer.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, prog == &program ? results.id() : results_deferred.id());
        glDispatchCompute((per_batch + 63) / 64, 1, 1);
        }
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        const std::vector<uint32_t> words = results.download<uint32_t>();
        const std::vector<uint32_t> words_deferred = results_deferred.download<uint32_t>();
        for (uint32_t i = 0; i < per_batch; ++i) {
            const Case& k = cases[i];
            const uint32_t w = words[i];
            const bool filtered = (w >> 2) & 1u, fp64 = (w >> 3) & 1u;
            ++total;
            mismatched += w > 15u || filtered != fp64 || words_deferred[i] != uint32_t(fp64);
            uncertain += (w & 3u) == 2u;
            glm::vec3 lf;
            float l_error;
            penumbra::detail::blockerFilterLightPoint(k.p, k.light, k.reach, lf, l_error);
            const BlockerFilterState cpu = penumbra::detail::blockerFilter(k.a, k.b, k.c, k.p, lf, l_error, k.eps, k.offset);
            if ((w & 3u) != uint32_t(cpu) && ++state_mismatched <= 5)
                MESSAGE("GPU filter state ", (w & 3u), " CPU ", int(cpu), " (", std::string(kKindNames[kind]), ")");
            const bool cpu_fp64 = exactTest(glm::dvec3(k.a), glm::dvec3(k.b), glm::dvec3(k.c), glm::dvec3(k.p),
                                            penumbra::detail::blockerLightPoint(glm::dvec3(k.p), glm::dvec3(glm::vec3(k.light)),
                                                                                double(k.reach), k.light.w != 0.0f),
                                            k.eps, k.offset, k.extent);
            cpu_mismatched += cpu_fp64 != fp64;
        }
    }
    MESSAGE("GPU cases ", total, ", filtered (inline or deferred) != fp64: ", mismatched, ", fallback ", 100.0 * double(uncertain) / double(total),
            " %, GPU state != CPU state: ", state_mismatched, ", GPU fp64 != CPU afhBlocks<double>: ", cpu_mismatched);
    CHECK(total >= 100000);
    // Portable: the filter's certified answers equal the fp64 test on the same driver (GLSL's
    // correctly rounded float +, -, * and the `precise` qualifier are what the filter's error bound
    // assumes). Bitwise tier: the GPU's filter states equal the CPU model's, and its fp64 answers
    // the CPU's (the adversarial cases sit within fp64 rounding of ties; GLSL does not promise
    // correctly rounded doubles).
    CHECK(mismatched == 0);
    PENUMBRA_CHECK_BITWISE("blocker filter: GPU filter states == CPU model", state_mismatched == 0);
    PENUMBRA_CHECK_BITWISE("blocker filter: GPU fp64 test == CPU afhBlocks<double> on adversarial cases", cpu_mismatched == 0);
}
