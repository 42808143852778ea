// Airlight (penumbra/airlight.hpp; issue 12, billeter2010 light volumes, closed form after sun2005):
// the table and the per-ray quadrature against the adaptive reference over random rays, lights,
// distances and media (thin to thick fog, sigma_t = 0, rays through the light, lights behind the
// eye, t = Inf); Henyey–Greenstein against the reference, g = 0 against the isotropic table;
// A(0) = 0, monotone in t, additive over segments; the no-extinction limit against the arctan form
// computed here; the table against Q computed here; bad input.
//
// Random inputs come from support/test_support.hpp's testSeed(): fixed by default and printed;
// PENUMBRA_SEED=<n> replays a run, PENUMBRA_SEED=random draws fresh ones. Every input is rounded to
// float first, so the float path, the double path and the reference see the same numbers.
#include <penumbra/airlight.hpp>

#include "support/splitmix.hpp"
#include "support/test_support.hpp"

#include <doctest/doctest.h>

#include <glm/geometric.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace {

using glm::dvec3;
using glm::vec3;
using penumbra::AirlightMedium;
using penumbra::AirlightMethod;
using penumbra::AirlightOptions;
using penumbra::AirlightSetup;
using penumbra::test::contains;
using penumbra::test::errorOf;
using Rng = penumbra::test::SplitMix64;

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// Measured bounds (relative to the reference), with margin; the figures are in airlight.hpp.
constexpr double kTableMaxDouble = 2e-3;      // relative
constexpr double kTableRmsDouble = 2e-4;
constexpr double kTableMaxFloat = 3e-3;       // relative, where A(t) >= A(inf) / 100, well conditioned
constexpr double kScaledFloat = 1e-5;         // float: |error| / A(inf) on top (see ErrorStats)
constexpr double kQuadIsoMax = 1e-3;          // 16 nodes, g = 0
constexpr double kQuadHgMax[3] = {2.5e-1, 1e-2, 1e-3};  // 8, 16, 32 nodes, |g| <= 0.9
constexpr double kQuadHgRms[3] = {1e-2, 1e-3, 1e-4};
constexpr double kMonotoneFloat = 1e-5;       // float: decreases up to this times A(inf) (rounding)

double logUniform(Rng& rng, double lo, double hi) { return lo * std::pow(hi / lo, rng.uniform()); }

dvec3 randomUnit(Rng& rng) {
    for (;;) {
        const dvec3 v = rng.point(-1, 1);
        const double l = glm::length(v);
        if (l > 0.1 && l <= 1) return v / l;
    }
}

dvec3 toFloat(const dvec3& v) { return dvec3(vec3(v)); }
double toFloat(double v) { return double(float(v)); }

struct Ray {
    dvec3 eye, dir, light;
    double t = 0;
};

std::string describe(const Ray& r) {
    std::ostringstream out;
    out.precision(9);
    out << "eye (" << r.eye.x << ", " << r.eye.y << ", " << r.eye.z << ") dir (" << r.dir.x << ", " << r.dir.y << ", "
        << r.dir.z << ") light (" << r.light.x << ", " << r.light.y << ", " << r.light.z << ") t " << r.t;
    const double t0 = glm::dot(r.light - r.eye, r.dir), h = glm::length(glm::cross(r.light - r.eye, r.dir));
    out << " [t0 " << t0 << " h " << h << "]";
    return out.str();
}

std::string describe(const AirlightMedium& m, double intensity) {
    std::ostringstream out;
    out.precision(9);
    out << "sigma_s " << m.sigma_s << " sigma_t " << m.sigma_t << " g " << m.hg_g << " I " << intensity;
    return out.str();
}

/// A random eye ray, light and distance (inputs rounded to float): lights anywhere, near the ray,
/// within min_distance of it (the clamped geometry), behind the eye; t short, long, around the
/// light's foot, huge or +Inf.
Ray randomRay(Rng& rng) {
    Ray r;
    r.eye = toFloat(rng.point(-10, 10));
    r.dir = toFloat(randomUnit(rng));
    dvec3 side = glm::cross(r.dir, randomUnit(rng));
    side = glm::length(side) > 1e-3 ? glm::normalize(side) : dvec3(0);
    const uint32_t kind = rng.below(10);
    if (kind < 4) r.light = rng.point(-10, 10);
    else if (kind < 7) r.light = r.eye + r.dir * rng.uniform(-5, 20) + side * logUniform(rng, 2e-3, 3);
    else if (kind < 8) r.light = r.eye + r.dir * rng.uniform(-5, 20) + side * logUniform(rng, 1e-7, 1e-3);
    else r.light = r.eye - r.dir * rng.uniform(0.5, 20) + side * rng.uniform(0, 5);
    r.light = toFloat(r.light);
    const double t0 = glm::dot(r.light - r.eye, r.dir);
    const double h = std::max(glm::length(glm::cross(r.light - r.eye, r.dir)), 1e-3);
    const uint32_t t_kind = rng.below(20);
    if (t_kind < 10) r.t = logUniform(rng, 1e-2, 1e3);
    else if (t_kind < 14) r.t = std::max(t0 + h * rng.uniform(-3, 3), logUniform(rng, 1e-2, 1));
    else if (t_kind < 16) r.t = logUniform(rng, 1e-2, 1) * h;  // short: a fraction of h
    else if (t_kind < 19) r.t = logUniform(rng, 1e4, 1e18);
    else r.t = kInf;
    r.t = toFloat(r.t);
    return r;
}

