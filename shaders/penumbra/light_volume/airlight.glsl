// penumbra — airlight: single scattering of a point light in a homogeneous medium, cumulative along
// an eye ray (issue 12, billeter2010 light volumes; closed form after sun2005). The GLSL twin of
// include/penumbra/airlight.hpp's airlight<float>, operation for operation in the same order (not
// bit for bit: exp, atan, sin, log and sqrt are the driver's). The derivation, the table and the
// error figures are in that header's opening comment. A snippet: no version line, no bindings,
// no main.
//
// Arguments, from the host's AirlightSetup:
//   medium = shaderMedium() = (sigma_s, sigma_t, hg_g, intensity)
//   params = shaderParams() = (table width W, table height H, min_distance, method: 1 table, 2 quadrature)
//   eye, dir (unit), light: world positions (float: pass them relative to a nearby origin)
//   t: distance along the ray; <= 0 (or NaN) gives 0, clamped to 1e18.
// Functions: penumbraAirlight (by params.w), penumbraAirlightTable (isotropic, the table),
// penumbraAirlightQuadrature (any hg_g, Gauss–Legendre on two panels).
//
// Hooks the integrator defines before including this file (one of the first two):
//   PENUMBRA_AIRLIGHT_TABLE(uv)         -> float: AirlightSetup::table as an R32F W x H texture
//                                         sampled at uv with GL_LINEAR, GL_CLAMP_TO_EDGE
//                                         (e.g. texture(table, uv).r; the hardware's filter
//                                         weights are coarse: ~1e-5 relative)
//   PENUMBRA_AIRLIGHT_TABLE_FETCH(texel) -> float: texel ivec2(i, j) of the table (texelFetch, or an
//                                         SSBO element j * W + i); bilinear filtering is then done
//                                         here exactly as on the CPU (4 fetches)
//   PENUMBRA_AIRLIGHT_QUADRATURE_ONLY    (no value) instead of either: only the quadrature, no table
// Optional: PENUMBRA_AIRLIGHT_NODES = 8, 16 (default) or 32, Gauss–Legendre nodes per panel; must
// equal AirlightOptions::quadrature_nodes for the CPU twin to match.
#ifndef PENUMBRA_AIRLIGHT_GLSL
#define PENUMBRA_AIRLIGHT_GLSL

#if !defined(PENUMBRA_AIRLIGHT_QUADRATURE_ONLY) && !defined(PENUMBRA_AIRLIGHT_TABLE) && \
    !defined(PENUMBRA_AIRLIGHT_TABLE_FETCH)
#error "airlight.glsl: define the hook PENUMBRA_AIRLIGHT_TABLE(uv) (or PENUMBRA_AIRLIGHT_TABLE_FETCH(texel))"
#endif

#ifndef PENUMBRA_AIRLIGHT_NODES
#define PENUMBRA_AIRLIGHT_NODES 16
#endif

const float penumbraAirlightPi = 3.14159265358979323846;
const float penumbraAirlightTwoOverPi = 0.63661977236758134308;
const float penumbraAirlightZScale = 4.0;  // kAirlightZScale
const float penumbraAirlightMaxDistance = 1e18;  // kAirlightMaxDistance

// Gauss–Legendre nodes on [0, 1] and their weights: the literals of airlight.hpp's kNodes*.
#if PENUMBRA_AIRLIGHT_NODES == 8
const float penumbraAirlightNodeX[8] = float[8](
    0.019855071751231884, 0.10166676129318664, 0.2372337950418355, 0.4082826787521751,
    0.591717321247825, 0.7627662049581645, 0.8983332387068134, 0.9801449282487681);
const float penumbraAirlightNodeW[8] = float[8](
    0.05061426814518813, 0.11119051722668724, 0.15685332293894363, 0.181341891689181, 0.181341891689181,
    0.15685332293894363, 0.11119051722668724, 0.05061426814518813);
