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
#error "penumbra/light_volume/airlight.glsl: define the hook PENUMBRA_AIRLIGHT_TABLE(uv) (-> float, the table with linear filtering), or PENUMBRA_AIRLIGHT_TABLE_FETCH(texel) (-> float, one texel), or PENUMBRA_AIRLIGHT_QUADRATURE_ONLY"
#endif

#ifndef PENUMBRA_AIRLIGHT_NODES
#define PENUMBRA_AIRLIGHT_NODES 16
#endif

const float penumbraAirlightPi = 3.14159265358979323846;
const float penumbraAirlightTwoOverPi = 0.63661977236758134308;
const float penumbraAirlightZScale = 2.0;  // kAirlightZScale
const float penumbraAirlightMaxDistance = 1e18;  // kAirlightMaxDistance

// Gauss–Legendre nodes on [0, 1] and their weights: the literals of airlight.hpp's kNodes*.
#if PENUMBRA_AIRLIGHT_NODES == 8
const float penumbraAirlightNodeX[8] = float[8](PENUMBRA_AIRLIGHT_GL8_X);
const float penumbraAirlightNodeW[8] = float[8](PENUMBRA_AIRLIGHT_GL8_W);
#elif PENUMBRA_AIRLIGHT_NODES == 16
const float penumbraAirlightNodeX[16] = float[16](PENUMBRA_AIRLIGHT_GL16_X);
const float penumbraAirlightNodeW[16] = float[16](PENUMBRA_AIRLIGHT_GL16_W);
#elif PENUMBRA_AIRLIGHT_NODES == 32
const float penumbraAirlightNodeX[32] = float[32](PENUMBRA_AIRLIGHT_GL32_X);
const float penumbraAirlightNodeW[32] = float[32](PENUMBRA_AIRLIGHT_GL32_W);
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
    float fx = (1.0 - penumbraAirlightZScale / (sqrt(z) + penumbraAirlightZScale)) * (size.x - 1.0);
    float fy = omega * penumbraAirlightTwoOverPi * (size.y - 1.0);
    fx = fx > 0.0 ? min(fx, size.x - 1.0) : 0.0;
    fy = fy > 0.0 ? min(fy, size.y - 1.0) : 0.0;
#ifdef PENUMBRA_AIRLIGHT_TABLE_FETCH
    int i = min(int(fx), int(size.x) - 2), j = min(int(fy), int(size.y) - 2);
    float ax = fx - float(i), ay = fy - float(j);
    float q00 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i, j)), q10 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i + 1, j));
    float q01 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i, j + 1)), q11 = PENUMBRA_AIRLIGHT_TABLE_FETCH(ivec2(i + 1, j + 1));
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

// A(t) by Gauss–Legendre on two panels, any hg_g (detail::airlight::airlightQuadrature).
float penumbraAirlightQuadrature(vec4 medium, vec4 params, vec3 eye, vec3 dir, vec3 light, float t) {
    if (!(t > 0.0)) return 0.0;
    t = min(t, penumbraAirlightMaxDistance);
    vec3 ray = penumbraAirlightRay(eye, dir, light, params.z);
    float sigma_t = medium.y, g = medium.z;
    float h = ray.x, t0 = ray.y, r0 = ray.z;
    float u = sigma_t * h;
    float q0 = penumbraAirlightRPlusS(r0, -t0, h);
    float b0 = sigma_t * q0;
    float omega0 = atan(h, q0);
    float s1 = t - t0;
    float r1 = sqrt(h * h + s1 * s1);
    float q1 = penumbraAirlightRPlusS(r1, s1, h);
    float omega1 = atan(h, q1);
    float depth = max(sigma_t * (q1 - q0), 0.0);
    float depth_a = min(depth, 1.0);
    float omega_a = depth_a < depth ? atan(u, b0 + depth_a) : omega1;
    // Panel A: ω from omega0 down to omega_a.
    float width = max(omega0 - omega_a, 0.0);
    float sin0 = sin(omega0);
    float sum_a = 0.0;
    for (int k = 0; k < PENUMBRA_AIRLIGHT_NODES; ++k) {
        float d = width * penumbraAirlightNodeX[k];
        float omega = omega0 - d;
        float sin_w = sin(omega), cos_w = cos(omega);
        float e = u * sin(d) / (sin_w * sin0);
        sum_a += penumbraAirlightNodeW[k] * penumbraAirlightPhase2(g, cos_w * cos_w, sin_w * sin_w) * exp(-e);
    }
    float total = width * sum_a;
    // Panel B: y = 1 - exp(-(σ - σ_a)) over [0, y_end].
    if (depth > depth_a) {
        float y_end = 1.0 - exp(-(depth - depth_a));
        float sum_b = 0.0;
        for (int k = 0; k < PENUMBRA_AIRLIGHT_NODES; ++k) {
            float y = y_end * penumbraAirlightNodeX[k];
            float sigma = depth_a - log(1.0 - y);
            float c = b0 + sigma;
            float den = u * u + c * c;
            sum_b += penumbraAirlightNodeW[k] * penumbraAirlightPhase2(g, c * c / den, u * u / den) * (u / den);
        }
        total += y_end * exp(-depth_a) * sum_b;
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