/// A random medium: 1 in 20 no medium (sigma_t = 0), 1 in 20 nearly none, else thin to thick fog
/// (sigma_t D up to ~50 for the eye-light distances of randomRay).
AirlightMedium randomMedium(Rng& rng, double g = 0) {
    AirlightMedium m;
    const uint32_t kind = rng.below(20);
    if (kind == 0) m.sigma_t = 0;
    else if (kind == 1) m.sigma_t = logUniform(rng, 1e-9, 1e-5);
    else m.sigma_t = logUniform(rng, 1e-3, 1.5);
    m.sigma_s = toFloat(m.sigma_t * rng.uniform(0.05, 1));
    m.sigma_t = std::max(toFloat(m.sigma_t), m.sigma_s);
    m.hg_g = toFloat(g);
    return m;
}

/// The exact integrand a(t) (the opening comment of airlight.hpp), for the conditioning term below.
double integrand(const AirlightSetup& setup, const Ray& r, double t) {
    t = std::min(t, penumbra::kAirlightMaxDistance);
    const double t0 = glm::dot(r.light - r.eye, r.dir);
    const double h = std::max(glm::length(glm::cross(r.light - r.eye, r.dir)), setup.options.min_distance);
    const double s = t - t0, r2 = h * h + s * s, cos_theta = -s / std::sqrt(r2), g = setup.medium.hg_g;
    const double p = (1 - g * g) / (4 * kPi * std::pow(1 + g * g - 2 * g * cos_theta, 1.5));
    return setup.medium.sigma_s * setup.intensity * p / r2 * std::exp(-setup.medium.sigma_t * (std::sqrt(r2) + t));
}

/// What rounding the inputs' geometry in precision eps costs at most (first order, x4): L - E, t0
/// and h are formed from positions of size |E| + |L|, so t0 and h are off by ~eps (|E| + |L|), and
/// A moves by (a(0) + a(t)) per unit of t0 and by up to A(∞) / h per unit of h; s = t - t0 by eps t.
double conditioning(const AirlightSetup& setup, const Ray& r, double t, double scale, double eps) {
    const double size = glm::length(r.eye) + glm::length(r.light);
    const double h = std::max(glm::length(glm::cross(r.light - r.eye, r.dir)), setup.options.min_distance);
    const double t_eff = std::min(t, penumbra::kAirlightMaxDistance);
    const double at_t = integrand(setup, r, t);
    return 4 * eps * (size * (integrand(setup, r, 0) + at_t + scale / h) + t_eff * at_t);
}

/// Errors against the reference `want` for a path whose model is
///     |error| <= rel want + scaled A(∞) + conditioning
/// (A(∞) = `scale`, the ray's whole airlight: the size of what a renderer adds and subtracts; A(t) on
/// a short piece of a ray is the difference of two values of that size). Records the relative
/// error (max, rms), the relative error where the model's other terms are small (want >= A(∞) / 100
/// and conditioning <= 1e-4 want), |error| / A(∞), and every violation of the model.
struct ErrorStats {
    double rel_bound = 0, scaled_bound = 0;
    double max = 0, sum2 = 0, max_scaled = 0, max_clean = 0;
    size_t count = 0, zeros = 0, mismatched_zeros = 0, violations = 0;
    std::string worst, worst_violation;

    ErrorStats(double rel, double scaled) : rel_bound(rel), scaled_bound(scaled) {}

    template <typename Describe>
    void add(double got, double want, double scale, double cond, const Describe& where) {
        auto text = [&] {
            std::ostringstream out;
            out.precision(9);
            out << "got " << got << " want " << want << " A(inf) " << scale << " conditioning " << cond << ": "
                << where();
            return out.str();
        };
        const double err = std::abs(got - want);
        if (!(err <= rel_bound * want + scaled_bound * scale + cond)) {
            if (violations++ == 0) worst_violation = text();
        }
        if (want == 0) {
            ++zeros;
            if (got != 0) ++mismatched_zeros;
            return;
        }
        const double rel = err / want;
        ++count;
        sum2 += rel * rel;
        if (!(rel <= max)) {
            max = rel;
            worst = text();
        }
        max_scaled = std::max(max_scaled, err / scale);
        if (want >= 1e-2 * scale && cond <= 1e-4 * want) max_clean = std::max(max_clean, rel);
    }
    double rms() const { return count ? std::sqrt(sum2 / double(count)) : 0.0; }
    void report(const std::string& name) const {
        MESSAGE(name, ": rel err max ", max, " rms ", rms(), "; where A(t) >= A(inf) / 100 and well conditioned: max ",
                max_clean, "; |err| / A(inf) max ", max_scaled, "; over ", count, " (+ ", zeros, " exact zeros); ",
                violations, " outside |err| <= ", rel_bound, " A(t) + ", scaled_bound,
                " A(inf) + conditioning\n  worst rel: ", worst, "\n  first outside: ", worst_violation);
    }
};