#elif PENUMBRA_AIRLIGHT_NODES == 16
const float penumbraAirlightNodeX[16] = float[16](
    0.005299532504175033, 0.02771248846338371, 0.06718439880608412, 0.12229779582249849,
    0.19106187779867811, 0.2709916111713863, 0.35919822461037054, 0.4524937450811813,
    0.5475062549188188, 0.6408017753896295, 0.7290083888286137, 0.8089381222013219, 0.8777022041775016,
    0.9328156011939158, 0.9722875115366163, 0.994700467495825);
const float penumbraAirlightNodeW[16] = float[16](
    0.013576229705877048, 0.031126761969323947, 0.04757925584124639, 0.06231448562776694,
    0.07479799440828837, 0.08457825969750127, 0.09130170752246179, 0.09472530522753425,
    0.09472530522753425, 0.09130170752246179, 0.08457825969750127, 0.07479799440828837,
    0.06231448562776694, 0.04757925584124639, 0.031126761969323947, 0.013576229705877048);
#elif PENUMBRA_AIRLIGHT_NODES == 32
const float penumbraAirlightNodeX[32] = float[32](
    0.0013680690752592183, 0.007194244227365833, 0.017618872206246784, 0.03254696203113015,
    0.05183942211697394, 0.07531619313371501, 0.1027581020160288, 0.13390894062985517,
    0.1684778665348924, 0.20614212137961885, 0.2465500455338853, 0.2893243619346823,
    0.33406569885893617, 0.38035631887393145, 0.42776401920860174, 0.4758461671561308,
    0.5241538328438692, 0.5722359807913983, 0.6196436811260685, 0.6659343011410638, 0.7106756380653176,
    0.7534499544661147, 0.7938578786203812, 0.8315221334651076, 0.8660910593701449, 0.8972418979839712,
    0.9246838068662849, 0.9481605778830261, 0.9674530379688698, 0.9823811277937532, 0.9928057557726342,
    0.9986319309247408);
const float penumbraAirlightNodeW[32] = float[32](
    0.003509305004735048, 0.008137197365452835, 0.01269603265463103, 0.017136931456510716,
    0.02141794901111334, 0.025499029631188087, 0.029342046739267772, 0.032911111388180925,
    0.03617289705442425, 0.039096947893535156, 0.041655962113473374, 0.043826046502201906,
    0.045586939347881945, 0.04692219954040228, 0.04781936003963743, 0.0482700442573639,
    0.0482700442573639, 0.04781936003963743, 0.04692219954040228, 0.045586939347881945,
    0.043826046502201906, 0.041655962113473374, 0.039096947893535156, 0.03617289705442425,
    0.032911111388180925, 0.029342046739267772, 0.025499029631188087, 0.02141794901111334,
    0.017136931456510716, 0.01269603265463103, 0.008137197365452835, 0.003509305004735048);
#else
#error "penumbra/light_volume/airlight.glsl: PENUMBRA_AIRLIGHT_NODES must be 8, 16 or 32"
#endif

// The ray relative to the light (detail::airlight::rayToLight): x = h >= min_distance, y = t0,
// z = r(0) = sqrt(h² + t0²).
vec3 penumbraAirlightRay(vec3 eye, vec3 dir, vec3 light, float min_distance) {
    vec3 rel = light - eye;
    float t0 = dot(rel, dir);
    float h = max(length(cross(rel, dir)), min_distance);
    return vec3(h, t0, sqrt(h * h + t0 * t0));
}

// r + s = h tan η without cancellation (detail::airlight::rPlusS).
float penumbraAirlightRPlusS(float r, float s, float h) {
    return s >= 0.0 ? r + s : h * h / (r - s);
}

// 2 p_HG(cos θ), cos θ = sin²ω - cos²ω (detail::airlight::phase2).
float penumbraAirlightPhase2(float g, float cos2, float sin2) {
    float den = g >= 0.0 ? (1.0 - g) * (1.0 - g) + 4.0 * g * cos2 : (1.0 + g) * (1.0 + g) - 4.0 * g * sin2;
    return (1.0 - g * g) / (2.0 * penumbraAirlightPi * den * sqrt(den));
}

