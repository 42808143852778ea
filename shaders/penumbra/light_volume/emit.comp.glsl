// penumbra — light-volume emission (billeter2010: "if subdivide: four children, else check the
// neighbours and emit triangles"), the twin of tessellateLightVolume. Items: every cell of every
// level, coarsest level first, row-major (a leaf: 2 triangles, or a fan of 4 + m around its centre
// when m of its sides have a subdivided neighbour), then the 4 R border segments (bottom, right,
// top, left; a segment that starts a leaf's side closes it to the apex: 1 triangle).
//   PENUMBRA_LV_PASS 0: triangles per item into counts[item]; the host scans them (exclusive);
//   PENUMBRA_LV_PASS 1: the triangles at their offsets, 3 packed vertices each, outward.
// One invocation per item.
// penumbra-permutation: PENUMBRA_LV_PASS=0
// penumbra-permutation: PENUMBRA_LV_PASS=1
#include "penumbra/light_volume/light_volume_shared.h"
#include "penumbra/common/dispatch.glsl"

#ifndef PENUMBRA_LV_PASS
#error penumbra/light_volume/emit.comp.glsl needs PENUMBRA_LV_PASS (0 count, 1 write)
#endif

layout(local_size_x = PENUMBRA_LV_GROUP_SIZE) in;
layout(std140, binding = PENUMBRA_LV_BINDING_PARAMS) uniform PenumbraLvParamsBlock { PenumbraLightVolumeParams penumbraLvParams; };
layout(std430, binding = PENUMBRA_LV_BINDING_FLAGS) readonly buffer PenumbraLvFlagsBuffer { uint penumbraLvFlags[]; };
layout(std430, binding = PENUMBRA_LV_BINDING_COUNTS) buffer PenumbraLvCounts { uint penumbraLvCounts[]; };
layout(std430, binding = PENUMBRA_LV_BINDING_TRIANGLES) writeonly buffer PenumbraLvTriangles { uint penumbraLvTriangles[]; };

#include "penumbra/light_volume/light_volume.glsl"

uint penumbraLvOut = 0u;

/// Counter-clockwise (a, b, c) in NDC, stored clockwise (outward): (a, c, b).
void penumbraLvFloor(uint a, uint b, uint c) {
#if PENUMBRA_LV_PASS == 1
    penumbraLvTriangles[3u * penumbraLvOut] = a;
    penumbraLvTriangles[3u * penumbraLvOut + 1u] = c;
    penumbraLvTriangles[3u * penumbraLvOut + 2u] = b;
#endif
    ++penumbraLvOut;
}

/// The side of floor boundary edge a -> b: (b, a, apex).
void penumbraLvSide(uint a, uint b) {
#if PENUMBRA_LV_PASS == 1
    penumbraLvTriangles[3u * penumbraLvOut] = b;
    penumbraLvTriangles[3u * penumbraLvOut + 1u] = a;
    penumbraLvTriangles[3u * penumbraLvOut + 2u] = PENUMBRA_LV_APEX;
#endif
    ++penumbraLvOut;
}

void penumbraLvCell(uint k, uint cx, uint cy) {
    if (penumbraLvSubdivided(k, int(cx), int(cy))) return;
    if (k < penumbraLvLevels() && !penumbraLvSubdivided(k + 1u, int(cx / 2u), int(cy / 2u))) return;
    const uint s = 1u << k, h = s / 2u, x0 = cx * s, y0 = cy * s;
    const int icx = int(cx), icy = int(cy);
    const bool finer[4] = bool[4](penumbraLvSubdivided(k, icx, icy - 1), penumbraLvSubdivided(k, icx + 1, icy),
                                  penumbraLvSubdivided(k, icx, icy + 1), penumbraLvSubdivided(k, icx - 1, icy));
    if (!finer[0] && !finer[1] && !finer[2] && !finer[3]) {
        penumbraLvFloor(penumbraLvPack(x0, y0), penumbraLvPack(x0 + s, y0), penumbraLvPack(x0 + s, y0 + s));
        penumbraLvFloor(penumbraLvPack(x0, y0), penumbraLvPack(x0 + s, y0 + s), penumbraLvPack(x0, y0 + s));
        return;
    }
    const uint corner[4] = uint[4](penumbraLvPack(x0, y0), penumbraLvPack(x0 + s, y0), penumbraLvPack(x0 + s, y0 + s), penumbraLvPack(x0, y0 + s));
    const uint middle[4] = uint[4](penumbraLvPack(x0 + h, y0), penumbraLvPack(x0 + s, y0 + h), penumbraLvPack(x0 + h, y0 + s), penumbraLvPack(x0, y0 + h));
    uint ring[8];
    uint count = 0u;
    for (uint side = 0u; side < 4u; ++side) {
        ring[count++] = corner[side];
        if (finer[side]) ring[count++] = middle[side];
    }
    const uint centre = penumbraLvPack(x0 + h, y0 + h);
    for (uint v = 0u; v < count; ++v) penumbraLvFloor(centre, ring[v], ring[(v + 1u) % count]);
}

void penumbraLvBorder(uint segment) {
    const uint r = penumbraLvResolution(), side = segment / r, pos = segment % r;
    const uvec2 unit = side == 0u ? uvec2(pos, 0u) : side == 1u ? uvec2(r - 1u, pos) : side == 2u ? uvec2(pos, r - 1u) : uvec2(0u, pos);
    const uint s = penumbraLvLeafSize(unit.x, unit.y);
    if (pos % s != 0u) return;
    if (side == 0u) penumbraLvSide(penumbraLvPack(pos + s, 0u), penumbraLvPack(pos, 0u));
    else if (side == 1u) penumbraLvSide(penumbraLvPack(r, pos + s), penumbraLvPack(r, pos));
    else if (side == 2u) penumbraLvSide(penumbraLvPack(pos, r), penumbraLvPack(pos + s, r));
    else penumbraLvSide(penumbraLvPack(0u, pos), penumbraLvPack(0u, pos + s));
}

void main() {
    const uint item = penumbraLinearGroup() * PENUMBRA_LV_GROUP_SIZE + gl_LocalInvocationID.x;
    if (item >= penumbraLvParams.counts.y) return;
#if PENUMBRA_LV_PASS == 1
    penumbraLvOut = penumbraLvCounts[item];
#endif
    if (item < penumbraLvParams.counts.x) {
        uint k = penumbraLvLevels();
        while (k > 0u && item >= penumbraLvOffset(k) + penumbraLvCells(k) * penumbraLvCells(k)) --k;
        const uint local = item - penumbraLvOffset(k), cells = penumbraLvCells(k);
        penumbraLvCell(k, local % cells, local / cells);
    } else {
        penumbraLvBorder(item - penumbraLvParams.counts.x);
    }
#if PENUMBRA_LV_PASS == 0
    penumbraLvCounts[item] = penumbraLvOut;
#endif
}