template <typename T>
T evalAirlight(const AirlightSetup& setup, const Ray& r, double t) {
    using V = glm::vec<3, T>;
    return penumbra::airlight<T>(setup, V(r.eye), V(r.dir), V(r.light), T(t));
}

}  // namespace

TEST_CASE("cpu: airlight table (double and float) and quadrature against the adaptive reference") {
    const auto start = std::chrono::steady_clock::now();
    Rng rng(penumbra::test::testSeed());
    AirlightSetup table = penumbra::airlightSetup(AirlightMedium{1, 1, 0}, 1.0);
    AirlightOptions quad_options;
    quad_options.method = AirlightMethod::Quadrature;
    AirlightSetup quad = penumbra::airlightSetup(AirlightMedium{1, 1, 0}, 1.0, quad_options);
    REQUIRE(table.method == AirlightMethod::Table);
    REQUIRE(quad.method == AirlightMethod::Quadrature);
    ErrorStats table_double(kTableMaxDouble, 0), table_float(kTableMaxFloat, kScaledFloat);
    ErrorStats quad_double(kQuadIsoMax, 0), quad_float(kQuadIsoMax, kScaledFloat);
    size_t unconverged = 0;
    constexpr int kConfigs = 12000;
    for (int c = 0; c < kConfigs; ++c) {
        const Ray r = randomRay(rng);
        const AirlightMedium medium = randomMedium(rng);
        const double intensity = toFloat(logUniform(rng, 1e-2, 1e3));
        penumbra::airlightSetMedium(table, medium, intensity);
        penumbra::airlightSetMedium(quad, medium, intensity);
        double error = 0;
        const double want = penumbra::airlightReference(table, r.eye, r.dir, r.light, 0.0, r.t, 1e-10, &error);
        if (error > 1e-8 * want) ++unconverged;
        const double scale = penumbra::airlightReference(table, r.eye, r.dir, r.light, 0.0, kInf);
        const double cond_double = conditioning(table, r, r.t, scale, 0x1p-53);
        const double cond_float = conditioning(table, r, r.t, scale, 0x1p-24);
        auto where = [&] { return describe(r) + " " + describe(medium, intensity); };
        table_double.add(evalAirlight<double>(table, r, r.t), want, scale, cond_double, where);
        table_float.add(evalAirlight<float>(table, r, r.t), want, scale, cond_float, where);
        quad_double.add(evalAirlight<double>(quad, r, r.t), want, scale, cond_double, where);
        quad_float.add(evalAirlight<float>(quad, r, r.t), want, scale, cond_float, where);
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    MESSAGE(kConfigs, " configurations in ", seconds, " s; table ", table.tableWidth(), " x ", table.tableHeight(),
            "; reference unconverged (error estimate > 1e-8 relative): ", unconverged);
    table_double.report("table, double");
    table_float.report("table, float");
    quad_double.report("quadrature (16 nodes, g = 0), double");
    quad_float.report("quadrature (16 nodes, g = 0), float");
    CHECK(unconverged == 0);
    CHECK(table_double.count > size_t(kConfigs) * 8 / 10);
    for (const ErrorStats* e : {&table_double, &table_float, &quad_double, &quad_float}) {
        CHECK(e->mismatched_zeros == 0);
        CHECK(e->violations == 0);
    }
    CHECK(table_double.max <= kTableMaxDouble);
    CHECK(table_double.rms() <= kTableRmsDouble);
    CHECK(table_float.max_clean <= kTableMaxFloat);
    CHECK(quad_double.max <= kQuadIsoMax);
    CHECK(quad_float.max_clean <= kQuadIsoMax);
}

TEST_CASE("cpu: airlight Henyey-Greenstein quadrature against the reference; g = 0 is isotropic") {
    Rng rng(penumbra::test::testSeed(1));
    const uint32_t node_counts[3] = {8, 16, 32};
    std::vector<AirlightSetup> setups;
    for (uint32_t n : node_counts) {
        AirlightOptions options;
        options.method = AirlightMethod::Quadrature;
        options.quadrature_nodes = n;
        setups.push_back(penumbra::airlightSetup(AirlightMedium{0.1, 0.2, 0.5}, 1.0, options));
        CHECK(setups.back().table.empty());
    }
    ErrorStats stats[3] = {{kQuadHgMax[0], 0}, {kQuadHgMax[1], 0}, {kQuadHgMax[2], 0}};
    ErrorStats strong[3] = {{1, 0}, {1, 0}, {1, 0}}, stats_float16(kQuadHgMax[1], kScaledFloat);
    constexpr int kConfigs = 4000;
    for (int c = 0; c < kConfigs; ++c) {
        const Ray r = randomRay(rng);
        // |g| <= 0.9 asserted; 0.9 < |g| <= 0.99 only reported.
        const bool extreme = c % 8 == 0;
        const double g = extreme ? (rng.below(2) ? 1 : -1) * rng.uniform(0.9, 0.99) : rng.uniform(-0.9, 0.9);
        const AirlightMedium medium = randomMedium(rng, g);
        const double intensity = toFloat(logUniform(rng, 1e-2, 1e3));
        for (auto& s : setups) penumbra::airlightSetMedium(s, medium, intensity);
        const double want = penumbra::airlightReference(setups[0], r.eye, r.dir, r.light, 0.0, r.t);
        const double scale = penumbra::airlightReference(setups[0], r.eye, r.dir, r.light, 0.0, kInf);
        auto where = [&] { return describe(r) + " " + describe(medium, intensity); };
        const double cond_double = conditioning(setups[0], r, r.t, scale, 0x1p-53);
        for (int k = 0; k < 3; ++k)
            (extreme ? strong[k] : stats[k])
                .add(evalAirlight<double>(setups[k], r, r.t), want, scale, cond_double, where);
        if (!extreme)
            stats_float16.add(evalAirlight<float>(setups[1], r, r.t), want, scale,
                              conditioning(setups[1], r, r.t, scale, 0x1p-24), where);
    }
    for (int k = 0; k < 3; ++k) {
        stats[k].report("HG quadrature, " + std::to_string(node_counts[k]) + " nodes per panel, |g| <= 0.9");
        strong[k].report("HG quadrature, " + std::to_string(node_counts[k]) +
                         " nodes per panel, 0.9 < |g| <= 0.99 (reported only)");
        CHECK(stats[k].max <= kQuadHgMax[k]);
        CHECK(stats[k].rms() <= kQuadHgRms[k]);
        CHECK(stats[k].mismatched_zeros == 0);
    }
    stats_float16.report("HG quadrature, 16 nodes per panel, |g| <= 0.9, float");
    CHECK(stats_float16.violations == 0);
    CHECK(stats_float16.max_clean <= kQuadHgMax[1]);

    // g = 0: Auto picks the table; the HG phase is exactly 1 / (4π), so the quadrature with g = 0 and
    // the reference with g = 0 are the isotropic ones; the table agrees within both their errors.
    AirlightSetup iso = penumbra::airlightSetup(AirlightMedium{0.3, 0.5, 0.0}, 2.0);
    CHECK(iso.method == AirlightMethod::Table);
    CHECK(penumbra::detail::airlight::phase2(0.0, 0.3, 0.7) == 1.0 / (2.0 * kPi));
    CHECK(penumbra::detail::airlight::phase2(0.0f, 0.3f, 0.7f) == float(1.0 / (2.0 * kPi)));
    AirlightSetup iso_quad = setups[2];
    penumbra::airlightSetMedium(iso_quad, AirlightMedium{0.3, 0.5, 0.0}, 2.0);
    CHECK(iso_quad.method == AirlightMethod::Quadrature);
    double worst = 0;
    for (int c = 0; c < 500; ++c) {
        const Ray r = randomRay(rng);
        const double a = evalAirlight<double>(iso, r, r.t), b = evalAirlight<double>(iso_quad, r, r.t);
        if (a > 0) worst = std::max(worst, std::abs(a - b) / a);
    }
    MESSAGE("g = 0: table vs 32-node quadrature, max rel difference ", worst);
    CHECK(worst <= kTableMaxDouble + kQuadHgMax[2]);

    // The phase is normalised: ∫ p dΩ = 2π ∫_0^π p(cos θ) sin θ dθ = 1 (2 p = phase2,
    // cos θ = sin²ω - cos²ω, θ = π - 2ω), here by the composite midpoint rule in θ.
    for (double g : {-0.9, -0.3, 0.0, 0.5, 0.9}) {
        CAPTURE(g);
        double sum = 0;
        const int steps = 200000;
        for (int k = 0; k < steps; ++k) {
            const double theta = kPi * (k + 0.5) / steps, omega = 0.5 * (kPi - theta);
            const double c = std::cos(omega), s = std::sin(omega);
            sum += 0.5 * penumbra::detail::airlight::phase2(g, c * c, s * s) * std::sin(theta);
        }
        CHECK(std::abs(2 * kPi * sum * kPi / steps - 1) < 1e-6);
    }
}

TEST_CASE("cpu: airlight A(0) = 0, A(t <= 0) = 0, monotone non-decreasing in t, t = Inf") {
    Rng rng(penumbra::test::testSeed(2));
    AirlightSetup table = penumbra::airlightSetup(AirlightMedium{1, 1, 0}, 1.0);
    AirlightOptions options;
    options.method = AirlightMethod::Quadrature;
    AirlightSetup quad = penumbra::airlightSetup(AirlightMedium{1, 1, 0.5}, 1.0, options);
    std::vector<double> ts = {0.0};
    for (double t = 1e-4; t < 1e5; t *= 1.04) ts.push_back(toFloat(t));
    ts.push_back(1e18);
    ts.push_back(1e30);
    ts.push_back(kInf);
    // Decreases between successive t (4 % apart), per path: count and largest, relative to A(t)
    // (double) or to A(∞) (float).
    size_t decreasing[4] = {}, evaluations = 0;
    double largest[4] = {};
    std::string worst[4];
    for (int c = 0; c < 300; ++c) {
        const Ray r = randomRay(rng);
        const AirlightMedium medium = randomMedium(rng);
        const AirlightMedium anisotropic{medium.sigma_s, medium.sigma_t, toFloat(rng.uniform(-0.9, 0.9))};
        penumbra::airlightSetMedium(table, medium, 10.0);
        penumbra::airlightSetMedium(quad, anisotropic, 10.0);
        for (const AirlightSetup* s : {&table, &quad}) {
            CHECK(evalAirlight<double>(*s, r, 0.0) == 0.0);
            CHECK(evalAirlight<float>(*s, r, 0.0) == 0.0f);
            CHECK(evalAirlight<double>(*s, r, -1.0) == 0.0);
            CHECK(evalAirlight<float>(*s, r, -kInf) == 0.0f);
            CHECK(evalAirlight<double>(*s, r, kNaN) == 0.0);
            const double at_inf = evalAirlight<double>(*s, r, kInf);
            CHECK(std::isfinite(at_inf));
            CHECK(at_inf == evalAirlight<double>(*s, r, 1e18));
            CHECK(at_inf == evalAirlight<double>(*s, r, 1e300));
            CHECK(std::isfinite(evalAirlight<float>(*s, r, kInf)));
        }
        double last[4] = {0, 0, 0, 0}, final_value[4];
        for (int k = 0; k < 4; ++k) final_value[k] = k % 2 ? evalAirlight<float>(k < 2 ? table : quad, r, kInf)
                                                           : evalAirlight<double>(k < 2 ? table : quad, r, kInf);
        for (double t : ts) {
            const double now[4] = {evalAirlight<double>(table, r, t), double(evalAirlight<float>(table, r, t)),
                                   evalAirlight<double>(quad, r, t), double(evalAirlight<float>(quad, r, t))};
            for (int k = 0; k < 4; ++k) {
                if (now[k] < last[k]) {
                    ++decreasing[k];
                    // float: against the ray's A(∞) (rounding noise of the terms A(t) is the difference of)
                    const double drop = (last[k] - now[k]) / (k % 2 ? final_value[k] : last[k]);
                    if (drop > largest[k]) {
                        largest[k] = drop;
                        std::ostringstream out;
                        out.precision(9);
                        out << "t " << t << ": " << now[k] << " < " << last[k] << " " << describe(r) << " "
                            << describe(k < 2 ? medium : anisotropic, 10.0);
                        worst[k] = out.str();
                    }
                }
                last[k] = now[k];
            }
            ++evaluations;
        }
    }
    const char* names[4] = {"table double", "table float", "quadrature double", "quadrature float"};
    for (int k = 0; k < 4; ++k)
        MESSAGE("monotone, ", std::string(names[k]), ": ", decreasing[k], " decreases in ", evaluations,
                " steps, largest ", largest[k], " relative; ", worst[k]);
    // The table in double never decreased (the float paths by rounding only, the quadrature by its
    // error, which varies with t).
    CHECK(decreasing[0] == 0);
    CHECK(largest[1] <= kMonotoneFloat);
    CHECK(largest[2] <= kQuadHgMax[1]);
    CHECK(largest[3] <= kQuadHgMax[1]);
}

TEST_CASE("cpu: airlight is additive: A(t2) - A(t1) = reference over [t1, t2]") {
    Rng rng(penumbra::test::testSeed(3));
    AirlightSetup table = penumbra::airlightSetup(AirlightMedium{1, 1, 0}, 1.0);
    AirlightOptions options;
    options.method = AirlightMethod::Quadrature;
    options.quadrature_nodes = 32;
    AirlightSetup quad = penumbra::airlightSetup(AirlightMedium{1, 1, 0}, 1.0, options);
    double ref_worst = 0, table_worst = 0, quad_worst = 0;
    for (int c = 0; c < 1000; ++c) {
        const Ray r = randomRay(rng);
        const double g = toFloat(rng.uniform(-0.8, 0.8));
        const AirlightMedium medium = randomMedium(rng);
        penumbra::airlightSetMedium(table, medium, 5.0);
        penumbra::airlightSetMedium(quad, AirlightMedium{medium.sigma_s, medium.sigma_t, g}, 5.0);
        const double t1 = toFloat(r.t * rng.uniform(0.0, 1.0)), t2 = r.t;
        for (const AirlightSetup* s : {&table, &quad}) {
            const double whole = penumbra::airlightReference(*s, r.eye, r.dir, r.light, 0.0, t2);
            const double head = penumbra::airlightReference(*s, r.eye, r.dir, r.light, 0.0, t1);
            const double rest = penumbra::airlightReference(*s, r.eye, r.dir, r.light, t1, t2);
            if (whole == 0) continue;
            ref_worst = std::max(ref_worst, std::abs(head + rest - whole) / whole);
            // Against A(t2), the scale of what a renderer sums (a short segment's own relative error
            // grows like 1 / its length).
            const double diff = evalAirlight<double>(*s, r, t2) - evalAirlight<double>(*s, r, t1);
            (s == &table ? table_worst : quad_worst) =
                std::max(s == &table ? table_worst : quad_worst, std::abs(diff - rest) / whole);
        }
    }
    MESSAGE("additivity: reference [0,t1] + [t1,t2] vs [0,t2] max rel ", ref_worst, "; table A(t2) - A(t1) vs [t1,t2] ",
            table_worst, "; 32-node quadrature (|g| <= 0.8) ", quad_worst, " (relative to A(t2))");
    CHECK(ref_worst <= 1e-9);
    CHECK(table_worst <= 2 * kTableMaxDouble);
    CHECK(quad_worst <= 2 * kQuadHgMax[2]);
}

TEST_CASE("cpu: airlight without extinction is the arctan form; sigma_t = 0 gives 0") {
    // sigma_t -> 0 with A / sigma_s fixed: A = sigma_s I / (4π) ∫_0^t dt' / (h² + (t' - t0)²)
    //   = sigma_s I / (4π h) (atan((t - t0) / h) + atan(t0 / h)), computed here from the geometry.
    Rng rng(penumbra::test::testSeed(4));
    const double tiny = 1e-12;
    AirlightSetup table = penumbra::airlightSetup(AirlightMedium{tiny, tiny, 0}, 3.0);
    AirlightOptions options;
    options.method = AirlightMethod::Quadrature;
    AirlightSetup quad = penumbra::airlightSetup(AirlightMedium{tiny, tiny, 0}, 3.0, options);
    double worst_table = 0, worst_quad = 0, worst_ref = 0;
    for (int c = 0; c < 2000; ++c) {
        const Ray r = randomRay(rng);
        // t <= 1e4: the extinction sigma_t (r + t) stays below 1e-7; t >= 1e-2: no segment so short
        // that A is below ~1e-8 of the terms it is the difference of (cancellation in double).
        const double t = std::clamp(r.t, 1e-2, 1e4);
        const double t0 = glm::dot(r.light - r.eye, r.dir);
        const double h = std::max(glm::length(glm::cross(r.light - r.eye, r.dir)), table.options.min_distance);
        // atan((t - t0) / h) - atan(-t0 / h), as one atan2 (no cancellation).
        const double want = tiny * 3.0 / (4 * kPi * h) * std::atan2(t * h, h * h - (t - t0) * t0);
        worst_table = std::max(worst_table, std::abs(evalAirlight<double>(table, r, t) - want) / want);
        worst_quad = std::max(worst_quad, std::abs(evalAirlight<double>(quad, r, t) - want) / want);
        const double ref = penumbra::airlightReference(table, r.eye, r.dir, r.light, 0, t);
        worst_ref = std::max(worst_ref, std::abs(ref - want) / want);
    }
    MESSAGE("no extinction (sigma_s = sigma_t = 1e-12) vs arctan form: table ", worst_table, ", quadrature ", worst_quad,
            ", reference ", worst_ref);
    CHECK(worst_table <= 1e-6);
    CHECK(worst_quad <= 1e-6);
    CHECK(worst_ref <= 1e-8);
    // No medium at all: exactly 0 on every path.
    penumbra::airlightSetMedium(table, AirlightMedium{}, 3.0);
    penumbra::airlightSetMedium(quad, AirlightMedium{}, 3.0);
    const Ray r = randomRay(rng);
    CHECK(evalAirlight<double>(table, r, 5.0) == 0.0);
    CHECK(evalAirlight<float>(table, r, 5.0) == 0.0f);
    CHECK(evalAirlight<double>(quad, r, 5.0) == 0.0);
    CHECK(penumbra::airlightReference(table, r.eye, r.dir, r.light, 0, 5.0) == 0.0);
}

TEST_CASE("cpu: airlight degenerate geometry: through the light, light at the eye, behind the eye") {
    AirlightSetup table = penumbra::airlightSetup(AirlightMedium{0.2, 0.4, 0}, 1.0);
    AirlightOptions options;
    options.method = AirlightMethod::Quadrature;
    AirlightSetup quad = penumbra::airlightSetup(AirlightMedium{0.2, 0.4, 0.7}, 1.0, options);
    const dvec3 dir = glm::normalize(dvec3(1, 2, 2));
    const dvec3 eye(0.5, -1, 2);
    struct Case {
        const char* name;
        dvec3 light;
    };
    const Case cases[] = {{"light on the ray ahead", eye + 3.0 * dir},
                          {"light at the eye", eye},
                          {"light on the ray behind the eye", eye - 4.0 * dir},
                          {"light 1e-9 off the ray", eye + 2.0 * dir + dvec3(0, 1e-9, 0)}};
    for (const Case& c : cases) {
        CAPTURE(c.name);
        for (double t : {1e-3, 1.0, 2.999, 3.0, 3.001, 10.0, kInf}) {
            CAPTURE(t);
            for (const AirlightSetup* s : {&table, &quad}) {
                const Ray r{eye, dir, c.light, t};
                const double want = penumbra::airlightReference(*s, eye, dir, c.light, 0, t);
                const double scale = penumbra::airlightReference(*s, eye, dir, c.light, 0, kInf);
                const double got = evalAirlight<double>(*s, r, t);
                const float got_f = evalAirlight<float>(*s, r, t);
                REQUIRE(std::isfinite(want));
                CHECK(want > 0);
                CHECK(std::abs(got - want) <= (s == &table ? kTableMaxDouble : kQuadHgMax[1]) * want);
                CHECK(std::isfinite(got_f));
                CHECK(std::abs(double(got_f) - want) <=
                      (s == &table ? kTableMaxFloat : kQuadHgMax[1]) * want + kScaledFloat * scale);
            }
        }
    }
}

TEST_CASE("cpu: airlight table holds Q(z, ω); bilinear error against Q computed here") {
    const AirlightSetup setup = penumbra::airlightSetup(AirlightMedium{0.1, 0.1, 0}, 1.0);
    const uint32_t w = setup.tableWidth(), h = setup.tableHeight();
    REQUIRE(setup.table.size() == size_t(w) * h);
    CHECK(setup.tableBytes() == size_t(w) * h * 4);
    // Q computed independently: the composite midpoint rule of (1 + z) ∫_0^1 exp(-z sin(ω(1-x)) / sin(ωx)) dx
    // in the variable x = 1 - v², which resolves the layer at x = 1.
    // x in [0, 1/2] as x = e^w (the layer of width ~z at x = 0 when z is small), x in [1/2, 1] as
    // x = 1 - v² (the layer of width ~1/z at x = 1 when z is large).
    auto q_here = [](double z, double omega) {
        auto f = [&](double x) {
            const double ratio = omega == 0 ? (1 - x) / x : std::sin(omega * (1 - x)) / std::sin(omega * x);
            return std::exp(-z * ratio);
        };
        const int steps = 20000;
        const double w_lo = std::log(1e-14), w_hi = std::log(0.5), v_hi = std::sqrt(0.5);
        double low = 0, high = 0;
        for (int k = 0; k < steps; ++k) {
            const double w = w_lo + (w_hi - w_lo) * (k + 0.5) / steps, x = std::exp(w);
            low += f(x) * x;
            const double v = v_hi * (k + 0.5) / steps;
            high += f(1 - v * v) * 2 * v;
        }
        return (1 + z) * (low * (w_hi - w_lo) + high * v_hi) / steps;
    };
    double min_q = 2, max_q = 0;
    for (float q : setup.table) {
        min_q = std::min(min_q, double(q));
        max_q = std::max(max_q, double(q));
    }
    MESSAGE("table ", w, " x ", h, ": Q in [", min_q, ", ", max_q, "]");
    CHECK(min_q >= 2 / kPi - 1e-7);
    CHECK(max_q <= 1 + 1e-7);
    for (uint32_t j = 0; j < h; ++j) {
        const double omega = 0.5 * kPi * j / (h - 1);
        CHECK(setup.table[size_t(j) * w] == 1.0f);  // z = 0
        CHECK(std::abs(setup.table[size_t(j) * w + w - 1] - (j == 0 ? 1.0 : std::sin(omega) / omega)) < 1e-7);  // z = ∞
    }
    Rng rng(penumbra::test::testSeed(5));
    double worst_texel = 0, worst_lookup = 0;
    for (int c = 0; c < 300; ++c) {
        const uint32_t i = rng.below(w - 1), j = rng.below(h);
        const double x = double(i) / (w - 1), z_i = penumbra::kAirlightZScale * std::pow(x, 4) / (1 - std::pow(x, 4));
        const double omega = 0.5 * kPi * j / (h - 1);
        worst_texel = std::max(worst_texel, std::abs(setup.table[size_t(j) * w + i] - q_here(z_i, omega)));
        const double z = std::pow(10.0, rng.uniform(-8, 4)), om = rng.uniform(0, 0.5 * kPi);
        const double got = penumbra::detail::airlight::tableQ(setup.table.data(), w, h, z, om);
        worst_lookup = std::max(worst_lookup, std::abs(got - q_here(z, om)));
    }
    MESSAGE("table texels vs Q computed here: max abs err ", worst_texel, "; bilinear lookups: max abs err ",
            worst_lookup);
    CHECK(worst_texel <= 1e-6);
    CHECK(worst_lookup <= kTableMaxDouble);
}

TEST_CASE("cpu: airlight bad input names the value") {
    auto setup = [](AirlightMedium m, double intensity = 1.0, AirlightOptions o = {}) {
        return errorOf([&] { penumbra::airlightSetup(m, intensity, o); });
    };
    auto with = [](auto change) {
        AirlightOptions o;
        change(o);
        return o;
    };
    const AirlightMedium ok{0.5, 1, 0};
    CHECK(contains(setup({-1, 1, 0}), "sigma_s = -1"));
    CHECK(contains(setup({kNaN, 1, 0}), "sigma_s = nan"));
    CHECK(contains(setup({kInf, kInf, 0}), "sigma_s = inf"));
    CHECK(contains(setup({0, -0.5, 0}), "sigma_t = -0.5"));
    CHECK(contains(setup({0, kNaN, 0}), "sigma_t = nan"));
    CHECK(contains(setup({0, kInf, 0}), "sigma_t = inf"));
    CHECK(contains(setup({2, 1, 0}), "sigma_s = 2 exceeds sigma_t = 1"));
    CHECK(contains(setup({0.5, 1, 1}), "hg_g = 1"));
    CHECK(contains(setup({0.5, 1, -1.5}), "hg_g = -1.5"));
    CHECK(contains(setup({0.5, 1, kNaN}), "hg_g = nan"));
    CHECK(contains(setup({0.5, 1, 0}, 0.0), "intensity = 0"));
    CHECK(contains(setup({0.5, 1, 0}, -3.0), "intensity = -3"));
    CHECK(contains(setup({0.5, 1, 0}, kInf), "intensity = inf"));
    CHECK(contains(setup({0.5, 1, 0}, kNaN), "intensity = nan"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.table_width = 1; })), "table width = 1"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.table_width = 5000; })), "table width = 5000"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.table_height = 0; })), "table height = 0"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.quadrature_nodes = 12; })),
                   "quadrature_nodes = 12"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.min_distance = 0; })), "min_distance = 0"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.min_distance = -2; })), "min_distance = -2"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.min_distance = kNaN; })), "min_distance = nan"));
    CHECK(contains(setup(ok, 1.0, with([](AirlightOptions& o) { o.method = AirlightMethod(7); })), "method = 7"));
    CHECK(contains(setup({0.5, 1, 0.3}, 1.0, with([](AirlightOptions& o) { o.method = AirlightMethod::Table; })),
                   "hg_g = 0.3 needs AirlightMethod::Quadrature"));
    CHECK(contains(errorOf([] { penumbra::airlightTable(3, 1); }), "table height = 1"));
    // airlightSetMedium validates the same way and leaves the setup unchanged on error.
    AirlightSetup s = penumbra::airlightSetup(AirlightMedium{0.1, 0.2, 0}, 1.0);
    CHECK(contains(errorOf([&] { penumbra::airlightSetMedium(s, AirlightMedium{0.3, 0.2, 0}, 1.0); }),
                   "sigma_s = 0.3 exceeds sigma_t = 0.2"));
    CHECK(contains(errorOf([&] { penumbra::airlightSetMedium(s, AirlightMedium{0.1, 0.2, 0}, -1.0); }),
                   "intensity = -1"));
    CHECK(s.medium.sigma_s == 0.1);
    CHECK(s.intensity == 1.0);
    CHECK(contains(errorOf([] { penumbra::airlightSetup(AirlightMedium{0.1, 0.2, 0}, 1.0); }),
                   "no penumbra::Error thrown"));
}

TEST_CASE("cpu: airlight shader constants pack the setup") {
    AirlightOptions options;
    options.table_width = 32;
    options.table_height = 48;
    options.min_distance = 0.25;
    const AirlightSetup s = penumbra::airlightSetup(AirlightMedium{0.1, 0.3, 0}, 7.0, options);
    CHECK(s.shaderMedium() == glm::vec4(0.1f, 0.3f, 0.0f, 7.0f));
    CHECK(s.shaderParams() == glm::vec4(32.0f, 48.0f, 0.25f, 1.0f));
    options.method = AirlightMethod::Quadrature;
    CHECK(penumbra::airlightSetup(AirlightMedium{0.1, 0.3, -0.4}, 7.0, options).shaderParams().w == 2.0f);
}