#ifndef PENUMBRA_AIRLIGHT_QUADRATURE_ONLY
// Bilinear Q(z, ω) on texel centres (detail::airlight::tableQ).
float penumbraAirlightTableQ(vec2 size, float z, float omega) {
    float fx = sqrt(sqrt(1.0 - penumbraAirlightZScale / (z + penumbraAirlightZScale))) * (size.x - 1.0);
    float fy = omega * penumbraAirlightTwoOverPi * (size.y - 1.0);
    fx = fx > 0.0 ? min(fx, size.x - 1.0) : 0.0;
    fy = fy > 0.0 ? min(fy, size.y - 1.0) : 0.0;
#ifdef PENUMBRA_AIRLIGHT_TABLE_FETCH
    int i = min(int(fx), int(size.x) - 2), j = min(int(fy), int(size.y) - 2);
    float ax = fx - float(i), ay = fy - float(j);
    float q00 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i, j));
    float q10 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i + 1, j));
    float q01 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i, j + 1));
    float q11 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i + 1, j + 1));
    float q0 = q00 + ax * (q10 - q00);
    float q1 = q01 + ax * (q11 - q01);
    return q0 + ay * (q1 - q0);
#else
    return PENUMBRA_AIRLIGHT_TABLE((vec2(fx, fy) + 0.5) / size);
#endif
}

// Ĥ = exp(-sigma_t path) ω Q(z, ω) / (1 + z) (detail::airlight::remaining).
float penumbraAirlightRemaining(vec2 size, float sigma_t, float h, float s, float r, float path) {
    float q = penumbraAirlightRPlusS(r, s, h);
    float omega = atan(h, q);
    float z = sigma_t * sqrt(h * h + q * q);
    float big_q = penumbraAirlightTableQ(size, z, omega);
    return exp(-sigma_t * path) * omega * big_q / (1.0 + z);
}

// A(t) by the table, isotropic (detail::airlight::airlightTable); medium.z (g) is ignored.
float penumbraAirlightTable(vec4 medium, vec4 params, vec3 eye, vec3 dir, vec3 light, float t) {
    if (!(t > 0.0)) return 0.0;
    t = min(t, penumbraAirlightMaxDistance);
    vec3 ray = penumbraAirlightRay(eye, dir, light, params.z);
    float h = ray.x, t0 = ray.y, r0 = ray.z;
    float s1 = t - t0;
    float r1 = sqrt(h * h + s1 * s1);
    float head = penumbraAirlightRemaining(params.xy, medium.y, h, -t0, r0, r0);
    float tail = penumbraAirlightRemaining(params.xy, medium.y, h, s1, r1, r1 + t);
    float a = medium.x * medium.w * (head - tail) / (2.0 * penumbraAirlightPi * h);
    return max(a, 0.0);
}
#endif

// log(1 + x), x >= 0 (detail::airlight::log1pPortable; `precise` keeps u - 1 from folding to x).
float penumbraAirlightLog1p(float x) {
    precise float u = 1.0 + x;
    precise float du = u - 1.0;
    return u == 1.0 ? x : log(u) * (x / du);
}

// 1 - exp(-x), x >= 0 (detail::airlight::oneMinusExp).
float penumbraAirlightOneMinusExp(float x) {
    if (x < 0.1) return x * (1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0)))));
    return 1.0 - exp(-x);
}

