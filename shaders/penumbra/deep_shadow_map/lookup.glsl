// penumbra — deep shadow map lookup (lokovic2000 §3.4, §5.3): V(z) of one texel by binary search
// (left-continuous: a receiver exactly at a step's depth gets the value before it), bilinear over
// texels, trilinear over mip levels. Twins: dsmVisibility, dsmLookupLevel, dsmLookup
// (include/penumbra/deep_shadow_map.hpp).
//   hooks (define before including):
//     PENUMBRA_DSM_LOAD_OFFSET(word)   uint: word `word` of the map's offset buffer
//     PENUMBRA_DSM_LOAD_WORD(index)    uint: word `index` of the map's vertex buffer
//     PENUMBRA_DSM_VERTEX_CAPACITY     uint: the vertex capacity (where the 16-bit values start)
//     PENUMBRA_DSM_RESOLUTION          uint: R of level 0
//     PENUMBRA_DSM_LEVELS              uint: levels in the map
//   PENUMBRA_DSM_CHANNELS: 1 (default) or 3; `c` selects the channel.
// Layout: level l's offsets are R_l^2 + 1 words at word sum_{k<l} R_k^2 + l (local vertex indices);
// its vertices follow the vertices of levels 0 .. l-1. Vertex i: z = float bits of word i; V of
// channel c = 16-bit halfword h = i * channels + c at word capacity + h / 2 (low half first), V =
// q / 32768.
#ifndef PENUMBRA_DSM_LOOKUP_GLSL
#define PENUMBRA_DSM_LOOKUP_GLSL

#ifndef PENUMBRA_DSM_LOAD_OFFSET
#error penumbra/deep_shadow_map/lookup.glsl needs the hook PENUMBRA_DSM_LOAD_OFFSET(word)
#endif
#ifndef PENUMBRA_DSM_LOAD_WORD
#error penumbra/deep_shadow_map/lookup.glsl needs the hook PENUMBRA_DSM_LOAD_WORD(index)
#endif
#ifndef PENUMBRA_DSM_VERTEX_CAPACITY
#error penumbra/deep_shadow_map/lookup.glsl needs the hook PENUMBRA_DSM_VERTEX_CAPACITY
#endif
#ifndef PENUMBRA_DSM_RESOLUTION
#error penumbra/deep_shadow_map/lookup.glsl needs the hook PENUMBRA_DSM_RESOLUTION
#endif
#ifndef PENUMBRA_DSM_LEVELS
#error penumbra/deep_shadow_map/lookup.glsl needs the hook PENUMBRA_DSM_LEVELS
#endif
#ifndef PENUMBRA_DSM_CHANNELS
#define PENUMBRA_DSM_CHANNELS 1
#endif

// x: first vertex of the level, y: first offset word of the level.
uvec2 penumbraDsmLevelStart(uint level) {
    uint base = 0u, word = 0u;
    for (uint l = 0u; l < level; ++l) {
        uint r = uint(PENUMBRA_DSM_RESOLUTION) >> l;
        base += PENUMBRA_DSM_LOAD_OFFSET(word + r * r);
        word += r * r + 1u;
    }
    return uvec2(base, word);
}

float penumbraDsmLookupZ(uint vertex) { return uintBitsToFloat(PENUMBRA_DSM_LOAD_WORD(vertex)); }
float penumbraDsmLookupV(uint vertex, uint c) {
    uint h = vertex * uint(PENUMBRA_DSM_CHANNELS) + c;
    uint w = PENUMBRA_DSM_LOAD_WORD(uint(PENUMBRA_DSM_VERTEX_CAPACITY) + h / 2u);
    return float((h & 1u) != 0u ? (w >> 16u) : (w & 0xFFFFu)) * (1.0 / 32768.0);
}

float penumbraDsmVisibilityAt(uvec2 start, uint texel, float z, uint c) {
    uint first = start.x + PENUMBRA_DSM_LOAD_OFFSET(start.y + texel);
    uint last = start.x + PENUMBRA_DSM_LOAD_OFFSET(start.y + texel + 1u);
    if (first == last) return 1.0;
    uint lo = first, hi = last;
    while (lo < hi) {
        uint mid = lo + (hi - lo) / 2u;
        if (penumbraDsmLookupZ(mid) < z) lo = mid + 1u; else hi = mid;
    }
    if (lo == first) return penumbraDsmLookupV(first, c);
    if (lo == last) return penumbraDsmLookupV(last - 1u, c);
    float za = penumbraDsmLookupZ(lo - 1u), zb = penumbraDsmLookupZ(lo);
    float va = penumbraDsmLookupV(lo - 1u, c), vb = penumbraDsmLookupV(lo, c);
    if (zb == z) return vb;
    precise float t = (z - za) / (zb - za);
    precise float v = va + (vb - va) * t;
    return v;
}

float penumbraDsmVisibility(uint level, uint texel, float z, uint c) {
    return penumbraDsmVisibilityAt(penumbraDsmLevelStart(level), texel, z, c);
}

float penumbraDsmLookupLevel(uint level, float u, float v, float z, uint c) {
    uvec2 start = penumbraDsmLevelStart(level);
    int r = int(uint(PENUMBRA_DSM_RESOLUTION) >> level);
    precise float fx = u * float(r) - 0.5;
    precise float fy = v * float(r) - 0.5;
    float bx = floor(fx), by = floor(fy);
    precise float tx = fx - bx;
    precise float ty = fy - by;
    int ix = int(bx), iy = int(by);
    int x0 = clamp(ix, 0, r - 1), x1 = clamp(ix + 1, 0, r - 1), y0 = clamp(iy, 0, r - 1), y1 = clamp(iy + 1, 0, r - 1);
    float a = penumbraDsmVisibilityAt(start, uint(y0 * r + x0), z, c);
    float b = penumbraDsmVisibilityAt(start, uint(y0 * r + x1), z, c);
    float d = penumbraDsmVisibilityAt(start, uint(y1 * r + x0), z, c);
    float e = penumbraDsmVisibilityAt(start, uint(y1 * r + x1), z, c);
    precise float top = a + (b - a) * tx;
    precise float bottom = d + (e - d) * tx;
    precise float result = top + (bottom - top) * ty;
    return result;
}

float penumbraDsmLookup(float u, float v, float z, float lod, uint c) {
    float l = clamp(lod, 0.0, float(uint(PENUMBRA_DSM_LEVELS) - 1u));
    uint l0 = uint(l);
    uint l1 = min(l0 + 1u, uint(PENUMBRA_DSM_LEVELS) - 1u);
    precise float t = l - float(l0);
    float a = penumbraDsmLookupLevel(l0, u, v, z, c);
    if (t == 0.0 || l1 == l0) return a;
    float b = penumbraDsmLookupLevel(l1, u, v, z, c);
    precise float result = a + (b - a) * t;
    return result;
}

#endif
