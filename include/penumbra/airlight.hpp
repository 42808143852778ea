// penumbra/airlight.hpp — airlight: single scattering of a point light in a homogeneous medium
// (light shafts in fog), as the cumulative integral along an eye ray (issue 12, billeter2010's
// polygonal light volumes; the closed form after sun2005, reformulated so that it neither
// overflows nor cancels).
//
// Integration summary
//   Needs:    GLM and the C++17 standard library; no GL. GLSL twin:
//             shaders/penumbra/light_volume/airlight.glsl (penumbraAirlight, penumbraAirlightTable,
//             penumbraAirlightQuadrature) through the hook PENUMBRA_AIRLIGHT_TABLE(uv) (-> float, the
//             table texture with linear filtering) or PENUMBRA_AIRLIGHT_TABLE_FETCH(texel) (-> float,
//             one texel: the shader then filters exactly like the CPU).
//   Input:    a medium (sigma_s, sigma_t, Henyey–Greenstein g), a point light's radiant intensity I
//             and position, eye rays (origin E, unit direction d) and distances t along them.
//   Produces: airlightSetup() -> AirlightSetup: validated constants, the table Q as
//             std::vector<float> (W x H, row-major: an R32F 2D texture, GL_LINEAR, CLAMP_TO_EDGE) and
//             the two vec4s the GLSL takes (shaderMedium, shaderParams); airlightSetMedium(): a new
//             medium or intensity without rebuilding the table (the table does not depend on them);
//             airlightTable(W, H): the table alone;
//             airlight<T>(): A(t), float = CPU twin of penumbraAirlight, double for the host;
//             airlightReference(): adaptive Gauss–Kronrod quadrature of the exact integral in fp64,
//             the ground truth.
//   Use:      billeter2010: the airlight a pixel sees through the lit volume is the sum over the
//             volume's faces along its ray, + A(t) for every face the ray leaves the volume through
//             (back faces) and - A(t) for every face it enters through (front faces), t clamped to
//             the depth buffer's distance (so the lit stretch [t_in, t_out] gives A(t_out) - A(t_in));
//             A(t <= 0) = 0, so faces behind the eye cost nothing. The per-pixel sum is of terms of
//             size ~A(∞): in float its error is ~1e-7 A(∞) per face, whatever the stretch's length.
//
// The physics. Medium: scattering sigma_s >= 0, extinction sigma_t = sigma_s + absorption >= sigma_s
// (1 / world unit). Light: a point at L of radiant intensity I (inverse-square falloff). Eye ray
// x(t) = E + t d, |d| = 1. Single scattering towards the eye, attenuated on both legs:
//     A(t) = ∫_0^t sigma_s p(cos θ) I / r(t')² exp(-sigma_t (r(t') + t')) dt',   r(t) = |x(t) - L|.
// θ is the angle between the light's direction of travel at x, (x - L) / r, and the direction towards
// the eye, -d: cos θ = dot(x - L, -d) / r. θ = 0 is light continuing straight on to the eye, so
// Henyey–Greenstein's g > 0 (forward scattering) gives the bright halo around a light one looks at:
//     p(cos θ) = (1 - g²) / (4π (1 + g² - 2 g cos θ)^(3/2)),   g = 0: p = 1 / (4π) (isotropic).
// Geometry of the ray relative to the light: t0 = dot(L - E, d) (closest approach along the ray),
// h = |(L - E) x d| (distance of the ray to the light), s = t - t0, r = sqrt(h² + s²), cos θ = -s / r.
//
// Closed form (sun2005 §3, re-derived). Substituting s = h tan ξ gives dt / r² = dξ / h,
// cos θ = -sin ξ and r + s = h tan η with η = π/4 + ξ/2 = θ/2 in (0, π/2) (θ is also the angle at x
// between d and the direction to the light, so θ(0) = γ, the angle between d and L - E):
//     A(t) = (sigma_s I / h) ∫_{η(0)}^{η(t)} 2 p(cos 2η) exp(-sigma_t (t0 + h tan η)) dη.
// Isotropic, with u = sigma_t h (sun2005's A_1 = T_sv sin γ), this is sun2005's
//     A(t) = sigma_s I exp(-sigma_t t0) / (2π h) [F(u, η(t)) - F(u, γ/2)],   F(u, v) = ∫_0^v exp(-u tan η) dη.
// Tabulating F as is fails both ways: exp(-sigma_t t0) overflows when the light is far behind the
// eye while F underflows, and the difference of two near-equal F cancels. Two identities avoid both.
// (1) sigma_t t0 + u tan η(t) = sigma_t (r(t) + t), the optical depth light -> x(t) -> eye, exactly.
// (2) With ω = π/2 - η = atan2(h, r + s) (ω(0) = π/2 - γ/2, ω -> 0 as t -> ∞) and
// z = u / sin ω = sigma_t sqrt(h² + (r + s)²), the rest of the integral is
//     ∫_η^{π/2} exp(-u tan η') dη' = exp(-u tan η) ω Q(z, ω) / (1 + z),
//     Q(z, ω) = (1 + z) ∫_0^1 exp(-z sin(ω (1 - x)) / sin(ω x)) dx
// (substitute π/2 - η' = ω x: u (cot(ω x) - cot ω) = z sin(ω - ω x) / sin(ω x)). Hence
//     A(t) = sigma_s I / (2π h) [Ĥ(0) - Ĥ(t)],   Ĥ(t) = exp(-sigma_t (r(t) + t)) ω(t) Q(z(t), ω(t)) / (1 + z(t)),
// every factor in [0, π/2] (Ĥ(t) is the airlight from t to infinity, scaled). Q is smooth and
// bounded: Q(0, ω) = 1 (so sigma_t -> 0 gives A = sigma_s I (ω(0) - ω(t)) / (2π h), the arctan form,
// exactly in the table), Q(∞, ω) = sin ω / ω, and Q stays within [2/π, 1]. Near z = 0 it behaves
// like 1 + z log z, so the table's z axis is x = (z / (z + k))^(1/4), k = kAirlightZScale = 4 (the
// fourth root flattens z log z to x⁴ log x; 1/z is smooth in x at x = 1; two sqrt on a GPU); its ω
// axis is linear: y = ω / (π/2). (Measured: the z axis dominates the error; sqrt(z) / (sqrt(z) + k)
// is 3x, a log ω axis no better.)
// r + s is computed as h² / (r - s) when s < 0 (no cancellation far before the light) and ω as
// atan2(h, r + s) (accurate near ω = 0, where the ray has passed the light).
//
// The table (AirlightMethod::Table, isotropic only). W x H texels, texel (i, j) at index j W + i
// holds Q(z_i, ω_j) at x = i / (W - 1), y = j / (H - 1) (column W - 1 is z = ∞), computed in fp64 by
// adaptive Gauss–Kronrod and stored as float (128 x 64, the default: 32 KiB, ~0.2 s to build, once:
// it does not depend on the medium). Lookup: bilinear on the texel centres; on a GPU
// uv = ((x (W - 1), y (H - 1)) + 0.5) / (W, H) with GL_LINEAR, where the hardware's 8-bit filter
// weights add up to ~5e-5 relative (adjacent texels differ by <= 0.01); the FETCH hook filters
// exactly like the CPU. Q's bilinear error: <= 3e-5 at 128 x 64 (64 x 64: 1.2e-4, 32 x 32: 5e-4).
// Measured error of A (tests/airlight_test.cpp: 12 000 random rays, lights, distances and media per
// run, sigma_t D from 0 to ~50, lights near, on and behind the ray, t from 1e-2 h to +Inf; default
// seed and 18 fresh ones), against airlightReference, with A(∞) = the whole ray's airlight (the size
// of the terms a renderer adds and subtracts):
//     double: relative error max 1.0e-3, rms 1.2e-4; |error| <= 4e-5 A(∞). (The relative error of
//             a piece that holds a small share of A(∞) is the table's ~3e-5 over that share.)
//     float:  the same where the geometry is well conditioned, and in general
//             |error| <= 3e-3 A(t) + 1e-5 A(∞) + 4ε (|E| + |L|) (a(0) + a(t) + A(∞) / h) + 4ε t a(t)
//             (ε = 2^-24, a = the integrand): L - E, t0 and h are only known to ε (|E| + |L|) in
//             float, which matters for rays passing within ~1e-4 |L - E| of the light (any float
//             implementation; keep positions near the origin). A(t) for t -> 0 is the difference of
//             two values of size ~A(∞), so its float error is ~1e-7 A(∞), not relative to A(t).
//     monotone in t: in double never seen to decrease; in float by rounding, <= 4e-6 A(∞).
//
// Anisotropic phase (AirlightMethod::Quadrature; any g, isotropic too). A 2D table cannot hold the
// extra parameter, so the η integral above is evaluated per ray by Gauss–Legendre on two panels
// whose variables flatten the integrand. With b0 = sigma_t (r(0) - t0) (= u tan η(0)), the optical
// depth gained past the eye's, o = u (tan η - tan η(0)), runs from 0 to S = sigma_t (r(t) + t - r(0))
// (formed as sigma_t t (q(t) + q(0)) / (r(t) + r(0)), q = r + s, without cancellation);
//   panel A, o in [0, min(S, 1)]: v = log((ω + c_lo) / (π/2 - ω + c_hi)). In ω the 1 / r² peak at
//            the light is flat (dt / r² = 2 dω / h); the logit spreads what is left to widths ~1 in
//            v: the exponential's tail exp(-u cot ω) at ω ~ u and the phase peak at ω -> 0 (g < 0),
//            both below c_lo, and the phase peak at ω -> π/2 (g > 0) below c_hi (the peak's width
//            (1 - |g|) / (2 sqrt|g|), u, clamped to [1e-6, 1]). The exponent u sin(ω0 - ω) / (sin ω sin ω0),
//            the panel's length and ω - ω_a, ω0 - ω are all formed without cancellation, so short
//            segments keep their relative accuracy (in float too);
//   panel B, o in [1, S] (when S > 1): o = 1 - 4 log(1 - y): e^-o do = 4 e^-1 (1 - y)³ dy absorbs
//            the exponential, and what is left, u / (u² + (b0 + o)²) and the phase, varies like
//            1 / log²(1 - y) near y = 1, tamed by the (1 - y)³;
// each with n = quadrature_nodes nodes (8, 16 or 32; GLSL: PENUMBRA_AIRLIGHT_NODES): per pixel 2n
// evaluations of a few exp / sin. Measured (same test, double; float adds the conditioning term
// above), relative error:
//     g = 0, 16 nodes: max 1.7e-4, rms 2.5e-6.
//     |g| <= 0.9:         8 nodes max 0.12, rms 5.6e-3; 16 nodes max 3.2e-3, rms 7.8e-5;
//                         32 nodes max 8e-5, rms 2e-6.
//     0.9 < |g| <= 0.99:  8 nodes max 0.14; 16 nodes max 5.1e-3; 32 nodes max 1.5e-4.
//     monotone in t only up to that error (its nodes move with t): decreases <= 2.2e-4 relative
//     seen with 16 nodes.
//
// Degenerate geometry, defined (the reference integrates the same definition):
//   - rays through or very near the light: the ray is treated as passing at distance
//     h_eff = max(h, min_distance) from the light (the light is moved off the ray, perpendicular to
//     it; the integrand 1 / r² is not integrable through r = 0). AirlightOptions::min_distance is in
//     world units (think: the light bulb's radius);
//   - sigma_t = 0 (then sigma_s = 0 too, as sigma_s <= sigma_t): A = 0; the limit sigma_t -> 0 with
//     A / sigma_s fixed is the arctan form above, exact in the table (Q = 1 at z = 0);
//   - t <= 0 or NaN: A = 0 exactly; t > kAirlightMaxDistance (1e18, also +Inf) is that distance
//     (the rest of the ray adds less than h / 1e18 of A). Positions must be finite; in float pass
//     them relative to a nearby origin (e.g. the eye at 0), as |L - E| is formed in the input type.
//
// Bad input (penumbra::Error at setup, naming the value): sigma_s or sigma_t negative or not finite,
// sigma_s > sigma_t, |hg_g| >= 1 or NaN, intensity <= 0 or not finite, table width or height outside
// 2..4096, quadrature_nodes not 8, 16 or 32, min_distance <= 0 or not finite, method Table with
// hg_g != 0. airlight() itself throws nothing and allocates nothing (direction: unit length, not
// checked).
#ifndef PENUMBRA_AIRLIGHT_HPP
#define PENUMBRA_AIRLIGHT_HPP