// A(t) by Gauss–Legendre on two panels, any hg_g (detail::airlight::airlightQuadrature; the panels'
// variables are explained there).
float penumbraAirlightQuadrature(vec4 medium, vec4 params, vec3 eye, vec3 dir, vec3 light, float t) {
    if (!(t > 0.0)) return 0.0;
    t = min(t, penumbraAirlightMaxDistance);
    vec3 ray = penumbraAirlightRay(eye, dir, light, params.z);
    float sigma_t = medium.y, g = medium.z;
    float h = ray.x, t0 = ray.y, r0 = ray.z;
    float u = sigma_t * h;
    float q0 = penumbraAirlightRPlusS(r0, -t0, h);
    float b0 = sigma_t * q0;
    float omega0 = atan(h, q0), eta0 = atan(q0, h);
    float s1 = t - t0;
    float r1 = sqrt(h * h + s1 * s1);
    float q1 = penumbraAirlightRPlusS(r1, s1, h);
    float dq = t * ((q1 + q0) / (r1 + r0));
    float depth = sigma_t * dq;
    bool two_panels = depth > 1.0;
    float dq_a = two_panels ? 1.0 / sigma_t : dq;
    float q_a = q0 + dq_a;
    float omega_a = atan(h, q_a), eta_a = atan(q_a, h);
    // Panel A: v = log((ω + c_lo) / (η + c_hi)) from v_a over `len`.
    float peak = g != 0.0 ? (1.0 - abs(g)) / (2.0 * sqrt(abs(g))) : 1.0;
    float min_scale = 1e-6;
    float c_lo = max(omega_a, min(u >= min_scale ? min(u, 1.0) : 1.0, g < 0.0 ? min(max(peak, min_scale), 1.0) : 1.0));
    float c_hi = g > 0.0 ? min(max(peak, min_scale), 1.0) : 1.0;
    float width = atan(h * dq_a, h * h + q0 * q_a);
    float len = penumbraAirlightLog1p(width / (omega_a + c_lo)) + penumbraAirlightLog1p(width / (eta0 + c_hi));
    float v_a = log((omega_a + c_lo) / (eta_a + c_hi));
    float sin0 = sin(omega0);
    float sum_a = 0.0;
    for (int k = 0; k < PENUMBRA_AIRLIGHT_NODES; ++k) {
        float v = v_a + len * penumbraAirlightNodeX[k];
        float e = exp(-abs(v));
        float sig_big = 1.0 / (1.0 + e), sig_small = e / (1.0 + e);
        float sig_pos = v >= 0.0 ? sig_big : sig_small, sig_neg = v >= 0.0 ? sig_small : sig_big;
        float omega = omega_a + sig_pos * (eta_a + c_hi) * penumbraAirlightOneMinusExp(len * penumbraAirlightNodeX[k]);
        float d = sig_neg * (omega0 + c_lo) * penumbraAirlightOneMinusExp(len * (1.0 - penumbraAirlightNodeX[k]));
        float eta = eta0 + d;
        float jacobian = (omega + c_lo) * sig_neg;
        float sin_w = sin(omega), cos_w = sin(eta);
        float exponent = u * sin(d) / (sin_w * sin0);
        sum_a += penumbraAirlightNodeW[k] * penumbraAirlightPhase2(g, cos_w * cos_w, sin_w * sin_w) * exp(-exponent) *
                 jacobian;
    }
    float total = len * sum_a;
    // Panel B: o = 1 - 4 log(1 - y), y in [0, y_end].
    if (two_panels) {
        float y_end = penumbraAirlightOneMinusExp((depth - 1.0) * 0.25);
        float sum_b = 0.0;
        for (int k = 0; k < PENUMBRA_AIRLIGHT_NODES; ++k) {
            float y = y_end * penumbraAirlightNodeX[k];
            float rest = 1.0 - y;
            float o = 1.0 - 4.0 * log(rest);
            float c = b0 + o;
            float den = u * u + c * c;
            sum_b += penumbraAirlightNodeW[k] * penumbraAirlightPhase2(g, c * c / den, u * u / den) * (u / den) *
                     (rest * rest * rest);
        }
        total += y_end * (4.0 * 0.36787944117144233) * sum_b;
    }
    return medium.x * medium.w * exp(-sigma_t * r0) * total / h;
}

// A(t) by the setup's method (params.w: 1 table, 2 quadrature).
float penumbraAirlight(vec4 medium, vec4 params, vec3 eye, vec3 dir, vec3 light, float t) {
#ifndef PENUMBRA_AIRLIGHT_QUADRATURE_ONLY
    if (params.w < 1.5) return penumbraAirlightTable(medium, params, eye, dir, light, t);
#endif
    return penumbraAirlightQuadrature(medium, params, eye, dir, light, t);
}

#endif
