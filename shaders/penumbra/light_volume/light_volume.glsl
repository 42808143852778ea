// penumbra — the light-volume tessellator's cell access (billeter2010): flags per cell of every
// level, leaves and their finer neighbours; the GLSL twin of detail::light_volume in
// include/penumbra/light_volume.hpp. Needs the params block and the flags buffer declared by the
// including entry shader as penumbraLvParams and penumbraLvFlags[].
#ifndef PENUMBRA_LIGHT_VOLUME_GLSL
#define PENUMBRA_LIGHT_VOLUME_GLSL

#include "penumbra/light_volume/light_volume_shared.h"

uint penumbraLvResolution() { return penumbraLvParams.size.x; }
uint penumbraLvLevels() { return penumbraLvParams.size.y; }
uint penumbraLvCells(uint k) { return penumbraLvParams.size.x >> k; }
uint penumbraLvOffset(uint k) { return penumbraLvParams.level_offset[k >> 2u][k & 3u]; }

/// Cell (cx, cy) of size 2^k is subdivided; false for level 0 and outside the map.
bool penumbraLvSubdivided(uint k, int cx, int cy) {
    const int cells = int(penumbraLvCells(k));
    if (k == 0u || cx < 0 || cy < 0 || cx >= cells || cy >= cells) return false;
    return penumbraLvFlags[penumbraLvOffset(k) + uint(cy) * uint(cells) + uint(cx)] != 0u;
}

/// Closure's test: some child of cell (cx, cy) of level k >= 1 is subdivided.
bool penumbraLvAnyChild(uint k, int cx, int cy) {
    return penumbraLvSubdivided(k - 1u, 2 * cx, 2 * cy) || penumbraLvSubdivided(k - 1u, 2 * cx + 1, 2 * cy) ||
           penumbraLvSubdivided(k - 1u, 2 * cx, 2 * cy + 1) || penumbraLvSubdivided(k - 1u, 2 * cx + 1, 2 * cy + 1);
}

uint penumbraLvPack(uint i, uint j) { return i | (j << 16u); }

/// The size of the leaf holding unit cell (ux, uy).
uint penumbraLvLeafSize(uint ux, uint uy) {
    uint k = 0u;
    while (k < penumbraLvLevels() && !penumbraLvSubdivided(k + 1u, int(ux >> (k + 1u)), int(uy >> (k + 1u)))) ++k;
    return 1u << k;
}

#endif