#include "penumbra/error.hpp"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <queue>
#include <type_traits>
#include <vector>

namespace penumbra {

/// A homogeneous participating medium. Value-initialised = no medium (no airlight).
struct AirlightMedium {
    double sigma_s = 0;  ///< scattering coefficient (1 / world unit): finite, >= 0
    double sigma_t = 0;  ///< extinction coefficient = sigma_s + absorption: finite, >= sigma_s
    double hg_g = 0;     ///< Henyey–Greenstein asymmetry in (-1, 1): 0 isotropic, > 0 forward
};

/// How airlight() evaluates the integral.
enum class AirlightMethod : uint32_t {
    Auto = 0,        ///< Table when hg_g == 0, else Quadrature (resolved by the setup)
    Table = 1,       ///< the isotropic table Q (requires hg_g == 0)
    Quadrature = 2,  ///< per-ray Gauss–Legendre on two panels, any hg_g
};

/// Value-initialised = the defaults.
struct AirlightOptions {
    uint32_t table_width = 128;       ///< W: table columns, along z (x axis); 2..4096
    uint32_t table_height = 64;       ///< H: table rows, along ω (y axis); 2..4096
    AirlightMethod method = AirlightMethod::Auto;
    uint32_t quadrature_nodes = 16;   ///< Gauss–Legendre nodes per panel: 8, 16 or 32
    double min_distance = 1e-3;       ///< world units: rays pass no closer to the light than this
};

/// The z-axis scale of the table: x = (z / (z + kAirlightZScale))^(1/4).
inline constexpr double kAirlightZScale = 4.0;
/// Distances t beyond this are clamped to it (float-safe squares; see the opening comment).
inline constexpr double kAirlightMaxDistance = 1e18;

/// Everything airlight() needs (airlightSetup; airlightSetMedium changes the medium in place).
struct AirlightSetup {
    AirlightMedium medium;
    double intensity = 0;   ///< I, radiant intensity of the light
    AirlightOptions options;
    AirlightMethod method = AirlightMethod::Table;  ///< resolved: Table or Quadrature, never Auto
    /// W * H values of Q, texel (i, j) at index j * W + i (i along z, j along ω): an R32F W x H
    /// texture. Empty when options.method == Quadrature (the table is not needed then).
    std::vector<float> table;

