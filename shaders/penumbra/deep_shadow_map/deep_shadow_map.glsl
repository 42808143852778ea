// penumbra — deep shadow maps: the functions every kernel shares (lokovic2000 §3.1-§3.2), each the
// twin of the function of the same name in include/penumbra/deep_shadow_map.hpp (penumbra::detail):
// the texel's sub-sample pattern, homogeneous edge functions (Olano & Greer) with the top-left rule,
// perspective-correct interpolation. Every product is `precise` (no FMA), in the twin's order.
// No bindings, no hooks.
#ifndef PENUMBRA_DEEP_SHADOW_MAP_GLSL
#define PENUMBRA_DEEP_SHADOW_MAP_GLSL

uint penumbraDsmHash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

uint penumbraDsmPattern(uint x, uint y) {
    return penumbraDsmHash((x * 0x9E3779B9u) ^ penumbraDsmHash(y + 0x632BE5ABu)) % uint(PENUMBRA_DSM_PATTERNS);
}

vec3 penumbraDsmCross(vec3 a, vec3 b) {
    precise vec3 n = vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return n;
}

float penumbraDsmEdge(vec3 n, float px, float py) {
    precise float e = (n.x * px + n.y * py) + n.z;
    return e;
}

bool penumbraDsmEdgeCovers(float e, vec3 n) {
    return e > 0.0 || (e == 0.0 && (n.x > 0.0 || (n.x == 0.0 && n.y > 0.0)));
}

float penumbraDsmInterpolate(float e0, float e1, float e2, float a0, float a1, float a2) {
    precise float num = (e0 * a0 + e1 * a1) + e2 * a2;
    precise float den = (e0 + e1) + e2;
    precise float r = num / den;
    return r;
}

vec4 penumbraDsmTransform(mat4 m, vec3 p) {
    precise vec4 c = ((m[0] * p.x + m[1] * p.y) + m[2] * p.z) + m[3];
    return c;
}

float penumbraDsmDepth(vec4 row, vec3 p) {
    precise float d = ((row.x * p.x + row.y * p.y) + row.z * p.z) + row.w;
    return d;
}

// Stored V: 16 bits, q / 32768 (twins of dsmQuantize / dsmDecode).
uint penumbraDsmQuantize(float v) {
    precise float q = v * 32768.0 + 0.5;
    return uint(q);
}
float penumbraDsmDecode(uint q) { return float(q) * (1.0 / 32768.0); }

bool penumbraDsmNonFinite(float f) { return (floatBitsToUint(f) & 0x7F800000u) == 0x7F800000u; }

// exp(-x), x >= 0, with + and * only (twin of detail::dsmExpNeg).
float penumbraDsmExpNeg(float x) {
    if (!(x < 87.0)) return 0.0;
    if (!(x > 0.0)) return 1.0;
    precise float nx = x * 1.44269504 + 0.5;
    float n = floor(nx);
    precise float r = (x - n * 0.693145752) - n * 1.42860677e-06;
    precise float p = -1.98412698e-04;
    p = p * r + 1.38888889e-03;
    p = p * r - 8.33333333e-03;
    p = p * r + 4.16666667e-02;
    p = p * r - 1.66666667e-01;
    p = p * r + 0.5;
    p = p * r - 1.0;
    p = p * r + 1.0;
    return ldexp(p, -int(n));
}

vec4 penumbraDsmTransform4(mat4 m, vec4 p) {
    precise vec4 c = ((m[0] * p.x + m[1] * p.y) + m[2] * p.z) + m[3] * p.w;
    return c;
}

// The part of the sub-sample ray through NDC (px, py) inside the medium box (twin of
// detail::dsmMediumSpan): x = depth in, y = depth out, z = sigma_t x path length per unit depth,
// w = 1 when valid, else 0.
vec4 penumbraDsmMediumSpan(mat4 inverse_vp, vec4 depth_row, vec4 lo, vec4 hi, float px, float py) {
    vec4 h0 = penumbraDsmTransform4(inverse_vp, vec4(px, py, -1.0, 1.0));
    vec4 h1 = penumbraDsmTransform4(inverse_vp, vec4(px, py, 1.0, 1.0));
    precise vec3 p0 = vec3(h0.x / h0.w, h0.y / h0.w, h0.z / h0.w);
    precise vec3 p1 = vec3(h1.x / h1.w, h1.y / h1.w, h1.z / h1.w);
    float d0 = penumbraDsmDepth(depth_row, p0), d1 = penumbraDsmDepth(depth_row, p1);
    precise float dd = d1 - d0;
    if (!(dd > 0.0) || penumbraDsmNonFinite(dd)) return vec4(0.0);
    precise vec3 D = p1 - p0;
    precise float tmin = -d0 / dd;
    float tmax = uintBitsToFloat(0x7F800000u);
    for (int a = 0; a < 3; ++a) {
        if (D[a] == 0.0) {
            if (p0[a] < lo[a] || p0[a] > hi[a]) return vec4(0.0);
            continue;
        }
        precise float t1 = (lo[a] - p0[a]) / D[a];
        precise float t2 = (hi[a] - p0[a]) / D[a];
        tmin = max(tmin, min(t1, t2));
        tmax = min(tmax, max(t1, t2));
    }
    if (!(tmin < tmax)) return vec4(0.0);
    precise float z_in = d0 + tmin * dd;
    precise float z_out = d0 + tmax * dd;
    precise float len2 = (D.x * D.x + D.y * D.y) + D.z * D.z;
    precise float len = sqrt(len2);
    precise float sk = lo.w * (len / dd);
    bool valid = z_in < z_out && !penumbraDsmNonFinite(z_in) && !penumbraDsmNonFinite(z_out) && !penumbraDsmNonFinite(sk);
    return valid ? vec4(z_in, z_out, sk, 1.0) : vec4(0.0);
}

#endif
