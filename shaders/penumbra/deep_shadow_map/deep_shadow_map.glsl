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

bool penumbraDsmNonFinite(float f) { return (floatBitsToUint(f) & 0x7F800000u) == 0x7F800000u; }

#endif