    uint32_t tableWidth() const { return options.table_width; }
    uint32_t tableHeight() const { return options.table_height; }
    /// Bytes of the table (4 per texel).
    size_t tableBytes() const { return table.size() * sizeof(float); }
    /// The GLSL `medium` argument: (sigma_s, sigma_t, hg_g, intensity) as floats.
    glm::vec4 shaderMedium() const {
        return glm::vec4(float(medium.sigma_s), float(medium.sigma_t), float(medium.hg_g), float(intensity));
    }
    /// The GLSL `params` argument: (W, H, min_distance, method: 1 table, 2 quadrature) as floats.
    glm::vec4 shaderParams() const {
        return glm::vec4(float(options.table_width), float(options.table_height), float(options.min_distance),
                         float(uint32_t(method)));
    }
};

namespace detail::airlight {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kHalfPi = 1.57079632679489661923;
inline constexpr double kTwoOverPi = 0.63661977236758134308;

// Gauss–Legendre nodes on [0, 1] (x, then w; sum of w = 1), identical literals in airlight.glsl.
// clang-format off
inline constexpr double kNodes8[2][8] = {
    {0.019855071751231884, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751,
     0.591717321247825, 0.7627662049581645, 0.8983332387068134, 0.9801449282487681},
    {0.05061426814518813, 0.11119051722668724, 0.15685332293894363, 0.181341891689181, 0.181341891689181,
     0.15685332293894363, 0.11119051722668724, 0.05061426814518813}};
inline constexpr double kNodes16[2][16] = {
    {0.005299532504175033, 0.02771248846338371, 0.06718439880608412, 0.12229779582249849,
     0.19106187779867811, 0.2709916111713863, 0.35919822461037054, 0.4524937450811813,
     0.5475062549188188, 0.6408017753896295, 0.7290083888286137, 0.8089381222013219, 0.8777022041775016,
     0.9328156011939158, 0.9722875115366163, 0.994700467495825},
    {0.013576229705877048, 0.031126761969323947, 0.04757925584124639, 0.06231448562776694,
     0.07479799440828837, 0.08457825969750127, 0.09130170752246179, 0.09472530522753425,
     0.09472530522753425, 0.09130170752246179, 0.08457825969750127, 0.07479799440828837,
     0.06231448562776694, 0.04757925584124639, 0.031126761969323947, 0.013576229705877048}};
inline constexpr double kNodes32[2][32] = {
    {0.0013680690752592183, 0.007194244227365833, 0.017618872206246784, 0.03254696203113015,
     0.05183942211697394, 0.07531619313371501, 0.1027581020160288, 0.13390894062985517,
     0.1684778665348924, 0.20614212137961885, 0.2465500455338853, 0.2893243619346823,
     0.33406569885893617, 0.38035631887393145, 0.42776401920860174, 0.4758461671561308,
     0.5241538328438692, 0.5722359807913983, 0.6196436811260685, 0.6659343011410638, 0.7106756380653176,
     0.7534499544661147, 0.7938578786203812, 0.8315221334651076, 0.8660910593701449, 0.8972418979839712,
     0.9246838068662849, 0.9481605778830261, 0.9674530379688698, 0.9823811277937532, 0.9928057557726342,
     0.9986319309247408},
    {0.003509305004735048, 0.008137197365452835, 0.01269603265463103, 0.017136931456510716,
     0.02141794901111334, 0.025499029631188087, 0.029342046739267772, 0.032911111388180925,
     0.03617289705442425, 0.039096947893535156, 0.041655962113473374, 0.043826046502201906,
     0.045586939347881945, 0.04692219954040228, 0.04781936003963743, 0.0482700442573639,
     0.0482700442573639, 0.04781936003963743, 0.04692219954040228, 0.045586939347881945,
     0.043826046502201906, 0.041655962113473374, 0.039096947893535156, 0.03617289705442425,
     0.032911111388180925, 0.029342046739267772, 0.025499029631188087, 0.02141794901111334,
     0.017136931456510716, 0.01269603265463103, 0.008137197365452835, 0.003509305004735048}};
// clang-format on

// Gauss–Kronrod 7/15 on [-1, 1] (QUADPACK qk15): Kronrod abscissae (the odd ones are Gauss's),
// Kronrod weights, Gauss weights of abscissae 1, 3, 5 and 7 (= 0).
inline constexpr double kGkX[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                   0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                   0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                   0.207784955007898467600689403773245, 0.0};
inline constexpr double kGkW[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                   0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                   0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                   0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
inline constexpr double kGW[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                  0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

struct Segment {
    double a, b, value, error;
    bool operator<(const Segment& o) const { return error < o.error; }
};

template <typename F>
Segment gaussKronrod15(const F& f, double a, double b) {
    const double c = 0.5 * (a + b), half = 0.5 * (b - a);
    const double fc = f(c);
    double kronrod = kGkW[7] * fc, gauss = kGW[3] * fc;
    for (int k = 0; k < 7; ++k) {
        const double sum = f(c - half * kGkX[k]) + f(c + half * kGkX[k]);
        kronrod += kGkW[k] * sum;
        if (k % 2 == 1) gauss += kGW[k / 2] * sum;
    }
    return {a, b, kronrod * half, std::abs((kronrod - gauss) * half)};
}

/// Global adaptive Gauss–Kronrod (QUADPACK qag style) of f over the sorted breakpoints: bisects the
/// segment with the largest error until the summed error is <= tolerance * |value| (or segments
/// run out). Returns the value; *error gets the summed estimate.
template <typename F>
double integrateAdaptive(const F& f, const std::vector<double>& breakpoints, double tolerance, double* error,
                         size_t max_segments = 20000) {
    std::priority_queue<Segment> queue;
    double value = 0, err = 0;
    for (size_t k = 0; k + 1 < breakpoints.size(); ++k) {
        if (!(breakpoints[k + 1] > breakpoints[k])) continue;
        const Segment s = gaussKronrod15(f, breakpoints[k], breakpoints[k + 1]);
        value += s.value;
        err += s.error;
        queue.push(s);
    }
    while (!queue.empty() && err > tolerance * std::abs(value) && queue.size() < max_segments) {
        const Segment worst = queue.top();
        const double mid = 0.5 * (worst.a + worst.b);
        if (!(mid > worst.a && mid < worst.b)) break;  // no room left to bisect
        queue.pop();
        const Segment left = gaussKronrod15(f, worst.a, mid), right = gaussKronrod15(f, mid, worst.b);
        value += left.value + right.value - worst.value;
        err += left.error + right.error - worst.error;
        queue.push(left);
        queue.push(right);
    }
    // Re-sum to shed the running sums' rounding.
    value = 0;
    err = 0;
    for (; !queue.empty(); queue.pop()) {
        value += queue.top().value;
        err += queue.top().error;
    }
    if (error) *error = err;
    return value;
}

/// Q(z, ω) = (1 + z) ∫_0^1 exp(-z sin(ω (1 - x)) / sin(ω x)) dx, fp64, relative error ~1e-13.
inline double exactQ(double z, double omega) {
    if (z == 0) return 1.0;
    if (std::isinf(z)) return omega == 0 ? 1.0 : std::sin(omega) / omega;
    auto f = [&](double x) {
        const double ratio = omega == 0 ? (1 - x) / x : std::sin(omega * (1 - x)) / std::sin(omega * x);
        return std::exp(-z * ratio);
    };
    // The integrand rises from 0 to 1 in a layer of width ~1 / z at x = 1: geometric breakpoints.
    std::vector<double> breakpoints = {0.0};
    for (int k = 1; k <= 40; ++k) breakpoints.push_back(1.0 - std::ldexp(1.0, -k));
    breakpoints.push_back(1.0);
    double error = 0;
    return (1 + z) * integrateAdaptive(f, breakpoints, 1e-13, &error);
}

/// The table's x coordinate of z: (z / (z + k))^(1/4), written so that z = Inf gives 1.
template <typename T>
T tableX(T z) {
    const T k = T(kAirlightZScale);
    return std::sqrt(std::sqrt(T(1) - k / (z + k)));
}

/// Bilinear lookup of Q at (z, ω) on texel centres (the CPU twin of penumbraAirlightTableQ).
template <typename T>
T tableQ(const float* table, uint32_t width, uint32_t height, T z, T omega) {
    // Clamped to the table, NaN to 0 (never an out-of-range index).
    T fx = tableX(z) * T(width - 1), fy = omega * T(kTwoOverPi) * T(height - 1);
    fx = fx > T(0) ? std::min(fx, T(width - 1)) : T(0);
    fy = fy > T(0) ? std::min(fy, T(height - 1)) : T(0);
    const uint32_t i = std::min(uint32_t(fx), width - 2), j = std::min(uint32_t(fy), height - 2);
    const T ax = fx - T(i), ay = fy - T(j);
    const float* row0 = table + size_t(j) * width + i;
    const float* row1 = row0 + width;
    const T q0 = T(row0[0]) + ax * (T(row0[1]) - T(row0[0]));
    const T q1 = T(row1[0]) + ax * (T(row1[1]) - T(row1[0]));
    return q0 + ay * (q1 - q0);
}

/// r + s = h tan η without cancellation (h² / (r - s) when s < 0).
template <typename T>
T rPlusS(T r, T s, T h) {
    return s >= T(0) ? r + s : h * h / (r - s);
}

/// The ray relative to the light: h (>= min_distance), t0, r(0) = sqrt(h² + t0²).
template <typename T>
struct RayToLight {
    T h, t0, r0;
};

template <typename T>
RayToLight<T> rayToLight(const glm::vec<3, T>& eye, const glm::vec<3, T>& dir, const glm::vec<3, T>& light,
                         T min_distance) {
    const glm::vec<3, T> rel = light - eye;
    const T t0 = glm::dot(rel, dir);
    const T h = std::max(glm::length(glm::cross(rel, dir)), min_distance);
    return {h, t0, std::sqrt(h * h + t0 * t0)};
}

/// Ĥ = exp(-sigma_t path) ω Q(z, ω) / (1 + z) at the point s = t - t0, r = r(t), path = r + t.
template <typename T>
T remaining(const AirlightSetup& setup, T sigma_t, T h, T s, T r, T path) {
    const T q = rPlusS(r, s, h);
    const T omega = std::atan2(h, q);
    const T z = sigma_t * std::sqrt(h * h + q * q);
    const T big_q = tableQ(setup.table.data(), setup.options.table_width, setup.options.table_height, z, omega);
    return std::exp(-sigma_t * path) * omega * big_q / (T(1) + z);
}

/// 2 p_HG(cos θ) with cos θ = sin²ω - cos²ω, written without cancellation for either sign of g.
template <typename T>
T phase2(T g, T cos2, T sin2) {
    const T den = g >= T(0) ? (T(1) - g) * (T(1) - g) + T(4) * g * cos2 : (T(1) + g) * (T(1) + g) - T(4) * g * sin2;
    return (T(1) - g * g) / (T(2.0 * kPi) * den * std::sqrt(den));
}

inline void nodesFor(uint32_t n, const double*& x, const double*& w) {
    if (n == 8) {
        x = kNodes8[0];
        w = kNodes8[1];
    } else if (n == 32) {
        x = kNodes32[0];
        w = kNodes32[1];
    } else {
        x = kNodes16[0];
        w = kNodes16[1];
    }
}

template <typename T>
T airlightTable(const AirlightSetup& setup, const RayToLight<T>& ray, T t) {
    const T sigma_s = T(setup.medium.sigma_s), sigma_t = T(setup.medium.sigma_t), intensity = T(setup.intensity);
    const T s1 = t - ray.t0;
    const T r1 = std::sqrt(ray.h * ray.h + s1 * s1);
    const T head = remaining(setup, sigma_t, ray.h, -ray.t0, ray.r0, ray.r0);
    const T tail = remaining(setup, sigma_t, ray.h, s1, r1, r1 + t);
    const T a = sigma_s * intensity * (head - tail) / (T(2.0 * kPi) * ray.h);
    return std::max(a, T(0));
}

/// log(1 + x) for x >= 0 without log1p (GLSL has none): Kahan's trick.
template <typename T>
T log1pPortable(T x) {
    const T u = T(1) + x;
    return u == T(1) ? x : std::log(u) * (x / (u - T(1)));
}

/// 1 - exp(-x) for x >= 0 without expm1: a series below 0.1 (relative error < 2e-8).
template <typename T>
T oneMinusExp(T x) {
    if (x < T(0.1)) return x * (T(1) - x * (T(0.5) - x * (T(1.0 / 6) - x * (T(1.0 / 24) - x * T(1.0 / 120)))));
    return T(1) - std::exp(-x);
}

template <typename T>
T airlightQuadrature(const AirlightSetup& setup, const RayToLight<T>& ray, T t) {
    const T sigma_s = T(setup.medium.sigma_s), sigma_t = T(setup.medium.sigma_t), intensity = T(setup.intensity);
    const T g = T(setup.medium.hg_g);
    const T h = ray.h;
    const T u = sigma_t * h;
    const T q0 = rPlusS(ray.r0, -ray.t0, h);
    const T b0 = sigma_t * q0;
    const T omega0 = std::atan2(h, q0), eta0 = std::atan2(q0, h);
    const T s1 = t - ray.t0;
    const T r1 = std::sqrt(h * h + s1 * s1);
    const T q1 = rPlusS(r1, s1, h);
    // q1 - q0 = t (q1 + q0) / (r1 + r0): no cancellation for short segments.
    const T dq = t * ((q1 + q0) / (r1 + ray.r0));
    const T depth = sigma_t * dq;  // S: optical depth gained past the eye's
    const bool two_panels = depth > T(1);
    const T dq_a = two_panels ? T(1) / sigma_t : dq;
    const T q_a = q0 + dq_a;
    const T omega_a = std::atan2(h, q_a), eta_a = std::atan2(q_a, h);
    const double* nx;
    const double* nw;
    nodesFor(setup.options.quadrature_nodes, nx, nw);
    const uint32_t n = setup.options.quadrature_nodes;
    // Panel A: ω from omega_a to omega0 in v = log((ω + c_lo) / (η + c_hi)), η = π/2 - ω: log-like
    // near ω = 0 down to the scale c_lo of the features there (the exponential's tail at ω ~ u, the
    // backward peak of g < 0), near ω = π/2 down to c_hi (the forward peak of g > 0), affine
    // elsewhere. With P = π/2 + c_lo + c_hi: ω + c_lo = P σ(v), η + c_hi = P σ(-v) (σ the logistic),
    // so from the ends, ω - ω_a = σ(v) (η_a + c_hi) (1 - e^-(v - v_a)) and
    // η - η0 = ω0 - ω = σ(-v) (ω0 + c_lo) (1 - e^-(v0 - v)), and the length
    // v0 - v_a = log1p(Δ / (ω_a + c_lo)) + log1p(Δ / (η0 + c_hi)), Δ = ω0 - ω_a = atan2(h Δq, h² + q0 q_a):
    // nothing cancels, also on short segments.
    const T peak = g != T(0) ? (T(1) - std::abs(g)) / (T(2) * std::sqrt(std::abs(g))) : T(1);  // HG peak width in ω
    const T min_scale = T(1e-6);  // a feature narrower than this carries < ~2e-5 of the integral
    const T c_lo = std::max(omega_a, std::min(u >= min_scale ? std::min(u, T(1)) : T(1),
                                              g < T(0) ? std::min(std::max(peak, min_scale), T(1)) : T(1)));
    const T c_hi = g > T(0) ? std::min(std::max(peak, min_scale), T(1)) : T(1);
    const T width = std::atan2(h * dq_a, h * h + q0 * q_a);
    const T length = log1pPortable(width / (omega_a + c_lo)) + log1pPortable(width / (eta0 + c_hi));
    const T v_a = std::log((omega_a + c_lo) / (eta_a + c_hi));
    const T sin0 = std::sin(omega0);
    T sum_a = 0;
    for (uint32_t k = 0; k < n; ++k) {
        const T v = v_a + length * T(nx[k]);
        const T e = std::exp(-std::abs(v));
        const T sig_big = T(1) / (T(1) + e), sig_small = e / (T(1) + e);
        const T sig_pos = v >= T(0) ? sig_big : sig_small, sig_neg = v >= T(0) ? sig_small : sig_big;
        const T omega = omega_a + sig_pos * (eta_a + c_hi) * oneMinusExp(length * T(nx[k]));
        const T d = sig_neg * (omega0 + c_lo) * oneMinusExp(length * (T(1) - T(nx[k])));  // ω0 - ω
        const T eta = eta0 + d;
        const T jacobian = (omega + c_lo) * sig_neg;  // dω/dv = P σ(v) σ(-v)
        const T sin_w = std::sin(omega), cos_w = std::sin(eta);
        const T exponent = u * std::sin(d) / (sin_w * sin0);
        sum_a += T(nw[k]) * phase2(g, cos_w * cos_w, sin_w * sin_w) * std::exp(-exponent) * jacobian;
    }
    T total = length * sum_a;
    // Panel B: o = 1 - 4 log(1 - y), y in [0, y_end]: e^-o do = 4 e^-1 (1 - y)³ dy, and what is left,
    // 2p u / (u² + (b0 + o)²), varies like 1 / log²(1 - y) near y = 1, tamed by the (1 - y)³.
    if (two_panels) {
        const T y_end = oneMinusExp((depth - T(1)) * T(0.25));
        T sum_b = 0;
        for (uint32_t k = 0; k < n; ++k) {
            const T y = y_end * T(nx[k]);
            const T rest = T(1) - y;
            const T o = T(1) - T(4) * std::log(rest);
            const T c = b0 + o;
            const T den = u * u + c * c;
            sum_b += T(nw[k]) * phase2(g, c * c / den, u * u / den) * (u / den) * (rest * rest * rest);
        }
        total += y_end * T(4 * 0.36787944117144233) * sum_b;  // 4 e^-1
    }
    return sigma_s * intensity * std::exp(-sigma_t * ray.r0) * total / h;
}

inline void validate(const AirlightMedium& medium, double intensity) {
    PENUMBRA_CHECK(std::isfinite(medium.sigma_s) && medium.sigma_s >= 0, "airlight: sigma_s = ", medium.sigma_s,
                   " is not a finite scattering coefficient >= 0");
    PENUMBRA_CHECK(std::isfinite(medium.sigma_t) && medium.sigma_t >= 0, "airlight: sigma_t = ", medium.sigma_t,
                   " is not a finite extinction coefficient >= 0");
    PENUMBRA_CHECK(medium.sigma_s <= medium.sigma_t, "airlight: sigma_s = ", medium.sigma_s, " exceeds sigma_t = ",
                   medium.sigma_t, " (extinction = scattering + absorption)");
    PENUMBRA_CHECK(std::abs(medium.hg_g) < 1, "airlight: hg_g = ", medium.hg_g,
                   " is not a Henyey-Greenstein asymmetry in (-1, 1)");
    PENUMBRA_CHECK(std::isfinite(intensity) && intensity > 0, "airlight: intensity = ", intensity,
                   " is not a finite radiant intensity > 0");
}

inline AirlightMethod resolveMethod(AirlightMethod requested, const AirlightMedium& medium) {
    if (requested == AirlightMethod::Auto) return medium.hg_g == 0 ? AirlightMethod::Table : AirlightMethod::Quadrature;
    PENUMBRA_CHECK(requested != AirlightMethod::Table || medium.hg_g == 0, "airlight: hg_g = ", medium.hg_g,
                   " needs AirlightMethod::Quadrature (the table is isotropic only)");
    return requested;
}

}  // namespace detail::airlight

/// Q(z, ω) tabulated on a width x height grid (AirlightSetup::table's layout), in fp64 then float.
/// Does not depend on the medium: compute once per size. Throws penumbra::Error on a size outside
/// 2..4096.
inline std::vector<float> airlightTable(uint32_t width, uint32_t height) {
    PENUMBRA_CHECK(width >= 2 && width <= 4096, "airlight: table width = ", width, " is outside 2..4096");
    PENUMBRA_CHECK(height >= 2 && height <= 4096, "airlight: table height = ", height, " is outside 2..4096");
    std::vector<float> table(size_t(width) * height);
    for (uint32_t j = 0; j < height; ++j) {
        const double omega = detail::airlight::kHalfPi * double(j) / double(height - 1);
        for (uint32_t i = 0; i < width; ++i) {
            // Invert x = (z / (z + k))^(1/4): z = k x⁴ / (1 - x⁴).
            const double x = double(i) / double(width - 1), x4 = (x * x) * (x * x);
            const double z =
                i + 1 == width ? std::numeric_limits<double>::infinity() : kAirlightZScale * x4 / (1.0 - x4);
            table[size_t(j) * width + i] = float(detail::airlight::exactQ(z, omega));
        }
    }
    return table;
}

/// Validates medium, intensity and options and builds the table (unless options.method is
/// Quadrature: Auto keeps it, as a later airlightSetMedium may make the medium isotropic). Throws
/// penumbra::Error naming the bad value (see the opening comment's list).
inline AirlightSetup airlightSetup(const AirlightMedium& medium, double intensity,
                                   const AirlightOptions& options = {}) {
    detail::airlight::validate(medium, intensity);
    PENUMBRA_CHECK(options.table_width >= 2 && options.table_width <= 4096, "airlight: table width = ",
                   options.table_width, " is outside 2..4096");
    PENUMBRA_CHECK(options.table_height >= 2 && options.table_height <= 4096, "airlight: table height = ",
                   options.table_height, " is outside 2..4096");
    PENUMBRA_CHECK(options.quadrature_nodes == 8 || options.quadrature_nodes == 16 || options.quadrature_nodes == 32,
                   "airlight: quadrature_nodes = ", options.quadrature_nodes, " is not 8, 16 or 32");
    PENUMBRA_CHECK(std::isfinite(options.min_distance) && options.min_distance > 0, "airlight: min_distance = ",
                   options.min_distance, " is not a finite distance > 0");
    PENUMBRA_CHECK(uint32_t(options.method) <= 2u, "airlight: method = ", uint32_t(options.method),
                   " is not an AirlightMethod");
    AirlightSetup setup;
    setup.medium = medium;
    setup.intensity = intensity;
    setup.options = options;
    setup.method = detail::airlight::resolveMethod(options.method, medium);
    if (options.method != AirlightMethod::Quadrature)
        setup.table = airlightTable(options.table_width, options.table_height);
    return setup;
}

/// Replaces the medium and intensity of a setup, keeping its table (Q does not depend on them):
/// the cheap per-frame change of fog density. Validates like airlightSetup (throws penumbra::Error
/// naming the value; the setup is unchanged then); allocates nothing.
inline void airlightSetMedium(AirlightSetup& setup, const AirlightMedium& medium, double intensity) {
    detail::airlight::validate(medium, intensity);
    const AirlightMethod method = detail::airlight::resolveMethod(setup.options.method, medium);
    setup.medium = medium;
    setup.intensity = intensity;
    setup.method = method;
}

/// A(t): the airlight gathered along the eye ray from the eye (t = 0) to distance t, by the setup's
/// method, in precision T (float: CPU twin of penumbraAirlight; double: the host's). `dir` unit
/// length; t <= 0 or NaN gives 0, t is clamped to kAirlightMaxDistance. Throws nothing, allocates
/// nothing.
template <typename T>
T airlight(const AirlightSetup& setup, const glm::vec<3, T>& eye, const glm::vec<3, T>& dir,
           const glm::vec<3, T>& light, T t) {
    static_assert(std::is_floating_point_v<T>, "airlight<T>: T is float or double");
    if (!(t > T(0))) return T(0);
    t = std::min(t, T(kAirlightMaxDistance));
    const auto ray = detail::airlight::rayToLight(eye, dir, light, T(setup.options.min_distance));
    if (setup.method == AirlightMethod::Table) return detail::airlight::airlightTable(setup, ray, t);
    return detail::airlight::airlightQuadrature(setup, ray, t);
}

namespace detail::airlight {
/// The integrand of A at distance t (opening comment), with the ray's h_eff.
inline double density(const AirlightSetup& setup, const RayToLight<double>& ray, double t) {
    const double g = setup.medium.hg_g;
    const double s = t - ray.t0;
    const double r2 = ray.h * ray.h + s * s, r = std::sqrt(r2);
    const double cos_theta = -s / r;
    const double base = 1 + g * g - 2 * g * cos_theta;
    const double p = (1 - g * g) / (4 * kPi * base * std::sqrt(base));
    return setup.medium.sigma_s * setup.intensity * p / r2 * std::exp(-setup.medium.sigma_t * (r + t));
}
}  // namespace detail::airlight

/// The airlight integrand at distance t along the ray (dA/dt: the in-scattered radiance per unit
/// length, attenuated on both legs), in fp64 with the same h_eff as airlight() and
/// airlightReference(): what a ray marcher sums (penumbra/reference/light_shafts.hpp).
inline double airlightDensity(const AirlightSetup& setup, const glm::dvec3& eye, const glm::dvec3& dir, const glm::dvec3& light,
                              double t) {
    return detail::airlight::density(setup, detail::airlight::rayToLight(eye, dir, light, setup.options.min_distance), t);
}

/// The ground truth: ∫_{t_begin}^{t_end} of the exact integrand (opening comment, with the same
/// h_eff = max(h, min_distance) and the same clamp of t to [0, kAirlightMaxDistance]) by adaptive
/// Gauss–Kronrod 7/15 in fp64 to the relative `tolerance`, in t itself (no substitution shared with
/// airlight()). Uses the setup's medium, intensity and min_distance only (not its method or table).
/// *error (optional) gets the quadrature's error estimate. Not for per-frame use (allocates).
inline double airlightReference(const AirlightSetup& setup, const glm::dvec3& eye, const glm::dvec3& dir,
                                const glm::dvec3& light, double t_begin, double t_end, double tolerance = 1e-10,
                                double* error = nullptr) {
    if (error) *error = 0;
    const double lo = std::clamp(t_begin, 0.0, kAirlightMaxDistance), hi = std::clamp(t_end, 0.0, kAirlightMaxDistance);
    if (!(hi > lo)) return 0.0;
    const auto ray = detail::airlight::rayToLight(eye, dir, light, setup.options.min_distance);
    const double sigma_t = setup.medium.sigma_t;
    if (setup.medium.sigma_s * setup.intensity == 0) return 0.0;
    auto f = [&](double t) { return detail::airlight::density(setup, ray, t); };
    // Breakpoints at the light's foot t0 and geometrically around it (the 1 / r² peak of width h),
    // and geometrically from the eye (the exponential's scale 1 / sigma_t may be anywhere).
    std::vector<double> breakpoints = {lo, hi};
    auto add = [&](double t) {
        if (t > lo && t < hi) breakpoints.push_back(t);
    };
    add(ray.t0);
    for (double step = ray.h; step < 4 * (hi - lo) + ray.h; step *= 4) {
        add(ray.t0 - step);
        add(ray.t0 + step);
    }
    if (sigma_t > 0)
        for (double step = 1 / sigma_t; step < hi; step *= 4) add(step);
    std::sort(breakpoints.begin(), breakpoints.end());
    return detail::airlight::integrateAdaptive(f, breakpoints, tolerance, error);
}

}  // namespace penumbra

#endif
